#pragma once
// Tier-1 errors (STYLE.md): a broken invariant is a programming error, not bad input.
// DRIFTCORR_CHECK(condition, "message") stays in every build type (assert is compiled out of the
// Release build users run). When the condition is false it throws InvariantError,
//   "broken invariant at <file>:<line>: <condition>: <message>",
// and prints nothing: core does no I/O. The edges say it once and stop (the CLI: one line and
// exit code 4; the online worker: its worker_error); uncaught, it ends the program through
// std::terminate. Bad external input is never checked this way: it gets an InputError
// (errors.h); numerical outcomes go into result structs.
#include <stdexcept>
#include <string>

namespace driftcorr {

/// A broken invariant (DRIFTCORR_CHECK). Adapters that turn a library's exceptions into
/// InputError let it through unchanged: it is never the input's fault.
class InvariantError : public std::logic_error {
public:
    using std::logic_error::logic_error;
};

namespace check_detail {

[[noreturn]] inline void Fail(const char* file, int line, const char* condition,
                              const char* message) {
    throw InvariantError(std::string("broken invariant at ") + file + ":" + std::to_string(line) +
                         ": " + condition + ": " + message);
}

}  // namespace check_detail
}  // namespace driftcorr

#define DRIFTCORR_CHECK(condition, message) \
    ((condition) ? static_cast<void>(0)     \
                 : ::driftcorr::check_detail::Fail(__FILE__, __LINE__, #condition, message))
