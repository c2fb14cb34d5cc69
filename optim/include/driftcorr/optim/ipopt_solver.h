#pragma once
// Solves a WindowProblem with Ipopt (exact first and second derivatives, MUMPS). Ipopt's types
// stay inside ipopt_solver.cpp. Safe to call from several threads: the calls take turns, because
// MUMPS is not thread-safe (a process-wide lock around each solve).
#include <string>

#include "driftcorr/optim/window_problem.h"

namespace driftcorr {

enum class SolveStatus { kSuccess, kAcceptable, kMaxIterations, kInfeasible, kFailed };
std::string ToString(SolveStatus status);
/// True when the solution may be used (solved to tolerance or to the acceptable level).
inline bool Usable(SolveStatus s) { return s == SolveStatus::kSuccess || s == SolveStatus::kAcceptable; }

struct IpoptOptions {
    int max_iterations = 100;
    double max_cpu_time_s = 60.0;
    double tolerance = 1e-6;
    double acceptable_tolerance = 1e-4;
    double constraint_tolerance = 1e-4;  ///< [m] allowed corridor violation at convergence
    int print_level = 0;
};

struct SolveReport {
    SolveStatus status = SolveStatus::kFailed;
    std::string message;   ///< Ipopt's return status name
    int iterations = 0;
    double objective = 0.0;
    double max_violation_m = 0.0;  ///< largest constraint violation at the solution
};

/// Solves and, when the outcome is usable, stores the solution into the problem's state.
SolveReport SolveWithIpopt(WindowProblem& problem, const IpoptOptions& options);

}  // namespace driftcorr
