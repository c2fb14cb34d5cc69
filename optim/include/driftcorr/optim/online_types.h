#pragma once
// What the online corrector (optim/online_corrector.h) takes and returns: its configuration (the
// params.yaml section `online`), a pose in the world plane, the result of a Push with the
// output's age and covariance, and how the corrector kept up.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/optim/corrector_config.h"
#include "driftcorr/optim/covariance.h"

namespace driftcorr {

struct OnlineConfig {
    CorrectorConfig corrector;  ///< chunk_m, window_m, model, ... exactly as in batch mode
    bool synchronous = false;   ///< solve inside Push (no worker thread)
    double gap_warn_s = 1.0;    ///< Push flags a step longer than this in time [s]
    /// The returned causal pose is moved into the traversable corridor when it lies outside it but
    /// within corridor.model.corridor_gate_m (what the refinement's hard constraint does to the
    /// smoothed poses), horizontally along the corridor distance gradient, in at most 3 Newton
    /// steps, each taken only where the horizontal slope is >= 0.5 and kept only when it lowers
    /// the distance. Only the output is moved; the solver state is not.
    bool project_output = true;
    /// Path between solves for the causal output, as a share of corrector.chunk_m (0.125: every
    /// 10 m with the road chunks of 80 m); 0: only at the chunk rule.
    double update_fraction = 0.125;
    /// Back-pressure (threaded mode): before taking a pose, Push waits while the previous pose
    /// is more than this many epochs past the last solved pose and a solve is requested or
    /// running; 0: never waits (under a burst the outputs then chain from older solves, and say
    /// so in their age).
    std::size_t max_lag_epochs = 1;
    /// false: back-pressure only while the input arrives faster than real time (kAheadFactor), so
    /// a live producer is never held back; true: whenever the lag exceeds max_lag_epochs.
    bool hold_live_input = false;
    /// The online windows' boundary pose: true, a variable under the marginalised prior of the
    /// poses before it (optim/fixed_lag.h; docs/method.md, Eq. 19); false, held fixed at its last
    /// solution. Measured both ways: docs/results.md, "The online windows' boundary prior".
    bool boundary_prior = true;
    /// With boundary_prior: the prior is joint with the scale of the boundary pose's segment,
    /// which the window then re-estimates (optim/fixed_lag.h); false: the prior is on the pose
    /// alone, given the scales, and the earlier segments' scales stay fixed. Measured both ways:
    /// docs/results.md, "Online correction that keeps up".
    bool boundary_scale = true;
    /// With one start scale (the road defaults): the first window is solved where the batch
    /// solves its first, when the first chunk (corrector.chunk_m of path) is complete; the
    /// outputs before it are the odometry from the known start. A window of a few metres cannot
    /// tell the step-length scale from the map's offset, and its outputs would carry the scale
    /// it guessed (measured: docs/results.md, "Online recovery"). false: from the first
    /// update_fraction of a chunk. With several start scales the chain nearest the prior's mean
    /// solves from the first pose and the others first at the chunk rule, either way.
    bool first_solve_at_chunk = true;
    /// Re-localisation (docs/method.md, "The online corrector"): after a window solve that is
    /// in doubt (kDoubtPoorWindow, kDoubtScale; kDoubtMoved with relocalise_when_moved), the whole
    /// prefix is solved as the batch solves a drive (CorrectFromStarts from the chain's start
    /// scale), on the worker; when the chain's own poses score an NLL more than
    /// relocalise_nll_ratio times that correction's, the chain lost the map and continues from the
    /// correction (kDoubtRelocalised on the first output that does). At most one such solve per
    /// max(relocalise_min_m, relocalise_share x the path so far) of path, so that all of them cost
    /// a few whole corrections. relocalise_min_m = 0: never.
    double relocalise_min_m = 200.0;     ///< [m]
    double relocalise_share = 0.25;      ///< [-]
    double relocalise_nll_ratio = 10.0;  ///< [-]
    /// A solve that moves the chain's newest pose outside that pose's 95 % region (kDoubtMoved)
    /// puts the chain in doubt for the re-localisation too.
    bool relocalise_when_moved = true;
    /// The outputs' covariance scaled by how well it held the stream's own later estimates.
    /// Once no window moves a pose any more, its final estimate differs from the output by d;
    /// if the model's covariance Sigma of the output held the output's error, d^T Sigma^-1 d
    /// would lie below chi2_2(0.95) = 5.991 for at least 95 % of the outputs (d misses the
    /// errors the final estimates share, so never more). Once 20 outputs have settled (the
    /// fewest that leave one beyond a 95 % quantile), every output's covariance is multiplied
    /// by max(1, the 95 % quantile of their d^T Sigma^-1 d over the stream so far / 5.991); an
    /// output in doubt for the odometry (kDoubtOdometry) by the larger of that and the same
    /// factor over the settled outputs that were in that doubt.
    /// The positions and the doubt bits (kDoubtMoved tests the model's region) are unchanged.
    bool calibrate_covariance = true;

