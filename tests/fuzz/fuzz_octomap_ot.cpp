// libFuzzer target: OctoMap full-tree (.ot) map layers (driftcorr::ReadSurfacePoints). See
// fuzz_targets.h for what counts as a finding.
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::string tmp_dir = driftcorr::fuzz::DefaultTempDir();
    driftcorr::fuzz::RunOctomapOt(driftcorr::fuzz::AsText(data, size), tmp_dir);
    return 0;
}
