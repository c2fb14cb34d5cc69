#pragma once
// The online corrector's solver: a fixed-lag smoother. Each solve re-solves the trailing window of
// about window_m of path that ends at a given pose (usually the newest), so its cost is bounded by
// the window, not by the trajectory. The poses before the window are not forgotten and not held
// fixed: they are marginalised into a Gaussian prior on the window's boundary pose first-1 and
// its segment's step-length scale, which are then variables (core PosePriorTerm, WindowProblem's
// boundary prior).
//
// The prior (method). Window k solved [f_k, e_k] with prior P_k on pose f_k - 1 and its segment's
// step-length scale. The next window [f, e] starts at f >= f_k. Its boundary pose b = f - 1 and
// the scale s_g of b's segment g receive the marginal, onto (b, s_g), of every term the new window
// leaves out: P_k and the terms of window k on poses up to b, with the scale walks and ranges of
// the segments up to g,
//   H_old = sum information J J^T over those terms at the current state (WindowProblem::
//   LineariseTerms on [f_k, b] with P_k) over the poses and scales,
//   Sigma = (H_old^-1) on (b, s_g),
// which is the Schur complement of H_old onto (b, s_g): the earlier poses and segments integrated
// out, the heading-rate biases held at their values. The new window makes s_g a variable under
// the prior (its walk and range terms are in the prior, not added again): when the window learns
// that the scale was wrong, the scale and the boundary's place along the track move together, as
// they do in the batch's joint solve. A prior on the pose alone, given the scales, holds the scale
// at what the first windows found; integrating the scales out of it while the window held the
// earlier ones fixed counts their uncertainty twice (measured: docs/results.md, "Online correction
// that keeps up").
// The linear term is kept: the state is the previous window's optimum, not the old terms' own,
// so their gradient g_old there is not zero (it balanced the terms the new window keeps). The
// prior's mean is the (b, s_g)-part of the old terms' Gauss-Newton minimiser,
// x + (-H_old^-1 g_old); without it every solve would let the kept terms pull the boundary off,
// one bias per solve.
// When b lies beyond the last solved pose e_k (the solver skipped ahead over poses it never
// solved), the marginal at e_k is carried to b through the odometry terms of the steps between
// (the same construction without the map: the dead-reckoning covariance). Fixed heights (planar
// mode) are not in the prior. A pose 0 boundary is the known start, held fixed.
// The heading-rate biases of segments before the window stay fixed at their last solution; their
// random walks tie the window's first ones to them (as in the batch windows).
//
// No I/O, no threads. Not thread-safe.
#include <cstddef>
#include <optional>
#include <vector>

#include "driftcorr/core/cost_terms.h"
#include "driftcorr/core/observables.h"
#include "driftcorr/optim/corrector.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/window_problem.h"

namespace driftcorr {

/// What one fixed-lag solve produced.
struct FixedLagSolution {
    std::size_t first = 0;         ///< first pose in `poses` (the boundary pose when it moved)
    std::size_t end = 0;           ///< the window's last pose
    std::vector<PoseState> poses;  ///< poses [first, end] as solved
    std::vector<double> scales;    ///< step-length scale of segments [0, segment of end]
    /// Heading-rate bias of bias segments [0, bias segment of end] [rad/s]; empty: the model
    /// has none.
    std::vector<double> biases;
    bool usable = false;  ///< the solver returned a usable solution (else the state is kept)
    bool boundary_prior = false;  ///< the boundary pose carried a marginalised prior
    /// The solution fails the windows' restart test even after its restarts (PoorWindow: poses
    /// off the roads, a high NLL per pose): the chain may be in a wrong basin.
    bool poor = false;
    /// Covariance of pose `end`: the batch's covariance model (ComputeCovariance) over the
    /// window relative to its boundary, plus the boundary's marginalised uncertainty carried
    /// rigidly (end_covariance_ok false when a matrix could not be factored).
    PoseCovariance end_covariance;
    bool end_covariance_ok = false;
};

/// The joint marginal of pose `last` and the step-length scale of its segment under the NLL of
/// window [first, last] (with `prior` on pose first-1; none: pose first-1 held fixed), the
/// heading-rate biases given, linearised at the state's values (gradient and Gauss-Newton
/// curvature), as a prior (PosePriorTerm with scale_segment = the segment of step `last`): mean =
/// the pose and scale moved by their part of the Gauss-Newton step, information = the inverse of
/// their 5x5 covariance (zero height row and column when heights are fixed). nullopt when the
/// curvature is singular (an unobserved variable). Precondition: 1 <= first <= last <
/// s.poses.size().
/// `with_scale` false: the marginal of the pose alone, the scales held at their values (a prior
/// without scale_segment).
std::optional<PosePriorTerm> MarginalPrior(TrajectoryState& s, const TraversableField* field,
                                           const ModelConfig& model, std::size_t first,
                                           std::size_t last,
                                           const std::optional<PosePriorTerm>& prior,
                                           bool with_scale = true);

class FixedLagSmoother {
public:
    /// Starts from the known pose 0. `field` may be null (odometry only) and must outlive this.
    /// Uses config.window_m, max_window_poses, model, window_ipopt and the restart settings.
    /// `marginalise`: the boundary pose carries the marginalised prior; false: it is held fixed
    /// at its last solution (the batch windows' rule). `boundary_scale`: the prior is joint with
    /// the boundary segment's scale (MarginalPrior with_scale).
    /// `start_scale`: the step-length scale the first segment starts from (later segments start
    /// from the latest estimate); the windows hold the scale prior about it (a hypothesis the
    /// first windows keep), Nll() about config's mean, so that hypotheses' NLLs compare.
    FixedLagSmoother(const PoseState& pose0, bool fix_height, const TraversableField* field,
                     const CorrectorConfig& config, bool marginalise = true,
                     bool boundary_scale = true, double start_scale = 1.0);

