// The definitions of what driftcorr/optim/covariance.h declares.
#include "driftcorr/optim/covariance.h"

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <optional>

#include "driftcorr/core/check.h"

namespace driftcorr {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// The covariance model's processes along the path (method steps 2 and 2b): the map's position
// error and the step length's error, each a Gauss-Markov process with one unknown (East and
// North for the map's) per stretch of 1 / kStretchesPerCorrelation of its correlation length that
// holds terms, numbered after the window's variables.
constexpr double kStretchesPerCorrelation = 4.0;

// A family's variance component is estimated only from at least one redundant observation.
constexpr double kMinRedundancy = 1.0;

struct PathProcess {
    int first_var = 0;                   // variable of stretch 0's first component
    int dims = 1;                        // components per stretch
    std::vector<std::size_t> last_pose;  // per stretch: the last pose of its terms
    int NumVars() const { return dims * static_cast<int>(last_pose.size()); }
};

// Builds a process: assigns terms, which come in pose order, to its stretches, then adds its own
// terms, per component: x_0 ~ N(0, 1 / information), x_k+1 - rho x_k ~ N(0, (1 - rho^2) /
// information) with rho = exp(-path between the stretches / correlation length).
class StretchBuilder {
public:
    StretchBuilder(PathProcess& process, double correlation_m)
        : process_(process),
          correlation_m_(correlation_m),
          stretch_m_(correlation_m / kStretchesPerCorrelation) {}

    /// The first variable of the stretch of a term of `pose` at path position `path_m`.
    int Var(std::size_t pose, double path_m) {
        const auto stretch = static_cast<long>(path_m / stretch_m_);
        if (stretch != last_stretch_) {
            last_stretch_ = stretch;
            process_.last_pose.push_back(0), centre_m_.push_back(0.0), count_.push_back(0);
        }
        process_.last_pose.back() = pose;
        centre_m_.back() += path_m, ++count_.back();
        return process_.first_var + process_.dims * (static_cast<int>(count_.size()) - 1);
    }

