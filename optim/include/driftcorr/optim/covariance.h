#pragma once
// Per-pose uncertainty of a corrected trajectory: the marginal covariances of the poses under the
// curvature of the weighted NLL at the solution, in time linear in the number of poses.
//
// Method.
//  1. The Gauss-Newton Hessian H = sum_i information_i J_i J_i^T of every term at the solution
//     (WindowProblem::LineariseTerms; core Linearisation): Gaussian terms w / sigma^2, the robust
//     (Cauchy) terms their IRLS weight, the map distance term max(rho''(d), 0) along grad d
//     (within a centre line's interpolation band along the line's unit normal). Positive
//     semi-definite by construction, and equal to the exact Hessian where every residual is zero.
//     Pose 0 (the known start) and fixed heights (planar mode) are not unknowns.
//  1b. The map term informs only across its pose's direction of travel (CovarianceConfig::
//     map_across_travel): its horizontal Jacobian J becomes (J . n) n, n the unit normal of the
//     pose's yaw. Moving a pose along the road it drives on leaves its distance to that road as
//     it is, so the min over the roads' distances rises by at most that road's term; at a junction
//     passed straight through, the crossing street's centre line is the nearer one and grad d
//     points along the travel, a curvature that holds only until the road driven on is nearer
//     again. Along-track information comes from the poses after a turn, whose travel is across
//     the road before it.
//  2. The map's error is not independent from pose to pose: the lane the platform keeps and the
//     map's own offset stay the same along a street, so more poses on it do not average it away
//     (independent terms would make the covariance shrink with the pose rate). A share of the map
//     variance becomes an offset b(path) of the map (East, North), a Gauss-Markov process along
//     the path with correlation length map_offset_correlation_m, sampled by one unknown pair per
//     quarter of it; each map term's residual becomes d(p - b) ~ d - grad d . b with the local b
//     (CovarianceConfig). Two-dimensional because a misplaced junction moves its streets along as
//     well as across: the along-track position a turn fixes keeps that uncertainty down the next
//     straight.
//  2b. Likewise the step length's error, when CovarianceConfig::step_error_sd > 0: a share e(path)
//     of the step, a Gauss-Markov process along the estimated path with standard deviation
//     step_error_sd and correlation length step_error_correlation_m, one unknown per quarter of
//     it; each step length residual becomes r - s L e_k. Independent step errors average away
//     along a corridor, so without it the position between two turns is too certain where the
//     step length errs with the gait for tens of steps (a pedestrian's dead reckoning).
//  3. Unknowns in the chain's order, each scale segment's and process stretch's unknown right after
//     the last pose that uses it: eliminating a pose fills only towards the next pose and the open
//     segments, so the factor H = L D L^T (Eigen::SimplicialLDLT, natural order) has O(n) entries.
//  4. Selected inversion (Takahashi, Fagan & Chin 1973; Erisman & Tinney 1975): the entries of
//     Sigma = H^-1 on the pattern of L + L^T, from the last column to the first,
//       Sigma(i, j) = -sum_{k in L(:, j)} Sigma(i, k) L(k, j)          for i in L(:, j), i > j,
//       Sigma(j, j) = 1 / D(j) - sum_{k in L(:, j)} L(k, j) Sigma(k, j),
//     in O(sum_j nnz(L(:, j))^2) operations; no dense inverse is formed. The pattern holds every
//     pose's own block and every pair of unknowns that share a term.
//  5. Redundancy numbers r_i = 1 - information_i J_i^T Sigma J_i (sum r_i = m - n) and chi2 per
//     term family; the a posteriori variance factor of least-squares adjustment
//       sigma0^2 = sum_i chi2_i / (m - n)   (= 2 NLL of the IRLS-weighted Gaussian model / (m -
//       n)),
//     m the terms with information > 0, n the unknowns.
//  6. Variance components (Foerstner 1979, one step): a family of observations whose residuals
//     exceed its sigmas (chi2 / redundancy > 1, from at least one redundant observation) has its
//     variance multiplied by that factor and the inversion is repeated once (on KITTI further
//     steps change the factors by < 1 %; with little redundancy they diverge). Factors are never
//     below 1: the solution absorbs correlated errors (a scale drift, a lane offset), so residuals
//     understate errors. The priors (heading preservation, the map offset) keep their variances.
//
// Hard corridor constraints: where the final solve's corridor constraint is active the posterior
// is truncated by the corridor; this first version ignores the constraints and uses the
// curvature of the soft NLL alone (the map term's curvature already pulls across the road).
// Positions East-North-Up [m], yaw [rad].
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/params.h"
#include "driftcorr/optim/window_problem.h"

