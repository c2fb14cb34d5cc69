#pragma once
// The incremental machinery of the batch corrector (CorrectTrajectory; OnlineCorrector::Finish
// runs it too): a growing trajectory state, solved chunk by chunk. SolveSoftWindow, the window
// solve with restarts, is shared with the online corrector's fixed-lag windows (fixed_lag.h).
//
// One chunk step (SolveChunk): the scale segments first entered by the new poses start from the
// latest scale estimate, the new poses are dead-reckoned by composing the odometry observations
// onto the corrected end, and a trailing window of about window_m of path is re-solved with the
// soft terms (the Newton solver, or Ipopt with window_newton false), restarting from other
// step-length scale hypotheses when the solution lands in a poor basin. Finish() then solves the
// whole trajectory with the hard corridor constraints (Ipopt; with refine_newton, only when a
// constrained pose lies outside its corridor at the soft terms' minimum).
//
// What a window keeps of the poses before it (they are not re-solved): pose first-1 is held fixed
// and anchors the window through the step and heading terms of step `first`; the step-length scale
// of the segments before the window is held fixed and the scale random walk ties the window's first
// scale segment to it. No marginalisation prior (covariance) is carried here: the boundary pose is
// treated as exact (the batch windows re-solve everything in the refinement; the online windows
// carry one, fixed_lag.h).
//
// No I/O, no threads: the caller decides when to solve. Not thread-safe.
#include <cstddef>
#include <optional>
#include <vector>

#include "driftcorr/optim/correction_result.h"
#include "driftcorr/optim/corrector_config.h"
#include "driftcorr/optim/window_problem.h"

namespace driftcorr {

class IncrementalCorrector {
public:
    /// Starts from a whole trajectory's initial state (the batch case): `state` holds every pose,
    /// observation and scale segment; poses [0, 0] count as corrected. `field` may be null
    /// (odometry only) and must outlive this object.
    IncrementalCorrector(TrajectoryState state, const TraversableField* field,
                         const CorrectorConfig& config);
    /// Starts from a whole trajectory that is already corrected (`state` as a correction left
    /// it, possibly with other unknowns added): done() is the last pose and Finish() refines it.
    struct Corrected {};
    IncrementalCorrector(TrajectoryState state, const TraversableField* field,
                         const CorrectorConfig& config, Corrected);
    /// Starts from a single known pose 0 (the online case); poses are added with Append.
    IncrementalCorrector(const PoseState& pose0, bool fix_height, const TraversableField* field,
                         const CorrectorConfig& config);

    /// Appends pose i = size() with its observation (the step from pose i-1) and its initial
    /// value (only its height is used, in planar mode; position and heading are dead-reckoned).
    void Append(const PoseState& initial, const StepObservation& step);

    std::size_t size() const { return state_.poses.size(); }
    /// Poses [0, done()] are corrected.
    std::size_t done() const { return done_; }
    /// Path length from pose 0 to pose i along the estimate [m].
    double PathLength(std::size_t i) const { return dist_[i]; }

    /// True when the chunk starting after done() is complete at pose `end` (the batch rule:
    /// chunk_m of path or max_chunk_poses poses). Precondition: done() < end < size().
    bool ChunkCompleteAt(std::size_t end) const;
    /// End of the next chunk of the batch rule, or the last pose. Precondition: done()+1 < size().
    std::size_t NextChunkEnd() const;
    /// Initialises poses (done(), end] by odometry and solves the trailing window ending at `end`.
    /// Precondition: done() < end < size().
    void SolveChunk(std::size_t end);
    /// Solves chunks until every appended pose is corrected.
    void SolveRemaining(const ProgressCallback& progress = {});
    /// Final whole-trajectory solve with the hard corridor (if config.refine) and the outcome.
    /// `t_s`: the timestamp of every pose. Precondition: size() >= 3, done()+1 == size().
    CorrectionResult Finish(const std::vector<double>& t_s, const ProgressCallback& progress = {});