    void AddPriors(double information, TermFamily family, std::vector<LinearisedTerm>& terms) {
        for (std::size_t k = 0; k < process_.last_pose.size(); ++k) {
            centre_m_[k] /= count_[k];
            const double rho =
                k == 0 ? 0.0 : std::exp(-(centre_m_[k] - centre_m_[k - 1]) / correlation_m_);
            for (int c = 0; c < process_.dims; ++c) {
                const int var = process_.first_var + process_.dims * static_cast<int>(k) + c;
                LinearisedTerm t;
                t.family = family;
                if (k > 0) t.var[t.size] = var - process_.dims, t.jacobian[t.size++] = -rho;
                t.var[t.size] = var, t.jacobian[t.size++] = 1.0;
                t.information = information / std::max(1.0 - rho * rho, 1e-9);
                terms.push_back(t);
            }
        }
    }

private:
    PathProcess& process_;
    double correlation_m_, stretch_m_;
    std::vector<int> count_;        // per stretch: its terms
    std::vector<double> centre_m_;  // per stretch: the mean path position of its terms
    long last_stretch_ = -1;
};

// Where a map term's Jacobian holds its pose's East and North (entries at[c], -1: not there)
// and their values.
struct HorizontalEntries {
    int at[2] = {-1, -1};
    Eigen::Vector2d j = Eigen::Vector2d::Zero();
};

HorizontalEntries Horizontal(const LinearisedTerm& t, int x_var) {
    HorizontalEntries h;
    for (int a = 0; a < t.size; ++a) {
        for (int c = 0; c < 2; ++c) {
            if (t.var[a] == x_var + c) h.at[c] = a, h.j[c] = t.jacobian[a];
        }
    }
    return h;
}

// Keeps of each map term's horizontal Jacobian only its component across the pose's direction of
// travel (method step 1b).
void KeepMapTermsAcrossTravel(const TrajectoryState& s, const WindowProblem& p,
                              std::vector<LinearisedTerm>& terms) {
    for (LinearisedTerm& t : terms) {
        if (t.family != TermFamily::kMapDistance) continue;
        const auto pose = static_cast<std::size_t>(t.pose);
        const int x_var = p.PoseVar(pose, 0);
        if (x_var < 0) continue;
        const double yaw = s.poses[pose].yaw_rad;
        const Eigen::Vector2d across(-std::sin(yaw), std::cos(yaw));
        const HorizontalEntries h = Horizontal(t, x_var);
        const Eigen::Vector2d kept = h.j.dot(across) * across;
        for (int c = 0; c < 2; ++c) {
            if (h.at[c] >= 0) t.jacobian[h.at[c]] = kept[c];
        }
    }
}

// Makes each map term's residual d(p - b_k) ~ d - grad d . b_k (variance (1 - share)
// map_sigma^2) and adds, per component, the process b_0 ~ N(0, share map_sigma^2),
// b_k+1 - rho b_k ~ N(0, (1 - rho^2) share map_sigma^2) with rho = exp(-path between the
// stretches / correlation length). The offset is two-dimensional: a misplaced junction or a
// map drawn off the true positions moves its streets along as well as across, so along a
// straight street the map term sees only the offset's cross component, and the along-track
// position that a turn fixed keeps the along component's uncertainty.
PathProcess AddMapOffset(const std::vector<double>& path_m, const WindowProblem& p,
                         const ModelConfig& model, const CovarianceConfig& config,
                         std::vector<LinearisedTerm>& terms) {
    PathProcess offset;
    offset.first_var = p.NumVariables();
    offset.dims = 2;
    if (!(config.map_offset_share > 0.0)) return offset;
    StretchBuilder stretches(offset, config.map_offset_correlation_m);
    for (LinearisedTerm& t : terms) {
        if (t.family != TermFamily::kMapDistance || !(t.information > 0.0)) continue;
        const auto pose = static_cast<std::size_t>(t.pose);
        const int b = stretches.Var(pose, path_m[pose]);
        t.information /= 1.0 - config.map_offset_share;
        t.chi2 /= 1.0 - config.map_offset_share;
        const Eigen::Vector2d j = Horizontal(t, p.PoseVar(pose, 0)).j;
        for (int c = 0; c < 2; ++c) t.var[t.size] = b + c, t.jacobian[t.size++] = -j[c];
    }
    const double info =
        model.map_weight / (config.map_offset_share * model.map_sigma_m * model.map_sigma_m);
    stretches.AddPriors(info, TermFamily::kMapOffset, terms);
    return offset;
}

// Makes each scaled step length residual r = along - s L into r - s L e_k (method step 2b) and
// adds the process e_0 ~ N(0, sd^2), e_k+1 - rho e_k ~ N(0, (1 - rho^2) sd^2). Steps without a
// scale unknown (discontinuities of the estimate) and stops keep their residual.
PathProcess AddStepError(const TrajectoryState& s, const std::vector<double>& path_m,
                         const WindowProblem& p, const CovarianceConfig& config, int first_var,
                         std::vector<LinearisedTerm>& terms) {
    PathProcess error;
    error.first_var = first_var;
    if (!(config.step_error_sd > 0.0)) return error;
    StretchBuilder stretches(error, config.step_error_correlation_m);
    for (LinearisedTerm& t : terms) {
        if (t.family != TermFamily::kStepLength || !(t.information > 0.0) || t.pose < 1) continue;
        const auto i = static_cast<std::size_t>(t.pose);
        const int scale_var = p.ScaleVar(s.scale_segment[i]);
        const bool scaled =
            std::find(t.var.begin(), t.var.begin() + t.size, scale_var) != t.var.begin() + t.size;
        const double length = s.scales[s.scale_segment[i]] * s.obs[i].length_m;
        if (!scaled || !(length > 0.0)) continue;
        const int e = stretches.Var(i, path_m[i - 1]);
        t.var[t.size] = e, t.jacobian[t.size++] = -length;
    }
    stretches.AddPriors(1.0 / (config.step_error_sd * config.step_error_sd), TermFamily::kStepError,
                        terms);
    return error;
}

// The unknowns of the covariance: every variable that is not held fixed, in the chain's order
// (method step 3). of_var[v] is the index of variable v, -1 when v is fixed.
struct Ordering {
    std::vector<int> of_var;
    int size = 0;
};

Ordering ChainOrdering(const WindowProblem& p, const TrajectoryState& s,
                       const std::array<const PathProcess*, 2>& processes) {
    Ordering o;
    int vars = p.NumVariables();
    for (const PathProcess* process : processes) vars += process->NumVars();
    o.of_var.assign(vars, -1);
    const std::size_t n = s.poses.size();
    int next_segment = s.scale_segment[1];
    int next_bias = s.bias_segment.empty() ? 0 : s.bias_segment[1];
    std::array<std::size_t, 2> next_stretch{0, 0};
    if (p.PoseVar(0, 0) >= 0) {  // pose 0 under a boundary prior: a variable, first
        for (int c = 0; c < 4; ++c) {
            if (c != 2 || !s.fix_height) o.of_var[p.PoseVar(0, c)] = o.size++;
        }
    }
    for (std::size_t i = 1; i < n; ++i) {
        for (int c = 0; c < 4; ++c) {
            if (c != 2 || !s.fix_height) o.of_var[p.PoseVar(i, c)] = o.size++;
        }
        // The scale segments no later step uses and the process stretches ending here follow
        // pose i.
        const int open = i + 1 < n ? s.scale_segment[i + 1] : s.scale_segment[n - 1] + 1;
        for (; next_segment < open; ++next_segment) o.of_var[p.ScaleVar(next_segment)] = o.size++;
        if (!s.bias_segment.empty()) {  // likewise the heading-rate bias segments
            const int open_bias = i + 1 < n ? s.bias_segment[i + 1] : s.bias_segment[n - 1] + 1;
            for (; next_bias < open_bias; ++next_bias) o.of_var[p.BiasVar(next_bias)] = o.size++;
        }
        for (std::size_t q = 0; q < processes.size(); ++q) {
            const PathProcess& process = *processes[q];
            std::size_t& k = next_stretch[q];
            for (; k < process.last_pose.size() && process.last_pose[k] == i; ++k) {
                for (int c = 0; c < process.dims; ++c) {
                    o.of_var[process.first_var + process.dims * static_cast<int>(k) + c] = o.size++;
                }
            }
        }
    }
    return o;
}

// The lower triangle of the Gauss-Newton Hessian over the ordered unknowns, plus structural zeros
// that keep each pose's own block in the factor's pattern.
SparseMatrix AssembleLower(const std::vector<LinearisedTerm>& terms, const Ordering& o,
                           const WindowProblem& p, const TrajectoryState& s) {
    // Assembled in chunks of at most kChunk entries, each added to the sum: the entries of all
    // terms at once (about 36 per term) would hold several kilobytes a pose at the peak.
    constexpr std::size_t kChunk = std::size_t(1) << 20;
    SparseMatrix h(o.size, o.size);
    std::vector<Eigen::Triplet<double, int>> triplets;
    triplets.reserve(kChunk + kMaxBlockVars * kMaxBlockVars);
    const auto flush = [&] {
        SparseMatrix part(o.size, o.size);
        part.setFromTriplets(triplets.begin(), triplets.end());
        h = h.nonZeros() == 0 ? part : SparseMatrix(h + part);
        triplets.clear();
    };
    for (std::size_t i = 1; i < s.poses.size(); ++i) {  // every pose's own block in the pattern
        const int first = o.of_var[p.PoseVar(i, 0)], last = o.of_var[p.PoseVar(i, 3)];
        for (int r = first; r <= last; ++r) {
            for (int c = first; c <= r; ++c) triplets.emplace_back(r, c, 0.0);
        }
        if (triplets.size() >= kChunk) flush();
    }
    for (const LinearisedTerm& t : terms) {
        if (!(t.information > 0.0)) continue;
        for (int a = 0; a < t.size; ++a) {
            const int ra = o.of_var[t.var[a]];
            if (ra < 0) continue;
            for (int b = 0; b < t.size; ++b) {
                const int rb = o.of_var[t.var[b]];
                if (rb < 0 || rb > ra) continue;
                triplets.emplace_back(ra, rb, t.information * t.jacobian[a] * t.jacobian[b]);
            }
        }
        if (triplets.size() >= kChunk) flush();
    }
    if (!triplets.empty()) flush();
    return h;
}

// Sigma = (L D L^T)^-1 on the pattern of L + L^T (method step 4). L: unit lower triangular,
// strictly lower part stored column by column with ascending rows, as SimplicialLDLT keeps it.
class SelectedInverse {
public:
    SelectedInverse(const SparseMatrix& l, const Eigen::VectorXd& d)
        : lp_(l.outerIndexPtr(), l.outerIndexPtr() + l.cols() + 1),
          li_(l.innerIndexPtr(), l.innerIndexPtr() + l.nonZeros()),
          lower_(l.nonZeros()),
          diag_(l.cols()) {
        const double* lx = l.valuePtr();
        for (int j = static_cast<int>(l.cols()) - 1; j >= 0; --j) {
            const int b = lp_[j], e = lp_[j + 1];
            for (int p = b; p < e; ++p) {
                double sum = 0.0;
                for (int q = b; q < e; ++q) sum += (*this)(li_[p], li_[q]) * lx[q];
                lower_[p] = -sum;
            }
            double djj = 1.0 / d[j];
            for (int p = b; p < e; ++p) djj -= lx[p] * lower_[p];
            diag_[j] = djj;
        }
    }