    /// Appends pose i = size() with its observation (the step from pose i-1); `initial` gives
    /// its height in planar mode (positions and heading are dead-reckoned when solved).
    void Append(const PoseState& initial, const StepObservation& step);
    std::size_t size() const { return state_.poses.size(); }
    /// The last pose covered by a solve (0: none yet).
    std::size_t solved_end() const { return solved_end_; }

    /// Solves the window ending at `end` (poses after the last solve are dead-reckoned onto it
    /// first). `restarts`: also try the other step-length scale hypotheses when the solution
    /// looks like a wrong basin. Precondition: solved_end() < end < size().
    FixedLagSolution Solve(std::size_t end, bool restarts);

    /// SoftNll of poses [1, end] as they stand (each at its last solution). Time linear in `end`.
    /// Precondition: 1 <= end <= solved_end().
    double Nll(std::size_t end);

    /// Path length from pose 0 to pose i [m] (the odometry's, as read). Precondition: i < size().
    double PathTo(std::size_t i) const { return dist_[i]; }

    /// Replaces the solution of poses [0, solved_end()] by another correction of the same poses
    /// (a re-localisation: the prefix solved as a whole): `poses` their states, `scales` and
    /// `biases` per pose (the step-length scale and heading-rate bias each pose moved by; biases
    /// may be empty: none). Each scale segment takes the scale of its last pose, each bias
    /// segment its bias. The next window's boundary prior is then marginalised from the whole
    /// prefix at the new solution. Precondition: the three sizes are solved_end() + 1 (biases:
    /// or 0).
    /// Returns the adopted solution as a solve's (poses [1, solved_end()], not poor; no
    /// covariance).
    FixedLagSolution Adopt(const std::vector<PoseState>& poses, const std::vector<double>& scales,
                           const std::vector<double>& biases);

    /// Window statistics so far (windows, restarts, iterations, failures).
    const CorrectionResult& stats() const { return stats_; }

private:
    /// Poses [first, end], the scales and biases up to end's segments, as a solution.
    FixedLagSolution Package(std::size_t first, std::size_t end) const;
    std::size_t WindowFirst(std::size_t end) const;
    std::optional<PosePriorTerm> BoundaryPrior(std::size_t boundary);
    std::optional<PoseMatrix> EndCovariance(std::size_t first, std::size_t end,
                                            const std::optional<PosePriorTerm>& prior) const;

    TrajectoryState state_;
    const TraversableField* field_;
    CorrectorConfig cfg_;
    bool marginalise_;
    bool boundary_scale_;
    double scored_prior_mean_;  ///< the scale prior's mean in Nll()
    std::vector<double> dist_;  ///< path length from pose 0 [m]
    double elapsed_s_ = 0.0;    ///< time of the appended steps [s]
    /// The median of the odometry's lengths of the GaitSteps so far
    /// (ModelConfig::step_length_exponent).
    RunningMedian gait_median_;
    std::size_t solved_end_ = 0;                 ///< last pose of the last solve
    std::size_t window_first_ = 1;               ///< first pose of the last solved window
    std::optional<PosePriorTerm> window_prior_;  ///< its prior on pose window_first_ - 1
    CorrectionResult stats_;
};

}  // namespace driftcorr
