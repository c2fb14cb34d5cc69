// The definitions of what driftcorr/optim/fixed_lag.h declares.
#include "driftcorr/optim/fixed_lag.h"

#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>

#include "driftcorr/core/check.h"
#include "driftcorr/optim/incremental_corrector.h"

namespace driftcorr {
namespace {

// The number of pose and scale variables of `problem` (they come first; the heading-rate biases
// follow). `last_segment`: the scale segment of the problem's last step.
int JointVariables(const WindowProblem& problem, int last_segment) {
    return problem.ScaleVar(last_segment) + 1;
}

// The Gauss-Newton information of `problem` at its initial point over its pose and scale
// variables, the heading-rate biases held at their values. A fixed height (planar mode: no term
// sees it) gets a unit diagonal so that the matrix can be factored without coupling it to
// anything.
Eigen::SparseMatrix<double> Information(const WindowProblem& problem, int n, bool fix_height) {
    std::vector<double> x(problem.NumVariables());
    problem.InitialPoint(x.data());
    std::vector<LinearisedTerm> terms;
    problem.LineariseTerms(x.data(), terms);
    std::vector<Eigen::Triplet<double>> entries;
    for (const LinearisedTerm& t : terms) {
        if (!(t.information > 0.0)) continue;
        for (int a = 0; a < t.size; ++a) {
            for (int b = 0; b < t.size; ++b) {
                if (t.var[a] >= n || t.var[b] >= n) continue;
                entries.emplace_back(t.var[a], t.var[b],
                                     t.information * t.jacobian[a] * t.jacobian[b]);
            }
        }
    }
    if (fix_height) {
        for (std::size_t i = problem.first(); i <= problem.last(); ++i) {
            entries.emplace_back(problem.PoseVar(i, 2), problem.PoseVar(i, 2), 1.0);
        }
        if (problem.PoseVar(problem.first() - 1, 2) >= 0) {
            const int z = problem.PoseVar(problem.first() - 1, 2);
            entries.emplace_back(z, z, 1.0);
        }
    }
    Eigen::SparseMatrix<double> h(n, n);
    h.setFromTriplets(entries.begin(), entries.end());
    return h;
}

// The joint marginal of pose `pose` and the scale of `segment` under `problem`'s NLL (the
// heading-rate biases given), linearised at its initial point x0 (the state):
// f(x0 + d) ~ f(x0) + g^T d + d^T H d / 2 (H Gauss-Newton, over the pose and scale variables).
// Its minimiser d* = -H^-1 g and covariance H^-1, read at the five variables: the mean shift and
// the 5x5 block.
struct JointMarginal {
    JointMatrix sigma;
    JointVector shift;
};

std::optional<JointMarginal> Marginal(const WindowProblem& problem, std::size_t pose, int segment,
                                      bool with_scale, bool fix_height) {
    const int n =
        with_scale ? JointVariables(problem, segment) : problem.PoseVar(problem.last(), 3) + 1;
    const Eigen::SparseMatrix<double> h = Information(problem, n, fix_height);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(h);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return std::nullopt;
    const int vars[5] = {problem.PoseVar(pose, 0), problem.PoseVar(pose, 1),
                         problem.PoseVar(pose, 2), problem.PoseVar(pose, 3),
                         problem.ScaleVar(segment)};
    const int k = with_scale ? 5 : 4;
    JointMarginal m;
    m.sigma.setZero();
    m.shift.setZero();
    Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
    for (int c = 0; c < k; ++c) {
        e.setZero();
        e[vars[c]] = 1.0;
        const Eigen::VectorXd col = ldlt.solve(e);
        for (int r = 0; r < k; ++r) m.sigma(r, c) = col[vars[r]];
    }
    std::vector<double> x0(problem.NumVariables()), g(problem.NumVariables());
    problem.InitialPoint(x0.data());
    problem.Gradient(x0.data(), g.data());
    const Eigen::VectorXd step = ldlt.solve(-Eigen::Map<const Eigen::VectorXd>(g.data(), n));
    for (int c = 0; c < k; ++c) m.shift[c] = step[vars[c]];
    if (!m.sigma.allFinite() || !m.shift.allFinite()) return std::nullopt;
    m.sigma = 0.5 * (m.sigma + m.sigma.transpose());
    if (fix_height) m.sigma.row(2).setZero(), m.sigma.col(2).setZero(), m.shift[2] = 0.0;
    return m;
}

// The inverse on the variables that are not fixed (height excluded when fixed): a covariance from
// an information matrix, or the other way round. N = 4 (a pose) or 5 (a pose and its scale).
template <int N>
std::optional<Eigen::Matrix<double, N, N>> InverseOnFree(const Eigen::Matrix<double, N, N>& m,
                                                         bool fix_height) {
    using Matrix = Eigen::Matrix<double, N, N>;
    std::vector<int> idx;
    for (int k = 0; k < N; ++k) {
        if (!(fix_height && k == 2)) idx.push_back(k);
    }
    const int f = static_cast<int>(idx.size());
    Eigen::MatrixXd sub(f, f);
    for (int r = 0; r < f; ++r) {
        for (int c = 0; c < f; ++c) sub(r, c) = m(idx[r], idx[c]);
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(sub);
    if (!lu.isInvertible()) return std::nullopt;
    const Eigen::MatrixXd inv = lu.inverse();
    Matrix out = Matrix::Zero();
    for (int r = 0; r < f; ++r) {
        for (int c = 0; c < f; ++c) out(idx[r], idx[c]) = inv(r, c);
    }
    if (!out.allFinite()) return std::nullopt;
    return Matrix(0.5 * (out + out.transpose()));
}

// The boundary pose's covariance under `prior` (its scale integrated out).
std::optional<PoseMatrix> BoundaryCovariance(const PosePriorTerm& prior, bool fix_height) {
    if (!prior.HasScale()) return InverseOnFree<4>(prior.information, fix_height);
    const std::optional<JointMatrix> sigma = InverseOnFree<5>(prior.JointInformation(), fix_height);
    if (!sigma) return std::nullopt;
    return PoseMatrix(sigma->topLeftCorner<4, 4>());
}

}  // namespace

std::optional<PosePriorTerm> MarginalPrior(TrajectoryState& s, const TraversableField* field,
                                           const ModelConfig& model, std::size_t first,
                                           std::size_t last,
                                           const std::optional<PosePriorTerm>& prior,
                                           bool with_scale) {
    DRIFTCORR_CHECK(first >= 1 && first <= last && last < s.poses.size(), "bad marginal window");
    const WindowProblem problem(s, field, model, first, last,
                                std::vector<std::uint8_t>(last - first + 1, 0),
                                WindowUse::kLinearise, prior);
    const int segment = s.scale_segment[last];
    const std::optional<JointMarginal> m =
        Marginal(problem, last, segment, with_scale, s.fix_height);
    if (!m) return std::nullopt;
    const PoseState& b = s.poses[last];
    PosePriorTerm out;
    out.mean = PoseVector(b.p.x(), b.p.y(), b.p.z(), b.yaw_rad) + m->shift.head<4>();
    if (!with_scale) {
        const std::optional<PoseMatrix> info =
            InverseOnFree<4>(PoseMatrix(m->sigma.topLeftCorner<4, 4>()), s.fix_height);
        if (!info) return std::nullopt;
        out.information = *info;
        return out;
    }
    const std::optional<JointMatrix> info = InverseOnFree<5>(m->sigma, s.fix_height);
    if (!info) return std::nullopt;
    out.information = info->topLeftCorner<4, 4>();
    out.scale_segment = segment;
    out.scale_mean = s.scales[segment] + m->shift[4];
    out.cross = info->topRightCorner<4, 1>();
    out.scale_information = (*info)(4, 4);
    return out;
}

FixedLagSmoother::FixedLagSmoother(const PoseState& pose0, bool fix_height,
                                   const TraversableField* field, const CorrectorConfig& config,
                                   bool marginalise, bool boundary_scale, double start_scale)
    : state_(StartState(pose0, fix_height, config.model)),
      field_(field),
      cfg_(config),
      marginalise_(marginalise),
      boundary_scale_(boundary_scale),
      scored_prior_mean_(config.model.scale_prior_mean) {
    dist_.assign(1, 0.0);
    state_.scales[0] = start_scale;
    cfg_.model.scale_prior_mean = start_scale;
}

double FixedLagSmoother::Nll(std::size_t end) {
    DRIFTCORR_CHECK(end >= 1 && end <= solved_end_, "Nll of poses not solved");
    ModelConfig scored = cfg_.model;
    scored.scale_prior_mean = scored_prior_mean_;
    return SoftNll(state_, field_, scored, end);
}

void FixedLagSmoother::Append(const PoseState& initial, const StepObservation& step) {
    StepObservation o = step;
    const ModelConfig& m = cfg_.model;
    if (m.step_length_exponent != 1.0 && GaitStep(o, m.max_speed_mps)) {  // about the steps so far
        gait_median_.Add(o.length_m);
        ReadAtGait(o, gait_median_.Median(), m.step_length_exponent, m.max_speed_mps);
    }
    AppendStep(state_, initial, o, dist_.back(), elapsed_s_, m);
    elapsed_s_ += std::max(o.dt_s, 0.0);
    dist_.push_back(dist_.back() + o.length_m);
}

FixedLagSolution FixedLagSmoother::Adopt(const std::vector<PoseState>& poses,
                                         const std::vector<double>& scales,
                                         const std::vector<double>& biases) {
    const std::size_t n = solved_end_ + 1;
    DRIFTCORR_CHECK(
        poses.size() == n && scales.size() == n && (biases.empty() || biases.size() == n),
        "Adopt needs a pose, a scale and a bias (or none) for every solved pose");
    for (std::size_t i = 1; i < n; ++i) {
        state_.poses[i] = poses[i];
        state_.scales[state_.scale_segment[i]] = scales[i];
        if (!state_.bias_segment.empty() && !biases.empty())
            state_.biases[state_.bias_segment[i]] = biases[i];
    }
    window_first_ = 1;  // the next boundary prior: the whole prefix marginalised, pose 0 known
    window_prior_.reset();
    FixedLagSolution out = Package(1, solved_end_);
    out.usable = true;
    return out;
}

FixedLagSolution FixedLagSmoother::Package(std::size_t first, std::size_t end) const {
    FixedLagSolution out;
    out.first = first;
    out.end = end;
    out.poses.assign(state_.poses.begin() + first, state_.poses.begin() + end + 1);
    out.scales.assign(state_.scales.begin(), state_.scales.begin() + state_.scale_segment[end] + 1);
    if (!state_.bias_segment.empty()) {
        out.biases.assign(state_.biases.begin(),
                          state_.biases.begin() + state_.bias_segment[end] + 1);
    }
    return out;
}

// The batch windows' rule: about window_m of path, at most max_window_poses poses.
std::size_t FixedLagSmoother::WindowFirst(std::size_t end) const {
    std::size_t first = end;
    while (first > 1 && dist_[end] - dist_[first - 1] <= cfg_.window_m &&
           end - first + 1 < cfg_.max_window_poses) {
        --first;
    }
    return first;
}

// The marginalised past of pose `boundary` (see the header): the last window's terms up to the
// boundary (or up to its end, then the odometry beyond it). nullopt: the boundary is pose 0 (the
// known start), or the curvature was singular (the boundary is then held fixed).
std::optional<PosePriorTerm> FixedLagSmoother::BoundaryPrior(std::size_t boundary) {
    if (boundary == 0) return std::nullopt;
    if (!marginalise_) return std::nullopt;
    if (boundary + 1 == window_first_) return window_prior_;
    std::optional<PosePriorTerm> prior = window_prior_;
    std::size_t from = window_first_;
    if (solved_end_ >= window_first_) {  // the solved part: with the map
        const std::size_t to = std::min(boundary, solved_end_);
        prior = MarginalPrior(state_, field_, cfg_.model, from, to, prior, boundary_scale_);
        if (!prior) return std::nullopt;
        from = to + 1;
    }
    if (boundary >= from) {  // never solved: odometry only
        prior = MarginalPrior(state_, nullptr, cfg_.model, from, boundary, prior, boundary_scale_);
    }
    return prior;
}

// The covariance of pose `end` for the output's uncertainty, with the batch's model
// (ComputeCovariance: the map offset correlated along the path, the variance components) over
// the window [first, end] relative to its boundary pose first-1, plus the boundary's own
// uncertainty (the marginalised prior's covariance) carried rigidly to pose `end`: a boundary
// moved by (dx, dy, dyaw) moves the window with it.
std::optional<PoseMatrix> FixedLagSmoother::EndCovariance(
    std::size_t first, std::size_t end, const std::optional<PosePriorTerm>& prior) const {
    TrajectoryState window;  // poses first-1 (held fixed, as pose 0) .. end
    window.obs.assign(state_.obs.begin() + (first - 1), state_.obs.begin() + end + 1);
    window.obs.front() = StepObservation{};
    window.scale_segment.assign(state_.scale_segment.begin() + (first - 1),
                                state_.scale_segment.begin() + end + 1);
    window.scales = state_.scales;
    if (!state_.bias_segment.empty()) {
        window.bias_segment.assign(state_.bias_segment.begin() + (first - 1),
                                   state_.bias_segment.begin() + end + 1);
        window.biases = state_.biases;
    }
    window.poses.assign(state_.poses.begin() + (first - 1), state_.poses.begin() + end + 1);
    window.fix_height = state_.fix_height;
    const CovarianceResult cov = ComputeCovariance(window, field_, cfg_.model, cfg_.covariance);
    if (cov.status != CovarianceStatus::kOk) return std::nullopt;
    PoseMatrix sigma = ToPoseMatrix(cov.poses.back());
    if (!prior) return sigma;  // the boundary is the known start
    const PoseState& b = state_.poses[first - 1];
    const PoseState& e = state_.poses[end];
    PoseMatrix j = PoseMatrix::Identity();  // d pose_end / d pose_boundary, the window rigid
    j(0, 3) = -(e.p.y() - b.p.y());
    j(1, 3) = e.p.x() - b.p.x();
    if (state_.fix_height) j(2, 2) = 0.0;
    const std::optional<PoseMatrix> sigma_b = BoundaryCovariance(*prior, state_.fix_height);
    if (!sigma_b) return std::nullopt;
    return PoseMatrix(sigma + j * *sigma_b * j.transpose());
}

FixedLagSolution FixedLagSmoother::Solve(std::size_t end, bool restarts) {
    DRIFTCORR_CHECK(solved_end_ < end && end < size(), "a solve must add poses");
    RepairRecentEpisodes(state_, end, cfg_.model);
    SeedNewScales(state_, solved_end_ + 1, end);
    ComposeOdometry(state_, solved_end_ + 1, end);
    const std::size_t first = WindowFirst(end);
    const std::optional<PosePriorTerm> prior = BoundaryPrior(first - 1);
    const SolveReport rep =
        SolveSoftWindow(state_, field_, cfg_, first, end, prior, restarts, stats_);
    ++stats_.windows;
    FixedLagSolution out = Package(prior ? first - 1 : first, end);
    out.boundary_prior = prior.has_value();
    out.usable = Usable(rep.status);
    out.poor = field_ && PoorWindow(state_, *field_, cfg_, first, end, rep);
    if (!out.usable) ++stats_.window_failures;
    if (const std::optional<PoseMatrix> sigma = EndCovariance(first, end, prior)) {
        out.end_covariance = ToPoseCovariance(*sigma);
        out.end_covariance_ok = true;
    }
    solved_end_ = end;
    window_first_ = first;
    window_prior_ = prior;
    return out;
}

}  // namespace driftcorr