    /// Sigma(r, c). Precondition: (r, c) is on the diagonal or in the pattern of L + L^T.
    double operator()(int r, int c) const {
        if (r == c) return diag_[r];
        if (r < c) std::swap(r, c);
        const auto begin = li_.begin() + lp_[c], end = li_.begin() + lp_[c + 1];
        const auto it = std::lower_bound(begin, end, r);
        DRIFTCORR_CHECK(it != end && *it == r, "entry outside the factor's pattern");
        return lower_[it - li_.begin()];
    }

private:
    std::vector<int> lp_;
    std::vector<int> li_;
    std::vector<double> lower_;
    std::vector<double> diag_;
};

// The first D(j) that is not safely positive (relative to H(j, j)), or -1.
int FirstNonPositivePivot(const Eigen::VectorXd& d, const SparseMatrix& h_lower) {
    for (int j = 0; j < d.size(); ++j) {
        const double hjj = h_lower.coeff(j, j);
        if (!std::isfinite(d[j]) || !(d[j] > 1e-13 * std::abs(hjj)) || !(d[j] > 0.0)) return j;
    }
    return -1;
}

// Factors the Gauss-Newton Hessian of `terms` and inverts it on the factor's pattern; nothing
// (and r.status, r.message set) when it is not positive definite. `h` receives the lower triangle.
// With `functional` (one weight per unknown) r.mean_scale_sd is set to the standard deviation of
// that linear combination of the unknowns, sqrt(w^T H^-1 w), by one solve with the factor.
std::optional<SelectedInverse> Invert(const std::vector<LinearisedTerm>& terms,
                                      const Ordering& order, const WindowProblem& problem,
                                      const TrajectoryState& state, CovarianceResult& r,
                                      SparseMatrix& h,
                                      const Eigen::VectorXd* functional = nullptr) {
    h = AssembleLower(terms, order, problem, state);
    Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::NaturalOrdering<int>> ldlt(h);
    DRIFTCORR_CHECK(ldlt.permutationP().size() == 0, "the chain order must be kept");
    const int bad = ldlt.info() == Eigen::Success ? FirstNonPositivePivot(ldlt.vectorD(), h) : -2;
    if (bad != -1) {
        r.status = CovarianceStatus::kNotPositiveDefinite;
        r.message = "Gauss-Newton Hessian not positive definite (" +
                    (bad >= 0 ? "pivot of unknown " + std::to_string(bad) : "a zero pivot") +
                    " of " + std::to_string(order.size) + "): a variable the terms do not observe";
        return std::nullopt;
    }
    if (functional) {
        r.mean_scale_sd = std::sqrt(std::max(functional->dot(ldlt.solve(*functional)), 0.0));
    }
    const SparseMatrix& l = ldlt.matrixL().nestedExpression();
    r.factor_nonzeros = static_cast<std::size_t>(l.nonZeros());
    return SelectedInverse(l, ldlt.vectorD());
}

PoseCovariance PoseBlock(const SelectedInverse& sigma, const Ordering& o, const WindowProblem& p,
                         std::size_t pose, bool fix_height) {
    const int x = o.of_var[p.PoseVar(pose, 0)], y = o.of_var[p.PoseVar(pose, 1)];
    const int yaw = o.of_var[p.PoseVar(pose, 3)];
    PoseCovariance c;
    c.xy_m2 << sigma(x, x), sigma(x, y), sigma(x, y), sigma(y, y);
    c.z_m2 = fix_height ? 0.0 : sigma(o.of_var[p.PoseVar(pose, 2)], o.of_var[p.PoseVar(pose, 2)]);
    c.yaw_rad2 = sigma(yaw, yaw);
    c.xy_yaw_m_rad = Eigen::Vector2d(sigma(x, yaw), sigma(y, yaw));
    return c;
}

// Observations, redundancy numbers and chi2 per family; the variance factor (method step 5).
void Statistics(const std::vector<LinearisedTerm>& terms, const Ordering& o,
                const SelectedInverse& sigma, CovarianceResult& r) {
    r.families = {};
    r.observations = 0;
    double chi2 = 0.0;
    for (const LinearisedTerm& t : terms) {
        if (!(t.information > 0.0)) continue;
        double leverage = 0.0;  // information J^T Sigma J
        for (int a = 0; a < t.size; ++a) {
            const int ra = o.of_var[t.var[a]];
            if (ra < 0) continue;
            for (int b = 0; b < t.size; ++b) {
                const int rb = o.of_var[t.var[b]];
                if (rb >= 0) leverage += t.jacobian[a] * t.jacobian[b] * sigma(ra, rb);
            }
        }
        FamilyStatistics& f = r.families[static_cast<int>(t.family)];
        ++f.terms;
        f.chi2 += t.chi2;
        f.redundancy += 1.0 - t.information * leverage;
        chi2 += t.chi2;
        ++r.observations;
    }
    r.variance_factor =
        r.observations > r.unknowns ? chi2 / double(r.observations - r.unknowns) : 1.0;
}

// Multiplies the variance of every observation family whose chi2 exceeds its redundancy by that
// ratio (method step 6); false (and nothing changed) when every ratio is below 1.01.
bool ScaleFamilies(CovarianceResult& r, std::vector<LinearisedTerm>& terms) {
    std::array<double, kTermFamilies> factor;
    bool changed = false;
    for (int f = 0; f < kTermFamilies; ++f) {
        const auto family = static_cast<TermFamily>(f);
        const bool prior =
            family == TermFamily::kHeadingPreservation || family == TermFamily::kMapOffset ||
            family == TermFamily::kScaleRange || family == TermFamily::kHeadingBiasWalk ||
            family == TermFamily::kBoundaryPrior || family == TermFamily::kFloorHeight ||
            family == TermFamily::kLiftDistance || family == TermFamily::kStepError;
        const bool estimable = r.families[f].redundancy >= kMinRedundancy;
        factor[f] = prior || !estimable ? 1.0 : std::max(1.0, r.families[f].VarianceFactor());
        changed = changed || factor[f] > 1.01;
    }
    if (!changed) return false;
    r.family_factors = factor;
    for (LinearisedTerm& t : terms) {
        const double k = factor[static_cast<int>(t.family)];
        t.information /= k, t.chi2 /= k;
    }
    return changed;
}

// Both triangles of the information matrix and each pose's unknowns.
CovarianceSystem System(const SparseMatrix& h_lower, const Ordering& o, const WindowProblem& p,
                        const TrajectoryState& s) {
    CovarianceSystem system;
    system.information = h_lower.selfadjointView<Eigen::Lower>();
    system.pose_unknowns.assign(s.poses.size(), {-1, -1, -1, -1});
    for (std::size_t i = 1; i < s.poses.size(); ++i) {
        for (int c = 0; c < 4; ++c) system.pose_unknowns[i][c] = o.of_var[p.PoseVar(i, c)];
    }
    return system;
}

}  // namespace

