#pragma once
// Tier-1 errors (STYLE.md): a broken invariant is a programming error, not bad input.
// DRIFTCORR_CHECK(condition, "message") stays in every build type (assert is compiled out of the
// Release build users run) and, when the condition is false, writes
//   driftcorr: internal error at <file>:<line>: <condition>: <message>
// to stderr and aborts. Bad external input is never checked this way: it gets an InputError
// (errors.h); numerical outcomes go into result structs.
#include <cstdio>
#include <cstdlib>

namespace driftcorr::check_detail {

[[noreturn]] inline void Fail(const char* file, int line, const char* condition,
                              const char* message) {
    std::fprintf(stderr, "driftcorr: internal error at %s:%d: %s: %s\n", file, line, condition,
                 message);
    std::abort();
}

}  // namespace driftcorr::check_detail

#define DRIFTCORR_CHECK(condition, message) \
    ((condition) ? static_cast<void>(0)     \
                 : ::driftcorr::check_detail::Fail(__FILE__, __LINE__, #condition, message))
