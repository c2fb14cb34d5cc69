#pragma once
// Solves a WindowProblem with Ipopt (exact first and second derivatives, MUMPS). Ipopt's types
// stay inside ipopt_solver.cpp. Safe to call from several threads: the calls take turns, because
// MUMPS is not thread-safe (a process-wide lock around each solve).
#include <functional>

#include "driftcorr/optim/solve_status.h"
#include "driftcorr/optim/window_problem.h"

namespace driftcorr {

struct IpoptOptions {
    int max_iterations = 100;
    double max_cpu_time_s = 60.0;
    double tolerance = 1e-6;
    double acceptable_tolerance = 1e-4;
    double constraint_tolerance = 1e-4;  ///< [m] allowed corridor violation at convergence
    int print_level = 0;
    /// Called after each iteration with its number (from 1); empty: none. For progress reports.
    std::function<void(int)> on_iteration;
};

/// Solves and, when the outcome is usable, stores the solution into the problem's state.
SolveReport SolveWithIpopt(WindowProblem& problem, const IpoptOptions& options);

}  // namespace driftcorr