std::optional<ParamProblem> CovarianceConfig::FindProblem() const {
    return CheckRows(kCovarianceParams, *this);
}

std::string CovarianceConfig::Validate() const {
    return ToMessage(kCovarianceParams.section, FindProblem());
}

const char* ToString(CovarianceStatus status) {
    switch (status) {
        case CovarianceStatus::kNotComputed:
            return "not computed";
        case CovarianceStatus::kOk:
            return "ok";
        case CovarianceStatus::kNotPositiveDefinite:
            return "not positive definite";
        case CovarianceStatus::kBadInput:
            return "bad input";
    }
    return "?";
}

bool InsideRegion95(const Eigen::Vector2d& d, const Eigen::Matrix2d& xy_m2) {
    constexpr double kChi2TwoDof95 = 5.991464547107979;  // -2 ln 0.05
    if (!(xy_m2(0, 0) > 0.0 && xy_m2.determinant() > 0.0)) return false;
    return d.dot(xy_m2.inverse() * d) <= kChi2TwoDof95;
}

double AgreementShareThreshold(double samples) {
    constexpr double kLevel = 0.95, kNormalOneSided95 = 1.6448536269514722;
    const double n = std::max(1.0, samples);
    return kLevel - kNormalOneSided95 * std::sqrt(kLevel * (1.0 - kLevel) / n);
}