    /// The first value kOnlineParams does not allow (corrector is not looked at).
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "<section>.<key>: <rule> (got <value>)" for the first bad field of
    /// corrector or of this struct (section online).
    std::string Validate() const;
};

/// Params.yaml section `online` (synchronous and corrector are set by the caller).
inline constexpr Param<OnlineConfig> kOnlineParamRows[] = {
    {"update_fraction", Field<&OnlineConfig::update_fraction>(), kShare,
     "a window solve for the causal output every this share of chunk_m; 0: at the chunk rule"},
    {"gap_warn_s", Field<&OnlineConfig::gap_warn_s>(), kPositive,
     "a longer input pause or timestamp gap is reported"},
    {"project_output", Field<&OnlineConfig::project_output>(), kNoRange,
     "the causal pose is moved into the corridor when within corridor_gate_m"},
    {"max_lag_epochs", Field<&OnlineConfig::max_lag_epochs>(), kNonNegative,
     "back-pressure: Push waits while this many epochs past the last solve; 0: never waits"},
    {"hold_live_input", Field<&OnlineConfig::hold_live_input>(), kNoRange,
     "back-pressure also on input that arrives at real time; false: only on faster input"},
    {"boundary_prior", Field<&OnlineConfig::boundary_prior>(), kNoRange,
     "online windows: the past marginalised onto the boundary pose"},
    {"boundary_scale", Field<&OnlineConfig::boundary_scale>(), kNoRange,
     "online windows: the boundary prior joint with its segment's scale, which the window "
     "re-estimates"},
    {"first_solve_at_chunk", Field<&OnlineConfig::first_solve_at_chunk>(), kNoRange,
     "one start scale: the first window solved when the first chunk is complete; false: after "
     "update_fraction of it"},
    {"relocalise_min_m", Field<&OnlineConfig::relocalise_min_m>(), kNonNegative,
     "a chain in doubt has the whole prefix re-solved, at most once per this much path; 0: "
     "never"},
    {"relocalise_share", Field<&OnlineConfig::relocalise_share>(), kNonNegative,
     "...and this share of the path so far apart"},
    {"relocalise_nll_ratio", Field<&OnlineConfig::relocalise_nll_ratio>(), kPositive,
     "the chain continues from the prefix's correction when its own NLL is this many times "
     "higher"},
    {"relocalise_when_moved", Field<&OnlineConfig::relocalise_when_moved>(), kNoRange,
     "a solve that moves the chain outside its 95 % region puts it in doubt for the "
     "re-localisation as well"},
    {"calibrate_covariance", Field<&OnlineConfig::calibrate_covariance>(), kNoRange,
     "the outputs' covariance scaled by the 95 % quantile of their normalised squared distance "
     "to the final estimates, over chi2_2(0.95), where above 1"},
};
inline constexpr ParamTable<OnlineConfig> kOnlineParams{"online", kOnlineParamRows};

/// One pose in the world plane (ENU at the anchor).
struct PlanarPose {
    double t_s = 0.0;
    Eigen::Vector2d p_en = Eigen::Vector2d::Zero();  ///< [m]
    double up_m = 0.0;                               ///< [m]
    std::optional<double> yaw_rad;  ///< heading, CCW from East [rad]; nullopt: from the steps
};

enum class PushStatus {
    kAccepted,
    kRejectedTime,       ///< timestamp not after the previous accepted one (out of order/repeated)
    kRejectedNonFinite,  ///< NaN or inf in any field
    kRejectedHeading,    ///< with a heading when the stream started without one, or vice versa
    kRejectedFinished,   ///< Push after Finish()
};

/// Why an output is in doubt: the bits of PushResult::doubt.
enum OnlineDoubt : unsigned {
    kDoubtOffMap = 1,      ///< the output lies outside the map field (odometry only)
    kDoubtPoorWindow = 2,  ///< the solve it chains from fails the windows' restart test (a wrong
                           ///< basin: poses off the roads, a high NLL per pose) after its restarts
    kDoubtScale = 4,       ///< the step-length scale it moves by lies outside the plausible range
                           ///< (model.scale_range_min..scale_range_max)
    kDoubtHypotheses = 8,  ///< with start scales: a hypothesis whose NLL is within 3 of the chosen
                           ///< one's (a likelihood ratio above 1/20) puts the pose outside the
                           ///< chosen output's 95 % region (the covariance holds the mixture)
    kDoubtOdometry = 16,   ///< the input's speed over 0.3 s changed faster than
                           ///< model.outlier_accel_mps2 within the last 10 s (dropped or doubled
                           ///< odometry steps, the longest episode the repair takes), or since
                           ///< then no solve has seen the estimate turn by 30 degrees
    kDoubtScaleSearch = 32,  ///< `scale: auto`: the estimate's global scale is still searched;
                             ///< the output is the input at the scale that fits the map best so
                             ///< far, not a correction (pipeline::StreamSession)
    kDoubtRelocalised = 64,  ///< the first output after the chain was re-localised: it continues
                             ///< from the prefix solved as a whole (the output may jump)
    kDoubtMoved = 128,  ///< the newest solve moved the previous output outside that output's own
                        ///< 95 % region: successive solves disagree (the covariance holds both)
};

struct PushResult {
    PushStatus status = PushStatus::kAccepted;
    std::string message;       ///< why rejected, or a warning (gap, outside map); empty otherwise
    std::size_t index = 0;     ///< index of the accepted pose in the stream
    PlanarPose corrected;      ///< causal estimate (valid when accepted); yaw_rad always set
    bool gap = false;          ///< the step took longer than gap_warn_s
    bool outside_map = false;  ///< the corrected pose lies outside the map field (odometry only)
    /// OnlineDoubt bits: why this output may be wrong, as it happens (0: none).
    unsigned doubt = 0;
    /// The solve the output chains from ended this many epochs (poses) before this one...
    std::size_t correction_age_epochs = 0;
    double correction_age_s = 0.0;  ///< ...and this much earlier in stream time [s]
    /// The output chains from the newest solve the schedule had requested before this pose
    /// (false: the solver was behind; the pose was composed onto an older solve).
    bool fresh = true;
    /// Time Push waited for the solver before taking the pose (back-pressure) [s]; with start
    /// scales, over every hypothesis
    double waited_s = 0.0;
    /// The start scale of the hypothesis this output comes from (docs/method.md, "Start scales").
    double start_scale = 1.0;
    /// The input arrived faster than real time when this pose was pushed (kAheadFactor).
    bool ahead_of_real_time = false;
    /// Covariance of the output pose: the solved pose's it chains from (FixedLagSolution::
    /// end_covariance, the batch's covariance model) carried through the odometry of the
    /// correction_age_epochs steps since (PropagateStep); before the first solve, the known
    /// start's (zero) so carried. Valid when covariance_ok (false after a solve whose matrices
    /// could not be factored, until the next).
    PoseCovariance covariance;
    bool covariance_ok = false;
    bool Accepted() const { return status == PushStatus::kAccepted; }
};

/// How the online corrector kept up (OnlineCorrector::Statistics).
struct OnlineStatistics {
    std::size_t poses = 0;            ///< accepted
    std::size_t stale_poses = 0;      ///< returned without the newest requested solve (!fresh)
    std::size_t max_age_epochs = 0;   ///< worst correction_age_epochs
    double max_age_s = 0.0;           ///< worst correction_age_s [s]
    std::size_t requests = 0;         ///< solves the schedule asked for
    std::size_t solves = 0;           ///< solves run (requests - solves were skipped)
    std::size_t failed_solves = 0;    ///< Ipopt gave no usable solution (state kept)
    std::size_t prior_solves = 0;     ///< solves whose boundary carried a marginalised prior
    std::vector<double> solve_s;      ///< wall time of every solve [s]
    std::size_t waits = 0;            ///< Pushes that waited (back-pressure)
    double wait_s = 0.0;              ///< total wait [s]
    std::size_t ahead_poses = 0;      ///< poses that arrived faster than real time
    std::size_t relocalisations = 0;  ///< prefixes solved as a whole (relocalise_min_m)
    std::size_t relocalised = 0;      ///< ...of which the chain continued from
    double relocalise_s = 0.0;        ///< their wall time, all together [s]
    std::string worker_error;         ///< a solve that threw (the worker then stopped)
};

}  // namespace driftcorr
