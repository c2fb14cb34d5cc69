// The definitions of what driftcorr/optim/ipopt_solver.h declares.
#include "driftcorr/optim/ipopt_solver.h"

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>
#include <algorithm>
#include <cmath>
#include <mutex>
#include <vector>

namespace driftcorr {
namespace {

using Ipopt::Index;
using Ipopt::Number;

// Thin TNLP adapter: every callback forwards to the solver-independent WindowProblem.
class WindowTnlp : public Ipopt::TNLP {
public:
    WindowTnlp(WindowProblem& p, std::function<void(int)> on_iteration)
        : p_(p), on_iteration_(std::move(on_iteration)) {}

    bool get_nlp_info(Index& n, Index& m, Index& nnz_jac, Index& nnz_h,
                      IndexStyleEnum& style) override {
        n = p_.NumVariables();
        m = p_.NumConstraints();
        nnz_jac = static_cast<Index>(p_.JacobianStructure().size());
        nnz_h = static_cast<Index>(p_.HessianStructure().size());
        style = C_STYLE;
        return true;
    }
    bool get_bounds_info(Index, Number* x_l, Number* x_u, Index, Number* g_l,
                         Number* g_u) override {
        p_.Bounds(x_l, x_u, g_l, g_u);
        return true;
    }
    bool get_starting_point(Index, bool init_x, Number* x, bool, Number*, Number*, Index, bool,
                            Number*) override {
        if (init_x) p_.InitialPoint(x);
        return true;
    }
    bool eval_f(Index, const Number* x, bool, Number& f) override {
        f = p_.Objective(x);
        return std::isfinite(f);
    }
    bool eval_grad_f(Index, const Number* x, bool, Number* g) override {
        p_.Gradient(x, g);
        return true;
    }
    bool eval_g(Index, const Number* x, bool, Index, Number* g) override {
        p_.Constraints(x, g);
        return true;
    }
    bool eval_jac_g(Index, const Number* x, bool, Index, Index, Index* rows, Index* cols,
                    Number* values) override {
        if (!values) {
            const auto& s = p_.JacobianStructure();
            for (std::size_t k = 0; k < s.size(); ++k) rows[k] = s[k].first, cols[k] = s[k].second;
        } else {
            p_.JacobianValues(x, values);
        }
        return true;
    }
    bool eval_h(Index, const Number* x, bool, Number obj_factor, Index, const Number* lambda, bool,
                Index, Index* rows, Index* cols, Number* values) override {
        if (!values) {
            const auto& s = p_.HessianStructure();
            for (std::size_t k = 0; k < s.size(); ++k) rows[k] = s[k].first, cols[k] = s[k].second;
        } else {
            p_.HessianValues(x, obj_factor, lambda, values);
        }
        return true;
    }
    bool intermediate_callback(Ipopt::AlgorithmMode, Index iter, Number, Number, Number, Number,
                               Number, Number, Number, Number, Index, const Ipopt::IpoptData*,
                               Ipopt::IpoptCalculatedQuantities*) override {
        if (on_iteration_ && iter > 0) on_iteration_(iter);
        return true;
    }
    void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*,
                           const Number*, Index m, const Number* g, const Number*, Number obj,
                           const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
        x_.assign(x, x + n);
        objective_ = obj;
        max_violation_ = 0.0;
        std::vector<Number> gl(m), gu(m), xl(n), xu(n);
        if (m > 0) p_.Bounds(xl.data(), xu.data(), gl.data(), gu.data());
        for (Index k = 0; k < m; ++k) max_violation_ = std::max(max_violation_, g[k] - gu[k]);
    }

