# Warnings are applied per target, never globally.
# -Wno-maybe-uninitialized: GCC 12 reports a false positive on copies of config structs holding a
# std::vector with a default member initialiser (CorrectorConfig::restart_scale_factors) when
# they are inlined in Release builds; -Wuninitialized (definite uses) stays on.
function(driftcorr_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wno-unused-parameter
                         $<$<CXX_COMPILER_ID:GNU>:-Wno-maybe-uninitialized>)
endfunction()
