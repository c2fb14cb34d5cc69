// The definitions of what driftcorr/optim/paper_solver.h declares.
#include "driftcorr/optim/paper_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"
#include "driftcorr/core/cost_terms.h"

namespace driftcorr {
namespace {

double Course(const Eigen::Vector2d& d) { return std::atan2(d.y(), d.x()); }

// The fixed inputs of one epoch: the previous corrected pose and the observed step.
struct Epoch {
    Eigen::Vector2d p_prev;
    double up_m = 0.0;
    double course_prev_rad = 0.0;  // corrected course of the previous step (unwrapped)
    double dcourse_obs_rad = 0.0;  // observed course change
    double length_m = 0.0;         // observed step length
};

// w_m min(d, h)^2 / 2 sigma_m^2 on the bilinear grid, and its gradient in (x, y). Zero outside
// the grid (no map there). Past the truncation the cost is flat: h is the road's constant.
double MapCost(const TraversableField* field, const PaperSolverConfig& c, const Eigen::Vector2d& p,
               double up_m, Eigen::Vector2d& grad) {
    grad.setZero();
    if (field == nullptr || field->empty() || c.map_weight == 0.0) return 0.0;
    const Eigen::Vector3d q(p.x(), p.y(), up_m);
    const std::optional<FieldSample> centre = field->QueryCentreBilinear(q);
    if (!centre) return 0.0;
    double h = c.map_truncation_m;
    if (h <= 0.0) {
        const std::optional<FieldSample> corridor = field->QueryCorridorBilinear(q);
        if (!corridor) return 0.0;
        h = std::max(0.0, centre->value - corridor->value);
    }
    const double k = c.map_weight / (c.map_sigma_m * c.map_sigma_m);
    if (centre->value >= h) return 0.5 * k * h * h;
    grad = k * centre->value * centre->gradient.head<2>();
    return 0.5 * k * centre->value * centre->value;
}

// E_i(p) of the header and its gradient in (x, y), through the core cost terms.
double EpochCost(const Epoch& e, const TraversableField* field, const PaperSolverConfig& c,
                 const Eigen::Vector2d& p, Eigen::Vector2d& grad) {
    const Eigen::Vector2d dp = p - e.p_prev;
    const double course = Course(dp);
    const double predicted = e.course_prev_rad + e.dcourse_obs_rad;
    StepVector x = StepVector::Zero();
    x[kXa] = e.p_prev.x(), x[kYa] = e.p_prev.y(), x[kXb] = p.x(), x[kYb] = p.y();
    x[kYawA] = e.course_prev_rad;
    x[kYawB] = predicted + AngleDiff(course, predicted);  // unwrapped near the prediction
    x[kScale] = 1.0;
    // d course / d p: the course is the step direction.
    const Eigen::Vector2d dcourse_dp =
        Eigen::Vector2d(-dp.y(), dp.x()) / std::max(dp.squaredNorm(), 1e-12);

    StepVector g;
    double cost = HeadingChangeTerm{e.dcourse_obs_rad, c.turn_sigma_rad, c.turn_weight}.Evaluate(
        x, &g, nullptr);
    grad = g[kYawB] * dcourse_dp;
    cost += HeadingPreservationTerm{c.preservation_sigma_rad, c.preservation_weight}.Evaluate(
        x, &g, nullptr);
    grad += g[kYawB] * dcourse_dp;
    // |p - p_prev| - L as the core step-length term with the direction set to the displacement's
    // own course: the projection then is the length, and its derivative through that course is
    // the sideways component, zero, so the (x_b, y_b) gradient is exact.
    StepVector xs = x;
    xs[kYawA] = course;
    cost +=
        StepLengthTerm{e.length_m, 0.0, c.step_sigma_m, c.step_weight}.Evaluate(xs, &g, nullptr);
    grad += Eigen::Vector2d(g[kXb], g[kYb]);

    Eigen::Vector2d g_map;
    cost += MapCost(field, c, p, e.up_m, g_map);
    grad += g_map;
    return cost;
}

// Course of the step into each pose, unwrapped; stops carry the last course, and pose 0 takes
// the course of the first moving step.
std::vector<double> EstimateCourses(const PlanarTrajectory& est, double stationary_m) {
    const std::size_t n = est.size();
    std::vector<double> course(n, 0.0);
    for (std::size_t i = 1; i < n; ++i) {
        const Eigen::Vector2d d = est.p_en[i] - est.p_en[i - 1];
        if (d.norm() >= stationary_m) {
            course[0] = Course(d);
            break;
        }
    }
    for (std::size_t i = 1; i < n; ++i) {
        const Eigen::Vector2d d = est.p_en[i] - est.p_en[i - 1];
        course[i] = d.norm() >= stationary_m ? course[i - 1] + AngleDiff(Course(d), course[i - 1])
                                             : course[i - 1];
    }
    return course;
}

}  // namespace

std::optional<ParamProblem> PaperSolverConfig::FindProblem() const {
    if (auto problem = CheckRows(kPaperSolverParams, *this)) return problem;
    if (!(min_step_m >= stationary_m)) {
        return RelationProblem("min_step_m", min_step_m, ">=", "stationary_m", stationary_m);
    }
    // Fixed-step descent on a quadratic of curvature k is stable only for learning_rate * k < 2.
    if (learning_rate * step_weight / (step_sigma_m * step_sigma_m) >= 2.0) {
        return ParamProblem{"step_sigma_m",
                            "too small for learning_rate (learning_rate * step_weight / "
                            "step_sigma_m^2 must be < 2)",
                            "learning_rate"};
    }
    const double turn_k =
        (turn_weight / (turn_sigma_rad * turn_sigma_rad) +
         preservation_weight / (preservation_sigma_rad * preservation_sigma_rad)) /
        (min_step_m * min_step_m);
    if (learning_rate * turn_k >= 2.0) {
        return ParamProblem{"min_step_m",
                            "too small for learning_rate and turn_sigma_rad (learning_rate * turn "
                            "curvature at min_step_m must be < 2)",
                            "learning_rate"};
    }
    return std::nullopt;
}

std::string PaperSolverConfig::Validate() const {
    return ToMessage(kPaperSolverParams.section, FindProblem());
}

CorrectionResult CorrectWithPaperMethod(const PlanarTrajectory& estimate,
                                        const TraversableField* field,
                                        const PaperSolverConfig& config,
                                        const ProgressCallback& progress) {
    DRIFTCORR_CHECK(estimate.size() >= 3, "the paper solver needs at least 3 poses");
    DRIFTCORR_CHECK(config.Validate().empty(), "invalid PaperSolverConfig");
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t n = estimate.size();
    CorrectionResult res;
    res.corrected = estimate;
    const std::vector<double> course_est = EstimateCourses(estimate, config.stationary_m);
    std::vector<double> course_corr(n, course_est[0]);
    const std::size_t report_every = std::max<std::size_t>(1, n / 100);

    for (std::size_t i = 1; i < n; ++i) {
        const Eigen::Vector2d& p_prev = res.corrected.p_en[i - 1];
        const double length = (estimate.p_en[i] - estimate.p_en[i - 1]).norm();
        const double dcourse = course_est[i] - course_est[i - 1];
        const double predicted = course_corr[i - 1] + dcourse;
        // Start: the previous corrected pose composed with the observed step.
        Eigen::Vector2d p =
            p_prev + length * Eigen::Vector2d(std::cos(predicted), std::sin(predicted));
        course_corr[i] = predicted;
        if (length >= config.min_step_m) {
            const Epoch e{p_prev, estimate.up_m[i], course_corr[i - 1], dcourse, length};
            Eigen::Vector2d grad;
            for (int it = 0; it < config.iterations_per_epoch; ++it) {
                EpochCost(e, field, config, p, grad);
                p -= config.learning_rate * grad;  // plain gradient descent, fixed step
            }
            res.iterations += config.iterations_per_epoch;
            if (!p.allFinite()) {
                res.status = SolveStatus::kFailed;
                res.message = "paper solver: gradient descent diverged at epoch " +
                              std::to_string(i) + " of " + std::to_string(n);
                res.corrected = PlanarTrajectory{};
                return res;
            }
            course_corr[i] = predicted + AngleDiff(Course(p - p_prev), predicted);
        }
        res.corrected.p_en[i] = p;
        if (progress && (i % report_every == 0 || i + 1 == n)) progress({"paper", i + 1, n});
    }
    if (estimate.HasYaw()) {
        for (std::size_t i = 0; i < n; ++i) {
            res.corrected.yaw_rad[i] = estimate.yaw_rad[i] + (course_corr[i] - course_est[i]);
        }
    }
    res.status = SolveStatus::kSuccess;
    res.message = "paper method: " + std::to_string(n - 1) + " epochs, " +
                  std::to_string(res.iterations) + " gradient steps";
    res.incremental_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
}

}  // namespace driftcorr