    const TrajectoryState& state() const { return state_; }
    /// Replaces every step observation (the poses stay): a correction composed from other
    /// readings of the odometry is then refined and scored against `obs`. Precondition:
    /// obs.size() == size().
    void ReplaceObservations(std::vector<StepObservation> obs);
    /// The NLL of the current state: the objective of the soft terms over poses [1, size()-1]
    /// (what the final solve minimises; its hard corridor adds no cost). Leaves the state as it
    /// is. Precondition: size() >= 2.
    double Nll();
    /// The mean of the first scale's prior in the solves from now on (ModelConfig::
    /// scale_prior_mean): CorrectFromStarts solves a start's windows about the start's scale and
    /// its final solve, whose NLL is compared, about the configured mean.
    void SetScalePriorMean(double mean) { cfg_.model.scale_prior_mean = mean; }
    /// The covariance of the current state (ComputeCovariance with config.covariance) and its
    /// time, into `result`.
    void AddCovariance(CorrectionResult& result) const;
    /// Window statistics so far (windows, restarts, iterations, ...).
    const CorrectionResult& stats() const { return stats_; }

private:
    TrajectoryState state_;
    const TraversableField* field_;
    CorrectorConfig cfg_;
    std::vector<double> dist_;
    double elapsed_s_ = 0.0;  ///< time of the appended steps (heading-rate bias segments)
    std::size_t done_ = 0;
    /// First pose of the trailing window that ends at `end`.
    std::size_t WindowFirst(std::size_t end) const;
    CorrectionResult stats_;
};

/// The state of a trajectory that grows one pose at a time (the incremental and fixed-lag
/// solvers): the known pose 0, its segments, the heading-rate bias segments when the model has
/// them (model.heading_bias_segment_s > 0).
TrajectoryState StartState(const PoseState& pose0, bool fix_height, const ModelConfig& model);
/// Appends pose i = s.poses.size() with `step` (the step from pose i-1) and its scale and bias
/// segments, by the rules of ScaleSegments and BiasSegments: `path_before_m` and
/// `elapsed_before_s` are the path length and the time from pose 0 to pose i-1.
void AppendStep(TrajectoryState& s, const PoseState& initial, const StepObservation& step,
                double path_before_m, double elapsed_before_s, const ModelConfig& model);

/// Dead reckoning of one step: pose `a` moved by observation `step` with step-length `scale`,
/// its heading change plus `bias_rad_s` * dt (the heading-rate bias; 0 where there is none).
/// The height follows dup_m unless `fix_height`, when it stays `up_fixed_m`.
PoseState ComposeStep(const PoseState& a, const StepObservation& step, double scale,
                      bool fix_height, double up_fixed_m, double bias_rad_s);

/// Dead-reckons poses [from, to] by composing the odometry onto the (corrected) pose from-1 with
/// each step's segment scale, the height changes times `height_gain` (those of the steps whose
/// reading is settled, TrajectoryState::height_settled, as they are). Precondition:
/// 1 <= from, to < s.poses.size().
void ComposeOdometry(TrajectoryState& s, std::size_t from, std::size_t to,
                     double height_gain = 1.0);
/// Scale (and heading-rate bias) segments first entered by steps [from, to] start from the
/// latest estimate.
void SeedNewScales(TrajectoryState& s, std::size_t from, std::size_t to);

/// One trailing-window solve with the soft terms (window_newton, window_ipopt), written into
/// `s`: poses [first, last] (and first-1 with a boundary prior) and the window's scales. With
/// `restarts`, a solution that leaves many poses off the roads or explains the window poorly (a
/// wrong basin) is re-solved from the restart_scale_factors hypotheses, and a window that changes
/// floor (its height changes add up to restart_height_change_m) from the restart_height_gains
/// hypotheses (another floor's basin); the lowest NLL wins. Counts its
/// iterations and restarts into `stats`. Time and memory bounded by the window, not by the
/// trajectory. Precondition: 1 <= first <= last < s.poses.size().
SolveReport SolveSoftWindow(TrajectoryState& s, const TraversableField* field,
                            const CorrectorConfig& cfg, std::size_t first, std::size_t last,
                            const std::optional<PosePriorTerm>& prior, bool restarts,
                            CorrectionResult& stats);

/// The restart test of SolveSoftWindow: whether the solved window [first, last] (`report` its
/// outcome) looks like a wrong basin: no usable solution, an NLL per pose above
/// restart_nll_per_pose, or more than restart_offroad_share of its poses farther than
/// restart_offroad_m from every traversable centre.
bool PoorWindow(const TrajectoryState& s, const TraversableField& field, const CorrectorConfig& cfg,
                std::size_t first, std::size_t last, const SolveReport& report);

/// The state of a whole drive for the batch correction: its observations with the dropped-step
/// episodes repaired (core RepairSpeedEpisodes, model.outlier_accel_mps2), scale and heading-rate
/// bias segments, the given poses (pose 0: the start), every scale at 1.
TrajectoryState BatchState(std::vector<StepObservation> obs, std::vector<PoseState> poses,
                           const CorrectorConfig& config, bool fix_height);
/// The dropped-step repair of BatchState over the steps of the last 2 * the longest episode
/// (20 s) up to pose `end`, for solvers that see the trajectory grow: an episode is repaired once
/// the speed after it has been seen. Steps repaired once stay repaired. Time bounded by the span,
/// not by the trajectory. Returns the number of episodes repaired in the span.
std::size_t RepairRecentEpisodes(TrajectoryState& s, std::size_t end, const ModelConfig& model);
/// The initial state of a whole estimate (BatchState of its observations, poses at the estimate).
TrajectoryState InitialState(const PlanarTrajectory& estimate, const CorrectorConfig& config,
                             bool fix_height);

}  // namespace driftcorr
