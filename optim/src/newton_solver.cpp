// The definitions of what driftcorr/optim/newton_solver.h declares.
#include "driftcorr/optim/newton_solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "driftcorr/core/check.h"
#include "driftcorr/optim/skyline_ldlt.h"

namespace driftcorr {
namespace {

// Armijo's sufficient decrease, the damping's first value and growth, the backtracking's
// halvings before the damping grows instead, and the damping beyond which the solve gives up.
constexpr double kArmijo = 1e-4, kDampingFirst = 1e-4, kDampingGrowth = 8.0, kDampingMax = 1e10;
constexpr int kHalvings = 12;

// Armijo's condition as Ipopt tests it: the trial's objective may exceed the required decrease
// by ten rounding units of the objective. Near the optimum of a window whose objective sums
// thousands of terms, the decrease a step promises falls below the rounding of that sum while
// the gradient is still above the tolerance; an exact test then rejects every step and halving,
// and the damping grows until the step is nothing.
bool SufficientDecrease(double f_trial, double f, double decrease) {
    return std::isfinite(f_trial) &&
           (f_trial - f) - kArmijo * decrease <=
               10.0 * std::numeric_limits<double>::epsilon() * std::abs(f);
}

// The order the factorisation takes the variables in: the problem's, except for the variables
// after the poses' (scale and heading-rate bias segments), each of which goes right after the
// last pose variable it is coupled with. The Hessian is then a band with a few short arrows, and
// its LDL^T fills in only within them, without a graph analysis per window.
std::vector<int> BandOrder(const WindowProblem& p) {
    const int n = p.NumVariables(), poses = p.PoseVar(p.last(), 3) + 1;
    std::vector<int> key(n - poses, -1);  // per segment variable
    for (const auto& [r, c] : p.HessianStructure()) {
        if (r >= poses && c < poses) key[r - poses] = std::max(key[r - poses], c);
    }
    // The segment variables by key (ties in their own order), each placed right after the pose
    // variable its key names; those coupled with no pose variable (key -1) first.
    std::vector<int> segments(n - poses);
    for (int k = 0; k < n - poses; ++k) segments[k] = k;
    std::stable_sort(segments.begin(), segments.end(),
                     [&](int a, int b) { return key[a] < key[b]; });
    std::vector<int> position(n);  // position[variable] = its place in the order
    int next = 0;
    auto segment = segments.begin();
    for (; segment != segments.end() && key[*segment] < 0; ++segment)
        position[poses + *segment] = next++;
    for (int k = 0; k < poses; ++k) {
        position[k] = next++;
        for (; segment != segments.end() && key[*segment] == k; ++segment)
            position[poses + *segment] = next++;
    }
    return position;
}

// The slot of a Hessian entry with no place in the matrix: it involves a held variable (one
// whose bounds are equal).
constexpr std::size_t kNone = static_cast<std::size_t>(-1);

// The Hessian's upper triangle in BandOrder, held by its envelope (the problem's pattern and a
// full diagonal), and where each entry of HessianValues lands in it. Held variables (a planar
// walk's heights) are left out: their step is zero, and with their rows and columns zero and a
// unit pivot they would add only zeros to the other entries of the factor and the solve.
struct Pattern {
    SkylineLdlt matrix;
    std::vector<int> variable;          ///< per row and column of the matrix: its variable
    std::vector<std::size_t> slot;      ///< per HessianStructure entry: index into matrix.values()
    std::vector<std::size_t> diagonal;  ///< per row of the matrix: index of its diagonal entry
};

Pattern BuildPattern(const WindowProblem& p, const std::vector<std::uint8_t>& held) {
    const auto& structure = p.HessianStructure();
    const int n = p.NumVariables();
    const std::vector<int> band = BandOrder(p);
    std::vector<int> order(n);  // order[band position] = variable
    for (int k = 0; k < n; ++k) order[band[k]] = k;
    std::vector<int> position(n, -1), variable;  // variable[row of the matrix]
    for (int q = 0; q < n; ++q) {
        if (held[order[q]]) continue;
        position[order[q]] = static_cast<int>(variable.size());
        variable.push_back(order[q]);
    }
    const int m = static_cast<int>(variable.size());
    auto upper = [&](int r, int c) {  // (row, column) with row <= column
        const int a = position[r], b = position[c];
        return a <= b ? std::make_pair(a, b) : std::make_pair(b, a);
    };
    std::vector<int> first(m);
    for (int k = 0; k < m; ++k) first[k] = k;
    for (const auto& [r, c] : structure) {
        if (held[r] || held[c]) continue;
        const auto [a, b] = upper(r, c);
        first[b] = std::min(first[b], a);
    }
    Pattern out{SkylineLdlt(std::move(first)), {}, {}, {}};
    out.slot.reserve(structure.size());
    for (const auto& [r, c] : structure) {
        if (held[r] || held[c]) {
            out.slot.push_back(kNone);
            continue;
        }
        const auto [a, b] = upper(r, c);
        out.slot.push_back(out.matrix.Index(a, b));
    }
    out.variable = std::move(variable);
    for (int q = 0; q < m; ++q) out.diagonal.push_back(out.matrix.Index(q, q));
    return out;
}

double MaxAbs(const std::vector<double>& v) {
    double m = 0.0;
    for (double e : v) m = std::max(m, std::abs(e));
    return m;
}

}  // namespace

SolveReport SolveWithNewton(WindowProblem& problem, const NewtonOptions& options) {
    DRIFTCORR_CHECK(problem.NumConstraints() == 0, "the Newton solver takes no constraints");
    DRIFTCORR_CHECK(!problem.HessianStructure().empty(), "a problem built with WindowUse::kSolve");
    const int n = problem.NumVariables();
    std::vector<double> lower(n), upper(n), x(n);
    problem.Bounds(lower.data(), upper.data(), nullptr, nullptr);
    problem.InitialPoint(x.data());
    std::vector<std::uint8_t> held(n);  // bytes, not bits: read in every loop
    for (int k = 0; k < n; ++k) {
        held[k] = lower[k] == upper[k];
        x[k] = std::clamp(x[k], lower[k], upper[k]);
    }
    Pattern pattern = BuildPattern(problem, held);
    const int m = pattern.matrix.size();

    const std::size_t entries = problem.HessianStructure().size();
    std::vector<double> grad(n), hessian(entries), trial(n), trial_grad(n), trial_hessian(entries);
    // The active set: held variables and those pressed against a bound by the gradient; they
    // stay where they are for the next step (projected Newton), and their gradient is left out.
    std::vector<std::uint8_t> active(n);
    auto project_gradient = [&] {
        for (int k = 0; k < n; ++k) {
            active[k] = held[k] || (x[k] <= lower[k] && grad[k] > 0.0) ||
                        (x[k] >= upper[k] && grad[k] < 0.0);
            if (active[k]) grad[k] = 0.0;
        }
    };
    SolveReport report;
    // The objective, its gradient and its Hessian are evaluated together: the Hessian is wasted
    // only where the gradient says the solve has converged.
    double f = problem.ObjectiveGradientHessian(x.data(), grad.data(), hessian.data());
    if (!std::isfinite(f)) {
        report.message = "objective not finite at the starting point";
        return report;
    }
    project_gradient();
    // Ipopt's scaling of the objective: its gradient at the start at most 100.
    const double scale = std::min(1.0, 100.0 / std::max(MaxAbs(grad), 1e-300));
    double damping = 0.0;
    // Whether the last line search took its first trial: the next first trial is then evaluated
    // with its gradient and Hessian (most are taken; a trial not taken wastes them).
    bool speculate = true;
    std::vector<double> step(n, 0.0), rhs(m), diagonal(m);
    report.status = SolveStatus::kMaxIterations;
    report.message = "Maximum_Iterations_Exceeded";
    // Where the method can go no further: acceptable if the gradient is small enough for that,
    // else `status` with `message`.
    auto stop_short = [&](double error, SolveStatus status = SolveStatus::kFailed,
                          const char* message = "Search_Direction_Becomes_Too_Small") {
        if (error <= options.acceptable_tolerance) {
            report.status = SolveStatus::kAcceptable;
            report.message = "Solved_To_Acceptable_Level";
        } else {
            report.status = status;
            report.message = message;
        }
    };
    // Steps in a row taken within the objective's rounding but without lowering it.
    int stalls = 0;
    for (int it = 0;; ++it) {
        const double error = scale * MaxAbs(grad);
        if (error <= options.tolerance) {
            report.status = SolveStatus::kSuccess;
            report.message = "Solve_Succeeded";
            break;
        }
        // Two such steps: the gradient left is below what the objective resolves (the gradient
        // of a window's objective can stay above the tolerance by rounding alone), as Ipopt
        // stops at repeated tiny steps.
        if (stalls >= 2) {
            stop_short(error);
            break;
        }
        if (it >= options.max_iterations) {
            stop_short(error, SolveStatus::kMaxIterations, "Maximum_Iterations_Exceeded");
            break;
        }
        report.iterations = it + 1;
        if (options.on_iteration) options.on_iteration(it + 1);
        std::vector<double>& values = pattern.matrix.values();
        std::fill(values.begin(), values.end(), 0.0);
        for (std::size_t e = 0; e < hessian.size(); ++e) {
            if (pattern.slot[e] != kNone) values[pattern.slot[e]] += hessian[e];
        }
        // The rows and columns of active variables: zero (a scale at its bound; seldom any).
        bool any_active = false;
        for (int q = 0; q < m; ++q) any_active = any_active || active[pattern.variable[q]];
        for (int c = 0; any_active && c < m; ++c) {
            const bool column_active = active[pattern.variable[c]];
            for (int r = pattern.matrix.first_row(c); r <= c; ++r) {
                if (column_active || active[pattern.variable[r]])
                    values[pattern.matrix.Index(r, c)] = 0.0;
            }
        }
        for (int q = 0; q < m; ++q) {
            diagonal[q] = active[pattern.variable[q]] ? 1.0 : values[pattern.diagonal[q]];
            values[pattern.diagonal[q]] = diagonal[q];
        }
        // Newton's step, damped (H + damping * max(|diag H|, 1)) until the system is positive
        // definite and the line search finds a decrease.
        bool moved = false, evaluated = false;
        while (!moved) {
            for (int q = 0; q < m; ++q) {
                values[pattern.diagonal[q]] =
                    diagonal[q] + (active[pattern.variable[q]]
                                       ? 0.0
                                       : damping * std::max(std::abs(diagonal[q]), 1.0));
            }
            if (pattern.matrix.Factorize()) {
                for (int q = 0; q < m; ++q) rhs[q] = -grad[pattern.variable[q]];
                pattern.matrix.Solve(rhs);
                for (int q = 0; q < m; ++q) step[pattern.variable[q]] = rhs[q];
                for (int alpha_k = 0; alpha_k < kHalvings && !moved; ++alpha_k) {
                    const double alpha = std::ldexp(1.0, -alpha_k);
                    double decrease = 0.0;  // the model's, along the projected step
                    for (int k = 0; k < n; ++k) {
                        trial[k] = std::clamp(x[k] + alpha * step[k], lower[k], upper[k]);
                        decrease += grad[k] * (trial[k] - x[k]);
                    }
                    if (!(decrease < 0.0)) break;
                    const bool full = alpha_k == 0 && speculate;
                    const double f_trial =
                        full ? problem.ObjectiveGradientHessian(trial.data(), trial_grad.data(),
                                                                trial_hessian.data())
                             : problem.Objective(trial.data());
                    const bool taken = SufficientDecrease(f_trial, f, decrease);
                    if (alpha_k == 0) speculate = taken;
                    if (taken) {
                        stalls = f_trial < f ? 0 : stalls + 1;
                        x.swap(trial);
                        f = f_trial;
                        moved = true;
                        evaluated = full;
                        if (alpha_k == 0)
                            damping =
                                damping / kDampingGrowth < 1e-8 ? 0.0 : damping / kDampingGrowth;
                    }
                }
                if (moved) break;
            }
            damping = damping == 0.0 ? kDampingFirst : damping * kDampingGrowth;
            if (damping > kDampingMax) break;
        }
        if (!moved) {  // no decrease along any damped step: as far as this method goes
            stop_short(error);
            break;
        }
        if (evaluated) {
            grad.swap(trial_grad);
            hessian.swap(trial_hessian);
        } else {
            problem.ObjectiveGradientHessian(x.data(), grad.data(), hessian.data());
        }
        project_gradient();
    }
    report.objective = f;
    if (Usable(report.status)) problem.Store(x.data());
    return report;
}

}  // namespace driftcorr