Eigen::MatrixXd DenseGaussNewtonHessian(const WindowProblem& problem, const double* x) {
    std::vector<LinearisedTerm> terms;
    problem.LineariseTerms(x, terms);
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(problem.NumVariables(), problem.NumVariables());
    for (const LinearisedTerm& t : terms) {
        for (int a = 0; a < t.size; ++a) {
            for (int b = 0; b < t.size; ++b) {
                h(t.var[a], t.var[b]) += t.information * t.jacobian[a] * t.jacobian[b];
            }
        }
    }
    return h;
}

namespace {

// The weights of the drive's mean step-length scale over the unknowns: each scale segment's
// share of the estimated path (steps 1..n-1); a segment held fixed adds nothing.
Eigen::VectorXd MeanScaleWeights(const TrajectoryState& state, const WindowProblem& problem,
                                 const Ordering& order) {
    Eigen::VectorXd w = Eigen::VectorXd::Zero(order.size);
    double path_m = 0.0;
    for (std::size_t i = 1; i < state.poses.size(); ++i) path_m += state.obs[i].length_m;
    if (!(path_m > 0.0)) return w;
    for (std::size_t i = 1; i < state.poses.size(); ++i) {
        const int v = problem.ScaleVar(state.scale_segment[i]);
        const int k = v >= 0 ? order.of_var[v] : -1;
        if (k >= 0) w[k] += state.obs[i].length_m / path_m;
    }
    return w;
}

// The covariance of a whole consistent state (ComputeCovariance without blocks); with `prior`,
// pose 0 is not the known start but a variable under that prior (the past of a block).
CovarianceResult WholeCovariance(const TrajectoryState& state, const TraversableField* field,
                                 const ModelConfig& model, const CovarianceConfig& config,
                                 CovarianceSystem* system,
                                 const std::optional<PosePriorTerm>& prior = std::nullopt) {
    CovarianceResult r;
    const std::size_t n = state.poses.size();
    TrajectoryState copy = state;  // WindowProblem writes solutions back; this one never does
    const WindowProblem problem(copy, field, model, 1, n - 1, std::vector<std::uint8_t>(n - 1, 0),
                                WindowUse::kLinearise, prior);
    std::vector<double> x(problem.NumVariables());
    problem.InitialPoint(x.data());
    std::vector<LinearisedTerm> terms;
    terms.reserve(6 * n);
    problem.LineariseTerms(x.data(), terms);
    if (config.map_across_travel) KeepMapTermsAcrossTravel(state, problem, terms);
    const std::vector<double> path_m = PathPositions(state.obs);  // the processes run along it
    const PathProcess offset = AddMapOffset(path_m, problem, model, config, terms);
    const PathProcess step_error =
        AddStepError(state, path_m, problem, config, offset.first_var + offset.NumVars(), terms);
    const Ordering order = ChainOrdering(problem, state, {&offset, &step_error});
    r.unknowns = order.size;

    const Eigen::VectorXd mean_scale = MeanScaleWeights(state, problem, order);
    SparseMatrix h;
    std::optional<SelectedInverse> sigma = Invert(terms, order, problem, state, r, h, &mean_scale);
    if (!sigma) return r;
    Statistics(terms, order, *sigma, r);
    if (config.family_variance_components && ScaleFamilies(r, terms)) {
        sigma = Invert(terms, order, problem, state, r, h, &mean_scale);
        if (!sigma) return r;
        Statistics(terms, order, *sigma, r);
    }
    if (system) *system = System(h, order, problem, state);

    r.variance_factor_applied = config.apply_variance_factor;
    const double factor = config.apply_variance_factor ? r.variance_factor : 1.0;
    r.mean_scale_sd *= std::sqrt(factor);
    r.poses.assign(n, PoseCovariance{});
    for (std::size_t i = 1; i < n; ++i) {
        PoseCovariance c = PoseBlock(*sigma, order, problem, i, state.fix_height);
        c.xy_m2 *= factor, c.z_m2 *= factor, c.yaw_rad2 *= factor, c.xy_yaw_m_rad *= factor;
        r.poses[i] = c;
    }
    r.status = CovarianceStatus::kOk;
    r.message = std::to_string(order.size) + " unknowns, " + std::to_string(r.observations) +
                " observations, variance factor " + std::to_string(r.variance_factor) +
                (r.variance_factor_applied ? " (applied)" : " (not applied)");
    return r;
}

// Poses [from - 1, to] of `s` as a state of their own (pose from - 1 its pose 0), its scale and
// bias segments renumbered from the first that step `from` uses.
TrajectoryState SubState(const TrajectoryState& s, std::size_t from, std::size_t to) {
    TrajectoryState sub;
    sub.fix_height = s.fix_height;
    sub.obs.assign(s.obs.begin() + (from - 1), s.obs.begin() + (to + 1));
    sub.poses.assign(s.poses.begin() + (from - 1), s.poses.begin() + (to + 1));
    const auto renumber = [&](const std::vector<int>& segment, const std::vector<double>& values,
                              std::vector<int>& sub_segment, std::vector<double>& sub_values) {
        const int first = segment[from];
        for (std::size_t i = from - 1; i <= to; ++i)
            sub_segment.push_back(std::max(segment[i] - first, 0));
        sub_values.assign(values.begin() + first, values.begin() + segment[to] + 1);
    };
    renumber(s.scale_segment, s.scales, sub.scale_segment, sub.scales);
    if (!s.bias_segment.empty()) renumber(s.bias_segment, s.biases, sub.bias_segment, sub.biases);
    if (!s.height_settled.empty()) {
        sub.height_settled.assign(s.height_settled.begin() + (from - 1),
                                  s.height_settled.begin() + (to + 1));
    }
    return sub;
}

// The prior that a pose's covariance `c` makes: its mean the pose, its information the inverse
// of c on the free components (the height left out when fixed); nothing when c is singular
// there.
std::optional<PosePriorTerm> PriorFrom(const PoseCovariance& c, const PoseState& pose,
                                       bool fix_height) {
    const PoseMatrix sigma = ToPoseMatrix(c);
    std::array<int, 4> free{0, 1, 2, 3};
    int k = 0;
    for (int v = 0; v < 4; ++v) {
        if (v != 2 || !fix_height) free[k++] = v;
    }
    Eigen::MatrixXd sub(k, k);
    for (int a = 0; a < k; ++a) {
        for (int b = 0; b < k; ++b) sub(a, b) = sigma(free[a], free[b]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(sub);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.vectorD().minCoeff() > 0.0)) {
        return std::nullopt;
    }
    const Eigen::MatrixXd info = ldlt.solve(Eigen::MatrixXd::Identity(k, k));
    PosePriorTerm prior;
    prior.mean = PoseVector(pose.p.x(), pose.p.y(), pose.p.z(), pose.yaw_rad);
    for (int a = 0; a < k; ++a) {
        for (int b = 0; b < k; ++b) prior.information(free[a], free[b]) = info(a, b);
    }
    prior.information = 0.5 * (prior.information + prior.information.transpose()).eval();
    if (!prior.information.allFinite()) return std::nullopt;
    return prior;
}

// ComputeCovariance of a drive of more than config.block_poses poses, so that memory is a
// block's. Block k (poses [first, last], block_poses of them) is computed from its terms and
// those of a tenth of a block on either side, poses [from, to]; the pose before them, from - 1,
// carries the past as a prior: its covariance given the terms before it alone (a filter, not the
// smoothed marginal, which would count the overlap's terms twice). That filtered covariance is
// the last pose's of the run over [from of block k-1, from - 1], under its own prior in turn.
// The statistics add up over the blocks' runs (margins counted in each run that holds them);
// the family factors are the largest of any run.
CovarianceResult BlockCovariance(const TrajectoryState& state, const TraversableField* field,
                                 const ModelConfig& model, const CovarianceConfig& config) {
    const std::size_t n = state.poses.size(), block = config.block_poses;
    const std::size_t margin = block / 10;
    CovarianceResult r;
    r.poses.assign(n, PoseCovariance{});
    r.family_factors.fill(1.0);
    double chi2 = 0.0;
    std::size_t runs = 0;
    const auto run = [&](std::size_t from, std::size_t to,
                         const std::optional<PosePriorTerm>& prior) -> CovarianceResult {
        CovarianceResult b =
            WholeCovariance(SubState(state, from, to), field, model, config, nullptr, prior);
        if (b.status != CovarianceStatus::kOk) {
            b.message =
                "poses " + std::to_string(from) + "-" + std::to_string(to) + ": " + b.message;
            return b;
        }
        ++runs;
        r.observations += b.observations;
        r.unknowns += b.unknowns;
        r.factor_nonzeros += b.factor_nonzeros;
        for (int f = 0; f < kTermFamilies; ++f) {
            r.families[f].terms += b.families[f].terms;
            r.families[f].chi2 += b.families[f].chi2;
            r.families[f].redundancy += b.families[f].redundancy;
            r.family_factors[f] = std::max(r.family_factors[f], b.family_factors[f]);
            chi2 += b.families[f].chi2;
        }
        r.variance_factor_applied = b.variance_factor_applied;
        return b;
    };
    std::optional<PosePriorTerm> past;  // on pose from - 1; none: pose 0, the known start
    std::size_t from = 1;
    for (std::size_t first = 1; first < n; first += block) {
        const std::size_t last = std::min(n - 1, first + block - 1);
        const std::size_t to = std::min(n - 1, last + margin);
        const CovarianceResult b = run(from, to, past);
        if (b.status != CovarianceStatus::kOk) return b;
        for (std::size_t i = first; i <= last; ++i) r.poses[i] = b.poses[i - from + 1];
        if (last == n - 1) break;
        // The next block's past: the filtered covariance of pose next_from - 1.
        const std::size_t next_from = last + 1 - margin;
        const CovarianceResult f = run(from, next_from - 1, past);
        if (f.status != CovarianceStatus::kOk) return f;
        past = PriorFrom(f.poses.back(), state.poses[next_from - 1], state.fix_height);
        if (!past) {
            CovarianceResult bad;
            bad.status = CovarianceStatus::kNotPositiveDefinite;
            bad.message = "pose " + std::to_string(next_from - 1) +
                          ": its covariance, the next block's past, is singular";
            return bad;
        }
        from = next_from;
    }
    r.variance_factor =
        r.observations > r.unknowns ? chi2 / double(r.observations - r.unknowns) : 1.0;
    r.status = CovarianceStatus::kOk;
    r.message = std::to_string(runs) + " runs over blocks of at most " + std::to_string(block) +
                " poses: " + std::to_string(r.unknowns) + " unknowns, " +
                std::to_string(r.observations) + " observations, variance factor " +
                std::to_string(r.variance_factor) +
                (r.variance_factor_applied ? " (applied per run)" : " (not applied)");
    return r;
}

}  // namespace

