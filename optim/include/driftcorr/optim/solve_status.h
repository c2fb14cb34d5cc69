#pragma once
// Solver-neutral outcome of one solve: the status every solver of optim/ reports (the Ipopt
// adapter, the paper's baseline, the correctors built on them) and the report of a single solve.
#include <string>

namespace driftcorr {

enum class SolveStatus { kSuccess, kAcceptable, kMaxIterations, kInfeasible, kFailed };
std::string ToString(SolveStatus status);
/// True when the solution may be used (solved to tolerance or to the acceptable level).
inline bool Usable(SolveStatus s) {
    return s == SolveStatus::kSuccess || s == SolveStatus::kAcceptable;
}

struct SolveReport {
    SolveStatus status = SolveStatus::kFailed;
    std::string message;  ///< the solver's own name for the outcome (Ipopt's return status)
    int iterations = 0;
    double objective = 0.0;
    double max_violation_m = 0.0;  ///< largest constraint violation at the solution
};

}  // namespace driftcorr
