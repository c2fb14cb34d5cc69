// The definitions of what driftcorr/optim/solve_status.h declares.
#include "driftcorr/optim/solve_status.h"

namespace driftcorr {

std::string ToString(SolveStatus status) {
    switch (status) {
        case SolveStatus::kSuccess:
            return "success";
        case SolveStatus::kAcceptable:
            return "acceptable";
        case SolveStatus::kMaxIterations:
            return "max_iterations";
        case SolveStatus::kInfeasible:
            return "infeasible";
        default:
            return "failed";
    }
}

}  // namespace driftcorr