namespace driftcorr {

/// Marginal covariance of one pose. Pose 0 (the known start) has all zeros.
struct PoseCovariance {
    Eigen::Matrix2d xy_m2 = Eigen::Matrix2d::Zero();  ///< East, North [m^2]
    double z_m2 = 0.0;                                ///< height; 0 when heights are fixed [m^2]
    double yaw_rad2 = 0.0;                            ///< [rad^2]
    Eigen::Vector2d xy_yaw_m_rad = Eigen::Vector2d::Zero();  ///< cov(East, yaw), cov(North, yaw)
};

struct CovarianceConfig {
    /// Share of the map term's variance (map_sigma_m^2) that is an offset (East, North) common to
    /// the poses along a street (method step 2), in [0, 1). 0: every map term independent, the
    /// solver's own model. The total variance per pose stays the model's map_sigma_m^2.
    double map_offset_share = 0.5;
    /// Correlation length of that offset along the path [m]: a street between junctions.
    double map_offset_correlation_m = 100.0;
    /// Each map term informs only across its pose's direction of travel (method step 1b); false:
    /// along grad d as the solver's model has it. Along the road a pose drives on its distance to
    /// the map stays the same, so moving the pose along its travel costs at most that road's
    /// term: where a crossing street's centre line is nearer (a junction passed straight
    /// through) grad d points along the travel, and its curvature would fix the pose along the
    /// track where no turn does.
    bool map_across_travel = true;
    /// Standard deviation of the step length's slowly varying error, as a share of the step
    /// (method step 2b), >= 0; 0: the step lengths' errors are independent, the solver's own
    /// model. Pedestrian dead reckoning's step length errs with the gait for tens of steps at a
    /// time; the solver's model has only the scale walk for that.
    double step_error_sd = 0.0;
    /// Correlation length of that error along the estimated path [m].
    double step_error_correlation_m = 10.0;
    /// Variance components of the observation families (method step 6); false: the model's
    /// sigmas as they are.
    bool family_variance_components = true;
    /// Multiply the covariances by the a posteriori variance factor sigma0^2 (method step 5;
    /// always reported). Off: on every drive measured it is far below 1 (0.08-0.5), because the
    /// map terms, most of the redundancy, fit the solution closer than their sigma (the solution
    /// absorbs the map's offset) and the heading-preservation prior is deliberately weak; applied,
    /// it shrinks covariances that are already too small (docs/results.md, Uncertainty).
    bool apply_variance_factor = false;
    /// A drive of more poses is computed block by block, each block of this many poses from the
    /// terms of the block and a tenth of a block on either side (the pose before them held
    /// fixed), which bounds the memory; shorter drives are computed whole.
    std::size_t block_poses = 50000;