CovarianceResult ComputeCovariance(const TrajectoryState& state, const TraversableField* field,
                                   const ModelConfig& model, const CovarianceConfig& config,
                                   CovarianceSystem* system) {
    DRIFTCORR_CHECK(config.Validate().empty(), "invalid CovarianceConfig");
    const std::size_t n = state.poses.size();
    if (n < 2 || state.obs.size() != n || state.scale_segment.size() != n ||
        !std::is_sorted(state.scale_segment.begin() + 1, state.scale_segment.end()) ||
        std::size_t(state.scale_segment.back()) >= state.scales.size() ||
        !(state.bias_segment.empty() ||
          (state.bias_segment.size() == n &&
           std::is_sorted(state.bias_segment.begin() + 1, state.bias_segment.end()) &&
           std::size_t(state.bias_segment.back()) < state.biases.size()))) {
        CovarianceResult r;
        r.status = CovarianceStatus::kBadInput;
        r.message = "need >= 2 poses with one observation and scale segment each";
        return r;
    }
    if (n - 1 > config.block_poses) return BlockCovariance(state, field, model, config);
    return WholeCovariance(state, field, model, config, system);
}

PoseMatrix PropagateStep(const PoseMatrix& sigma_a, const PoseState& a, const StepObservation& o,
                         double scale, bool fix_height, const ModelConfig& model) {
    const double phi = a.yaw_rad + o.direction_rad, len = ScaledLength(o, scale);
    const Eigen::Vector2d along(std::cos(phi), std::sin(phi)), across(-along.y(), along.x());
    PoseMatrix f = PoseMatrix::Identity();  // d pose_b / d pose_a (ComposeStep)
    f.block<2, 1>(0, 3) = len * across;
    if (fix_height) f(2, 2) = 0.0;
    const StepNoise n = StepNoiseOf(model, o);
    PoseMatrix q = PoseMatrix::Zero();
    q.topLeftCorner<2, 2>() = n.length_m * n.length_m * along * along.transpose() +
                              n.lateral_m * n.lateral_m * across * across.transpose();
    q(2, 2) = fix_height ? 0.0 : n.height_m * n.height_m;
    q(3, 3) = n.heading_rad * n.heading_rad;
    return f * sigma_a * f.transpose() + q;
}

PoseCovariance ToPoseCovariance(const PoseMatrix& sigma) {
    PoseCovariance c;
    c.xy_m2 = sigma.topLeftCorner<2, 2>();
    c.z_m2 = sigma(2, 2);
    c.yaw_rad2 = sigma(3, 3);
    c.xy_yaw_m_rad = Eigen::Vector2d(sigma(0, 3), sigma(1, 3));
    return c;
}

PoseMatrix ToPoseMatrix(const PoseCovariance& c) {
    PoseMatrix m = PoseMatrix::Zero();
    m.topLeftCorner<2, 2>() = c.xy_m2;
    m(2, 2) = c.z_m2;
    m(3, 3) = c.yaw_rad2;
    m.block<2, 1>(0, 3) = c.xy_yaw_m_rad;
    m.block<1, 2>(3, 0) = c.xy_yaw_m_rad.transpose();
    return m;
}

}  // namespace driftcorr