    std::vector<double> x_;
    double objective_ = 0.0, max_violation_ = 0.0;

private:
    WindowProblem& p_;
    std::function<void(int)> on_iteration_;
};

SolveStatus MapStatus(Ipopt::ApplicationReturnStatus s) {
    switch (s) {
        case Ipopt::Solve_Succeeded:
            return SolveStatus::kSuccess;
        case Ipopt::Solved_To_Acceptable_Level:
            return SolveStatus::kAcceptable;
        case Ipopt::Maximum_Iterations_Exceeded:
        case Ipopt::Maximum_CpuTime_Exceeded:
            return SolveStatus::kMaxIterations;
        case Ipopt::Infeasible_Problem_Detected:
            return SolveStatus::kInfeasible;
        default:
            return SolveStatus::kFailed;
    }
}

std::string StatusName(Ipopt::ApplicationReturnStatus s) {
    switch (s) {
        case Ipopt::Solve_Succeeded:
            return "Solve_Succeeded";
        case Ipopt::Solved_To_Acceptable_Level:
            return "Solved_To_Acceptable_Level";
        case Ipopt::Infeasible_Problem_Detected:
            return "Infeasible_Problem_Detected";
        case Ipopt::Search_Direction_Becomes_Too_Small:
            return "Search_Direction_Becomes_Too_Small";
        case Ipopt::Diverging_Iterates:
            return "Diverging_Iterates";
        case Ipopt::User_Requested_Stop:
            return "User_Requested_Stop";
        case Ipopt::Feasible_Point_Found:
            return "Feasible_Point_Found";
        case Ipopt::Maximum_Iterations_Exceeded:
            return "Maximum_Iterations_Exceeded";
        case Ipopt::Restoration_Failed:
            return "Restoration_Failed";
        case Ipopt::Error_In_Step_Computation:
            return "Error_In_Step_Computation";
        case Ipopt::Maximum_CpuTime_Exceeded:
            return "Maximum_CpuTime_Exceeded";
        case Ipopt::Not_Enough_Degrees_Of_Freedom:
            return "Not_Enough_Degrees_Of_Freedom";
        case Ipopt::Invalid_Problem_Definition:
            return "Invalid_Problem_Definition";
        case Ipopt::Invalid_Option:
            return "Invalid_Option";
        case Ipopt::Invalid_Number_Detected:
            return "Invalid_Number_Detected";
        default:
            return "Ipopt_Internal_Error (" + std::to_string(static_cast<int>(s)) + ")";
    }
}

}  // namespace

SolveReport SolveWithIpopt(WindowProblem& problem, const IpoptOptions& options) {
    // MUMPS keeps state in Fortran module variables and is not thread-safe (Ipopt >= 3.14 locks
    // around it itself; Debian's 3.11 does not): one solve at a time in the process, held for the
    // application's whole life, which creates and destroys the MUMPS instance.
    static std::mutex mumps_mutex;
    const std::lock_guard<std::mutex> lock(mumps_mutex);
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
    app->Options()->SetIntegerValue("print_level", options.print_level);
    app->Options()->SetStringValue("sb", "yes");
    app->Options()->SetStringValue("linear_solver", "mumps");  // the only one Debian ships
    // A fill-reducing ordering that is the same on every run: MUMPS's automatic choice takes
    // METIS (SCOTCH is the same), whose orderings change from run to run, and with them the
    // rounding; on kitti05 cvo the final solve then ended in one of two solutions (7.45 m and
    // `ok`, or 7.65 m after Maximum_Iterations_Exceeded and `failed`) on identical input. AMF
    // (2) was the fastest of the run-to-run identical orderings (AMD 0, AMF 2, PORD 4, QAMD 6)
    // summed over the three KITTI drives whose final solve needs Ipopt; it costs them 0.2-0.8 s
    // against METIS (docs/results.md).
    app->Options()->SetIntegerValue("mumps_pivot_order", 2);
    app->Options()->SetStringValue("hessian_approximation", "exact");
    app->Options()->SetStringValue("mu_strategy", "adaptive");
    app->Options()->SetIntegerValue("max_iter", options.max_iterations);
    app->Options()->SetNumericValue("max_cpu_time", options.max_cpu_time_s);
    app->Options()->SetNumericValue("tol", options.tolerance);
    app->Options()->SetNumericValue("acceptable_tol", options.acceptable_tolerance);
    app->Options()->SetNumericValue("constr_viol_tol", options.constraint_tolerance);
    SolveReport report;
    if (app->Initialize() != Ipopt::Solve_Succeeded) {
        report.message = "Ipopt initialisation failed";
        return report;
    }
    Ipopt::SmartPtr<WindowTnlp> tnlp = new WindowTnlp(problem, options.on_iteration);
    const Ipopt::ApplicationReturnStatus s = app->OptimizeTNLP(Ipopt::GetRawPtr(tnlp));
    report.status = MapStatus(s);
    report.message = StatusName(s);
    if (Ipopt::IsValid(app->Statistics())) report.iterations = app->Statistics()->IterationCount();
    report.objective = tnlp->objective_;
    report.max_violation_m = tnlp->max_violation_;
    if (Usable(report.status) && !tnlp->x_.empty()) problem.Store(tnlp->x_.data());
    return report;
}

}  // namespace driftcorr
