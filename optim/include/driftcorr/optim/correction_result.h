#pragma once
// What a correction of a whole trajectory returns, whichever solver made it (the batch corrector,
// optim/corrector.h; the paper's baseline, optim/paper_solver.h), and how it reports progress.
#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/observables.h"
#include "driftcorr/core/types.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/solve_status.h"

namespace driftcorr {

struct CorrectionProgress {
    /// "incremental", "refining" (the final solve runs: after each of its iterations),
    /// "refine" (it has ended) or "paper"
    std::string stage;
    std::size_t poses_done = 0;
    std::size_t poses_total = 0;
    int iteration = 0;  ///< "refining": the final solve's iterations so far
};
using ProgressCallback = std::function<void(const CorrectionProgress&)>;

/// Whether the heading-rate bias was kept (CorrectorConfig::decide_heading_bias): the NLL of the
/// correction with and without it and the price of its unknowns, k / 2 ln n.
struct HeadingBiasDecision {
    double nll_with = 0.0, nll_without = 0.0, price = 0.0;
    bool kept = true;
};

/// Whether the step-length scale walk was kept (CorrectorConfig::decide_scale_walk): the NLL and
/// the price, (k - 1) / 2 ln n for k scale segments over n poses plus the heading-rate bias's when
/// kept, of the correction with one scale for the whole drive, of its final solve repeated with
/// the walk's segments, and of the whole correction with the walk (NaN: not run or not usable).
struct ScaleWalkDecision {
    double nll_one_scale = 0.0, price_one_scale = 0.0;
    double nll_refined = 0.0, price_refined = 0.0;
    double nll_walk = 0.0, price_walk = 0.0;
    enum class Kept { kOneScale, kRefined, kWalk } kept = Kept::kOneScale;
};

/// The second start of a road correction (CorrectorConfig::one_scale_start): the NLL of the
/// correction with the scale walk, of its solution solved again with one scale for the whole
/// drive (a solution of the same model), and of that one refined with the walk, run only when
/// one scale's NLL is the lower (NaN: not run or not usable).
struct OneScaleStart {
    double nll_walk = 0.0, nll_one_scale = 0.0, nll_refined = 0.0;
    bool from_one_scale = false;  ///< the refined one-scale solution was kept
};

/// Whether the PDR's step lengths were read about their median or as they are
/// (CorrectorConfig::decide_step_reading): the NLL of the correction with each reading, each
/// with its step-length terms' normalisation (sum of ln sigma), which the two readings do not
/// share (NaN: not usable), and the price the reading as read pays, 1/2 ln n (n poses).
struct StepReadingDecision {
    double exponent = 1.0;  ///< ModelConfig::step_length_exponent of the reading about the median
    double nll_about_median = 0.0, nll_as_read = 0.0, price = 0.0;
    bool as_read = false;  ///< the correction with the step lengths as read was kept
};

struct CorrectionResult {
    SolveStatus status = SolveStatus::kFailed;
    std::string message;         ///< human-readable outcome, names the failing stage
    PlanarTrajectory corrected;  ///< valid only when Usable(status)
    /// windows, window_retries, window_restarts, iterations, incremental_s and refine_s add up
    /// over every start scale of the batch correction (start_scales); the rest is the kept one's.
    std::size_t windows = 0;
    std::size_t window_retries = 0;           ///< windows re-solved without hard constraints
    std::size_t window_failures = 0;          ///< windows that failed even then
    std::size_t window_restarts = 0;          ///< extra window solves from other scale hypotheses
    int iterations = 0;                       ///< solver iterations, all solves
    std::size_t constrained_poses = 0;        ///< poses with the hard corridor constraint (refine)
    double scale_min = 1.0, scale_max = 1.0;  ///< estimated step-length scale range
    /// Where the solve held the heights: the stretches of the corrected path the grade bound
    /// looked at, and those whose height change it limited (ModelConfig::max_grade).
    GradeBound grades;
    /// The corrected trajectory's NLL (the objective of the soft terms at the output).
    double nll = 0.0;
    /// The starts of the batch correction (CorrectorConfig::start_scales), the NLL each one's
    /// correction reached (NaN: not usable), the horizontal RMS distance of each one's correction
    /// to the kept one [m] (NaN: not usable; 0 for the kept one) and the one that was kept.
    std::vector<double> start_scales, start_nll, start_rms_m;
    std::size_t start_chosen = 0;
    /// The floor hypotheses of the batch correction (CorrectorConfig::floor_hypothesis_margin):
    /// each whole correction re-run on another floor after a floor change of the estimate.
    struct FloorHypothesis {
        double t_s = 0.0;       ///< the change ends (time from the first pose) [s]
        double from_m = 0.0;    ///< the floor before the change [m]
        double chosen_m = 0.0;  ///< the floor after it in the correction it was tried against
        double tried_m = 0.0;   ///< the floor tried [m]
        double nll = 0.0;       ///< that correction's NLL (NaN: not usable)
        double against = 0.0;   ///< the NLL it was compared with
        /// The NLL of each one's floor changes' gains (CorrectorConfig::floor_gain_sigma; 0: off),
        /// added to its NLL in the comparison.
        double gain_nll = 0.0, against_gain_nll = 0.0;
        bool kept = false;
    };
    std::vector<FloorHypothesis> floor_hypotheses;
    /// The odometry's step lengths as the model observed them [m], one per pose (step into pose
    /// i; [0] = 0): the estimate's, except the dropped steps RepairSpeedEpisodes replaced.
    std::vector<double> step_length_m;
    std::size_t repaired_steps = 0;  ///< steps whose length was replaced
    /// 1 where the model observed the step as a stair tread (MarkStairTreads: its run is its own,
    /// not the odometry's scaled), one per pose; empty when the solver does not say.
    std::vector<std::uint8_t> tread_steps;
    /// The odometry's height changes as the model observed them [m], one per pose (step into
    /// pose i; [0] = 0): the estimate's, except a lift ride's lagged reading moved into the ride
    /// (MoveRideLag, 3D). Empty when the solver does not say (the paper's).
    std::vector<double> height_change_m;
    SolveReport refine_report;
    double incremental_s = 0.0;  ///< wall time of the incremental pass [s]
    double refine_s = 0.0;       ///< wall time of the refinement [s]
    /// Marginal covariance of every corrected pose; status kNotComputed unless
    /// config.compute_covariance and the correction is usable.
    CovarianceResult covariance;
    double covariance_s = 0.0;  ///< wall time of the covariance [s]
    /// How the input lies in the correction's uncertainty (CorrectorConfig::keep_agreeing_input,
    /// corrector.h): of the poses with a covariance, how many have the input inside the
    /// correction's 95 % region (horizontally, and within the 95 % interval of the height where
    /// the covariance has one). 0 of 0 when it was not computed.
    std::size_t agreement_poses = 0, agreement_inside = 0;
    /// The least share inside that keeps the input: 95 % less the one-sided 5 % margin of a
    /// binomial share over the path's number of independent stretches (corrector.cpp).
    double agreement_threshold = 0.0;
    /// The input itself was kept: `corrected` is the estimate as handed in, since the share of
    /// its poses inside the correction's 95 % region is not significantly below 95 % (the map
    /// cannot tell it wrong), or since its NLL is lower than the correction's (input_nll_lower).
    bool input_kept = false;
    /// The input's NLL under the model (at scale 1, no heading-rate bias): what `nll` would be
    /// had the correction left the input as it was. NaN when not computed.
    double input_nll = std::numeric_limits<double>::quiet_NaN();
    /// input_nll < nll: the correction explains the odometry and the map worse than the input
    /// does, by the model's own measure (the solve ended in a poorer basin than its start).
    bool input_nll_lower = false;
    /// Set when the heading-rate bias was decided on (corrector.cpp DecideHeadingBias).
    std::optional<HeadingBiasDecision> heading_bias;
    /// Set when the scale walk was decided on (corrector.cpp CorrectWithDecidedScaleWalk).
    std::optional<ScaleWalkDecision> scale_walk;
    std::optional<OneScaleStart> one_scale_start;
    /// Set when the step-length reading was decided on (corrector.cpp
    /// CorrectWithDecidedStepReading).
    std::optional<StepReadingDecision> step_reading;
    /// Degenerate input or outcome worth a user's attention, one sentence each (the map covers
    /// none or little of the drive, the estimate does not move, the scale hit its bound, steps
    /// treated as discontinuities). The correction may still be usable.
    std::vector<std::string> warnings;
};

}  // namespace driftcorr
