#pragma once
// Solves a WindowProblem without constraints (the incremental and fixed-lag windows' soft terms)
// by a damped Newton method on its exact Hessian: the Hessian of a window is a band (each term
// couples consecutive poses) bordered by its few scale and heading-rate bias variables, so one
// LDL^T factorisation of its envelope (skyline_ldlt.h; each scale or bias variable ordered right
// after the last pose it touches) costs O(poses). Where the Hessian is not positive definite (the
// map term is not convex) a multiple of its diagonal is added, as Ipopt corrects the inertia of its
// own system; steps are accepted by a backtracking (Armijo) line search on the objective, tested
// as Ipopt tests it (within ten rounding units of the objective). Variables whose bounds coincide
// (heights in planar mode) are held; the scale variables are kept inside their bounds by
// projection.
//
// Convergence is Ipopt's test for an unconstrained problem: the gradient's largest component,
// with the objective scaled as Ipopt scales it (to a gradient of at most 100 at the start),
// below `tolerance`; `acceptable_tolerance` where the line search can no longer decrease the
// objective, or where two steps in a row were taken within its rounding without lowering it.
// The constrained program (the hard corridor) stays with Ipopt (ipopt_solver.h).
#include <functional>

#include "driftcorr/optim/solve_status.h"
#include "driftcorr/optim/window_problem.h"

namespace driftcorr {

struct NewtonOptions {
    int max_iterations = 50;
    double tolerance = 1e-6;
    double acceptable_tolerance = 1e-4;
    /// Called after each iteration with its number (from 1); empty: none. For progress reports.
    std::function<void(int)> on_iteration;
};

/// Solves and, when the outcome is usable, stores the solution into the problem's state.
/// Precondition: problem.NumConstraints() == 0 and the problem was built with WindowUse::kSolve.
SolveReport SolveWithNewton(WindowProblem& problem, const NewtonOptions& options);

}  // namespace driftcorr