    /// The first value kCovarianceParams does not allow.
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "covariance.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// The covariance settings of a CorrectorConfig (not a params.yaml section).
inline constexpr Param<CovarianceConfig> kCovarianceParamRows[] = {
    {"map_offset_share", Field<&CovarianceConfig::map_offset_share>(),
     ParamRange{0.0, 1.0, false, true},
     "share of the map variance that is an offset common along a street"},
    {"map_offset_correlation_m", Field<&CovarianceConfig::map_offset_correlation_m>(), kPositive,
     "correlation length of that offset along the path"},
    {"map_across_travel", Field<&CovarianceConfig::map_across_travel>(), kNoRange,
     "map terms inform only across each pose's direction of travel"},
    {"step_error_sd", Field<&CovarianceConfig::step_error_sd>(), kNonNegative,
     "slowly varying step length error, share of the step; 0: independent"},
    {"step_error_correlation_m", Field<&CovarianceConfig::step_error_correlation_m>(), kPositive,
     "correlation length of that error along the path"},
    {"family_variance_components", Field<&CovarianceConfig::family_variance_components>(), kNoRange,
     "variance components of the observation families"},
    {"apply_variance_factor", Field<&CovarianceConfig::apply_variance_factor>(), kNoRange,
     "multiply the covariances by the a posteriori variance factor"},
    {"block_poses", Field<&CovarianceConfig::block_poses>(), AtLeast(10),
     "a longer drive's covariance is computed in blocks of this many poses"},
};
inline constexpr ParamTable<CovarianceConfig> kCovarianceParams{"covariance", kCovarianceParamRows};

enum class CovarianceStatus {
    kNotComputed,
    kOk,
    kNotPositiveDefinite,  ///< the Gauss-Newton Hessian is singular: some variable is unobserved
    kBadInput,             ///< fewer than 2 poses, or an inconsistent state
};
const char* ToString(CovarianceStatus status);

/// What one term family contributes to the variance factor (after its variance component).
struct FamilyStatistics {
    std::size_t terms = 0;    ///< terms with information > 0
    double chi2 = 0.0;        ///< sum of the terms' IRLS-weighted squared normalised residuals
    double redundancy = 0.0;  ///< sum of the terms' redundancy numbers (0..terms)
    /// The family's variance factor estimate chi2 / redundancy (1 when redundancy is ~0).
    double VarianceFactor() const { return redundancy > 1e-9 ? chi2 / redundancy : 1.0; }
};

inline std::array<double, kTermFamilies> UnitFactors() {
    std::array<double, kTermFamilies> f;
    f.fill(1.0);
    return f;
}

struct CovarianceResult {
    CovarianceStatus status = CovarianceStatus::kNotComputed;
    std::string message;
    /// One per pose of the state; valid only when status == kOk. Scaled by variance_factor when
    /// variance_factor_applied.
    std::vector<PoseCovariance> poses;
    double variance_factor = 1.0;  ///< sigma0^2 = sum chi2 / (m - n) [-]
    bool variance_factor_applied = false;
    std::size_t observations = 0;                            ///< m: terms with information > 0
    std::size_t unknowns = 0;                                ///< n
    std::array<FamilyStatistics, kTermFamilies> families{};  ///< indexed by TermFamily
    /// The variance component applied to each family (method step 6; 1: as modelled); families
    /// holds the statistics after it.
    std::array<double, kTermFamilies> family_factors = UnitFactors();
    std::size_t factor_nonzeros = 0;  ///< entries of L below the diagonal (fill diagnostic)
    /// Standard deviation of the drive's mean step-length scale, its scale segments weighted by
    /// the estimated path each covers: the uncertainty of the corrected path over the input's.
    /// After the variance components, scaled as the poses' are. NaN for a drive computed in
    /// blocks (CovarianceConfig::block_poses).
    double mean_scale_sd = std::numeric_limits<double>::quiet_NaN();
};

/// Whether an offset `d` [m] from a pose lies inside that pose's horizontal 95 % region, of
/// covariance `xy_m2` (false unless it is positive definite).
bool InsideRegion95(const Eigen::Vector2d& d, const Eigen::Matrix2d& xy_m2);
/// The least share of trajectory poses inside their 95 % regions that does not reject "the
/// trajectory is as likely as the truth": 95 % less the one-sided 5 % margin of a binomial share
/// (normal approximation) over `samples` independent stretches (at least one). The poses of a
/// stretch of a map offset's correlation length share its error, so that length is one sample.
double AgreementShareThreshold(double samples);

/// The covariance [East, North, up, yaw] of pose b = ComposeStep(a, step, scale, ...) given pose
/// a's, to first order: a's through the step's Jacobian plus the step's own noise (StepNoiseOf;
/// length along the step direction, lateral across it, height unless `fix_height`, heading).
/// Dead reckoning's growth of the uncertainty, step by step.
PoseMatrix PropagateStep(const PoseMatrix& sigma_a, const PoseState& a, const StepObservation& step,
                         double scale, bool fix_height, const ModelConfig& model);
/// The 4x4 [East, North, up, yaw] matrix as the result type, and back.
PoseCovariance ToPoseCovariance(const PoseMatrix& sigma);
PoseMatrix ToPoseMatrix(const PoseCovariance& c);

/// The matrix the covariance inverts, for tests and diagnostics: the information matrix of the
/// unknowns (both triangles) after the variance components, and per pose its unknowns x, y, z,
/// yaw (-1: fixed; pose 0 all -1).
struct CovarianceSystem {
    Eigen::SparseMatrix<double> information;
    std::vector<std::array<int, 4>> pose_unknowns;
};

/// The marginal covariance of every pose of a solved trajectory (poses 1..n-1 free, pose 0 held
/// fixed, heights free unless state.fix_height; field may be null: odometry only), from the
/// Gauss-Newton curvature of the NLL that WindowProblem(state, field, model, 1, n-1) defines.
/// Time and memory linear in the number of poses, memory bounded by config.block_poses. Numerical
/// outcomes are the status, never an exception. `system`, when given, receives the matrix that
/// was inverted (not for a drive computed in blocks: then it is left as it is).
/// Precondition: config.Validate() is empty.
CovarianceResult ComputeCovariance(const TrajectoryState& state, const TraversableField* field,
                                   const ModelConfig& model, const CovarianceConfig& config = {},
                                   CovarianceSystem* system = nullptr);

/// The Gauss-Newton Hessian sum_i information_i J_i J_i^T of `problem`'s objective at x over all
/// of its variables (fixed ones included), dense and symmetric. For tests on small problems.
Eigen::MatrixXd DenseGaussNewtonHessian(const WindowProblem& problem, const double* x);

}  // namespace driftcorr
