#pragma once
// The verdict on a correction, from signals that need no ground truth: can the result be vouched
// for? A user has no ground truth, so every run ends with
//   ok        nothing speaks against the result;
//   degraded  the result is written, but parts of it are not supported (the reasons say which);
//   failed    the result cannot be vouched for (the caller writes nothing by default).
// and per pose a set of flags where the correction is not supported.
//
// The signals (each a small named predicate that writes its reason):
//  - the solver's outcome: no usable solution, or a final solve that could not keep the corridor
//    constraints and was re-solved without them (the map and the odometry could not be reconciled);
//  - the step-length scale: the correction explains the drive with a scale no odometry of this
//    kind has (visual / lidar odometry is a few percent off, not 25 %; pedestrian step models tens
//    of percent): outside the plausible range the drive was squeezed or stretched onto the map.
//    The plausible range is the model's own (ModelConfig::scale_range_min/max) when it has a
//    range prior, else VerdictConfig::scale_plausible_min/max.
//    Measured against the odometry as the model observed it (CorrectionResult::step_length_m:
//    dropped-step episodes repaired), so a repaired episode is not counted as a stretch, and
//    without the stair treads, whose run the scale does not scale (tread_steps);
//  - the start: the given anchor puts the leading path far from the map while another heading or
//    position fits it well (AnchorFitResult), or an estimated start that another start fits as
//    well;
//  - input jumps: the estimate's speed changes faster than any platform can accelerate (frame-to-
//    frame odometry dropping or doubling motion), which a smooth scale cannot follow;
//  - off the map: corrected poses farther from every traversable place than the map term reaches;
//  - roads: turns the estimate does not make: a stretch whose heading changes differ from the
//    estimate's far more than the rest of the drive's and than the model's heading noise (the
//    correction followed another road there, or left a start off the map);
//  - 3D: corrected height changes the estimate's deny, level walking between floors, and a floor
//    that another floor explains as well (neither the barometer nor the map tells them apart).
// No I/O.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/params.h"
#include "driftcorr/core/types.h"
#include "driftcorr/mapping/traversable_field.h"
#include "driftcorr/optim/anchor_fit.h"
#include "driftcorr/optim/corrector.h"

namespace driftcorr {

enum class VerdictLevel { kOk, kDegraded, kFailed };
std::string ToString(VerdictLevel level);

/// Per-pose flags (bits).
enum PoseFlag : std::uint8_t {
    kPoseOffMap = 1,            ///< farther from every traversable place than the map term reaches
    kPoseInputJump = 2,         ///< in a stretch where the estimate's speed changes abruptly
    kPoseScaleImplausible = 4,  ///< in a scale segment outside the plausible range
    /// a corrected height the estimate denies (a floor change it did not make, level walking
    /// between floors)
    kPoseHeightDisagrees = 8,
    /// on a floor that another floor explains as well (the barometer's floor changes read both,
    /// and the path, shifted by up to the map's reach, lies on both floors' map)
    kPoseFloorAmbiguous = 16,
    /// in a stretch where the correction turns where the estimate does not (its heading changes
    /// differ from the estimate's far more than over the rest of the drive)
    kPoseTurnUnsupported = 32,
};

struct VerdictConfig {
    /// Plausible step-length scale: outside it the result is degraded (a model with a scale
    /// range prior, scale_range_sigma > 0, brings its own range instead)...
    double scale_plausible_min = 0.8;   ///< [-]
    double scale_plausible_max = 1.25;  ///< [-]
    /// ...and outside this wider range it is failed.
    double scale_failed_min = 0.6;  ///< [-]
    double scale_failed_max = 1.6;  ///< [-]
    /// Input jumps: the estimate's mean speed over jump_window_s changes against the window
    /// before it faster than max_accel_mps2. About 1 g: no road vehicle brakes harder and no
    /// walker stops faster, while frame-to-frame odometry that drops motion does so in one frame.
    double jump_window_s = 0.3;    ///< [s]
    double max_accel_mps2 = 10.0;  ///< [m/s^2]
    /// 3D modes: over every height_window_s of the walk, the corrected height change may exceed
    /// the estimate's (barometric) one by height_disagree_m + height_disagree_rel times the
    /// estimate's, and fall short of it by height_disagree_m + height_short_rel times it; beyond,
    /// the correction climbed or descended where the estimate did not (or the other way round):
    /// a floor change the walk does not support, likely a wrong floor. A barometer reads a floor
    /// change 0.75-1.12x (the two real HCU walks: 0.78-0.81x on stairs, 1.09-1.12x in the lift)
    /// and drifts by centimetres a minute: a right correction changes height by 0.89-1.33x the
    /// reading. Degraded, failed beyond off_map_failed_share of the poses.
    double height_window_s = 60.0;      ///< [s]
    double height_disagree_m = 1.5;     ///< [m]
    double height_disagree_rel = 0.35;  ///< [-]
    double height_short_rel = 0.2;      ///< [-]
    /// Walkers walk level only on floors (stairs change height). With the floors' heights known
    /// (the field's floor_heights_m: a map of discrete floors, in the trajectory's height datum;
    /// empty: not known, no check), corrected poses farther than off_floor_m from every floor while
    /// the estimate's height stays within level_height_m over level_window_s around them walk
    /// level between floors (a stair hall or shaft at a height no floor has): degraded when such
    /// poses span level_window_s / 2 in a row, failed beyond off_map_failed_share of the poses.
    /// The same floors: a stay of level_window_s / 2 or more on a floor after a floor change is
    /// not determined (degraded, kPoseFloorAmbiguous) when the estimate's height changes into
    /// and out of it agree with another floor as well (the tolerances above) and the stay's path,
    /// shifted by up to the map term's reach, has at most off_map_degraded_share of its poses
    /// beyond that floor's reach.
    double off_floor_m = 1.0;      ///< [m]
    double level_window_s = 20.0;  ///< [s]
    double level_height_m = 1.0;   ///< [m] (a barometer reads a level walk 0.6-0.7 m peak to peak)
    /// Off the map: share of corrected poses beyond the map's reach for degraded / failed.
    double off_map_degraded_share = 0.1;  ///< [-]
    double off_map_failed_share = 0.3;    ///< [-]
    /// The start does not fit: another placement of the leading path at least this far from the
    /// given one (heading or position)...
    double anchor_other_yaw_deg = 5.0;      ///< [deg]
    double anchor_other_position_m = 10.0;  ///< [m] (a GNSS start fix is good to a few metres)
    /// ...brings its RMS distance to the map below this share of the given placement's.
    double anchor_rms_ratio = 0.5;  ///< [-]
    /// An estimated start is ambiguous when the next distinct start's RMS is within this factor
    /// of the best one's.
    double anchor_ambiguous_ratio = 1.5;  ///< [-]
    /// The size of a road drive (planar field; the solver estimates a scale): the corrected drive
    /// is scaled about its start by up to the model's scale_prior_sigma either way and scored
    /// against the map (FitSizes). Another size, distinct for the map (its farthest pose moved by
    /// more than twice the map term's reach), that fits within size_rms_margin_m of the corrected
    /// size's RMS, while the correction changed the drive's size (its path over the input's) by
    /// more than the map tells apart, is failed: the map does not determine the drive's size (a
    /// single turn after a long straight, onto one of a grid's streets; a straight the correction
    /// stretched), and the correction chose one.
    double size_rms_margin_m = 0.5;  ///< [m]
    /// Turns the estimate does not make: per turn_window_m of corrected path, the mean square of
    /// the difference between the corrected and the estimated heading change per step (headings
    /// of the steps' directions, steps longer than turn_min_step_m in both and not spanning a gap
    /// in the input's times, over 3 times its median step time), against the median
    /// over the drive's windows (at least three). A window beyond turn_ratio times that median,
    /// and beyond the model's own heading noise over its steps (heading_rw_rad_per_sqrt_s over
    /// each step's time, heading_sigma_rel of the estimate's turn), is a stretch the correction
    /// bent onto a road the odometry did not drive (another road, a start off the map):
    /// degraded, its poses flagged kPoseTurnUnsupported.
    double turn_window_m = 200.0;  ///< [m]
    double turn_min_step_m = 0.3;  ///< [m]
    double turn_ratio = 100.0;     ///< [-]

    /// The first value kVerdictParams or a rule between its values does not allow.
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "verdict.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// The verdict's thresholds (not a params.yaml section).
inline constexpr Param<VerdictConfig> kVerdictParamRows[] = {
    {"scale_plausible_min", Field<&VerdictConfig::scale_plausible_min>(),
     ParamRange{0.0, 1.0, true, false}, "a scale below is degraded"},
    {"scale_plausible_max", Field<&VerdictConfig::scale_plausible_max>(), AtLeast(1.0),
     "a scale above is degraded"},
    {"scale_failed_min", Field<&VerdictConfig::scale_failed_min>(), kPositive,
     "a scale below is failed; <= scale_plausible_min"},
    {"scale_failed_max", Field<&VerdictConfig::scale_failed_max>(), kPositive,
     "a scale above is failed; >= scale_plausible_max"},
    {"jump_window_s", Field<&VerdictConfig::jump_window_s>(), kPositive,
     "input jumps: mean speed over this window"},
    {"max_accel_mps2", Field<&VerdictConfig::max_accel_mps2>(), kPositive,
     "input jumps: the mean speed changes faster than this"},
    {"height_window_s", Field<&VerdictConfig::height_window_s>(), kPositive,
     "3D: corrected and estimated height changes compared over this window"},
    {"height_disagree_m", Field<&VerdictConfig::height_disagree_m>(), kNonNegative,
     "3D: they may differ by this..."},
    {"height_disagree_rel", Field<&VerdictConfig::height_disagree_rel>(), kNonNegative,
     "...plus this share of the estimate's height change where the correction's is larger"},
    {"height_short_rel", Field<&VerdictConfig::height_short_rel>(), kNonNegative,
     "...or this share where the correction's is smaller"},
    {"off_floor_m", Field<&VerdictConfig::off_floor_m>(), kPositive,
     "3D, floors known: a pose this far from every floor..."},
    {"level_window_s", Field<&VerdictConfig::level_window_s>(), kPositive,
     "...while the estimate stays level over this window..."},
    {"level_height_m", Field<&VerdictConfig::level_height_m>(), kPositive,
     "...within this height walks level between floors"},
    {"off_map_degraded_share", Field<&VerdictConfig::off_map_degraded_share>(), kShare,
     "share of off-map poses that is degraded; <= off_map_failed_share"},
    {"off_map_failed_share", Field<&VerdictConfig::off_map_failed_share>(), kShare,
     "share of off-map poses that is failed"},
    {"anchor_other_yaw_deg", Field<&VerdictConfig::anchor_other_yaw_deg>(), kPositive,
     "another start at least this far in heading..."},
    {"anchor_other_position_m", Field<&VerdictConfig::anchor_other_position_m>(), kPositive,
     "...or position..."},
    {"anchor_rms_ratio", Field<&VerdictConfig::anchor_rms_ratio>(),
     ParamRange{0.0, 1.0, true, true},
     "...that fits the map with less than this share of the RMS: the start does not fit"},
    {"anchor_ambiguous_ratio", Field<&VerdictConfig::anchor_ambiguous_ratio>(), AtLeast(1.0),
     "an estimated start is ambiguous when the next one's RMS is within this factor"},
    {"size_rms_margin_m", Field<&VerdictConfig::size_rms_margin_m>(), kNonNegative,
     "roads: another size of the drive that fits the map within this RMS makes its size "
     "undetermined"},
    {"turn_window_m", Field<&VerdictConfig::turn_window_m>(), kPositive,
     "turns the estimate does not make: window of corrected path"},
    {"turn_min_step_m", Field<&VerdictConfig::turn_min_step_m>(), kNonNegative,
     "...over the steps longer than this in the correction and the estimate"},
    {"turn_ratio", Field<&VerdictConfig::turn_ratio>(), AtLeast(1.0),
     "...a window whose heading changes differ from the estimate's more than this times the "
     "drive's median window and more than the model's heading noise is degraded"},
};
inline constexpr ParamTable<VerdictConfig> kVerdictParams{"verdict", kVerdictParamRows};

struct Verdict {
    VerdictLevel level = VerdictLevel::kOk;
    /// One sentence per finding, each starting with its level ("failed: ...", "degraded: ...").
    std::vector<std::string> reasons;
    std::vector<std::uint8_t> pose_flags;  ///< one per pose, PoseFlag bits
    /// The signals, for reports: scale range, jumps, share of poses off the map.
    double scale_min = 1.0, scale_max = 1.0;
    std::size_t input_jumps = 0;
    double off_map_share = 0.0;
};

/// Judges `result` of correcting `estimate` (world plane) against `field` (may be null) with
/// `model`. `anchor_fit`: how the start fits the map, with `start_estimated` when the start was
/// estimated from the map rather than given. `scale_estimated`: the solver estimates a step
/// scale (driftcorr's corrector; the paper's method does not).
Verdict JudgeCorrection(const PlanarTrajectory& estimate, const TraversableField* field,
                        const ModelConfig& model, const CorrectionResult& result,
                        const AnchorFitResult* anchor_fit, bool start_estimated,
                        bool scale_estimated, const VerdictConfig& config);

/// Two solutions of the same poses, the causal (online) outputs and the smoothed trajectory,
/// against each other. Both are corrections of the input, so they should agree far better than
/// either agrees with the input. When they lie farther apart (RMS over the poses) than the input
/// lies from the smoothed trajectory, one of them followed a wrong branch of the map (measured
/// both ways: a causal chain stuck on a wrong road while the smoothed solve recovered, and a
/// smoothed solve in a wrong corridor while the causal chain stayed right), and with no ground
/// truth neither can be vouched for.
/// In height (3D fields, where the heights are corrected): causal outputs more than
/// height_disagree_m above or below the smoothed trajectory for level_window_s or longer in a row
/// stand a floor apart from it (a causal chain that rode a lift to another floor than the smoothed
/// solve and stayed there), where an online output only lags a floor change by a few seconds. Those
/// runs' share of the poses (floor_apart_share) is degraded, failed beyond off_map_failed_share.
struct CausalCheck {
    double causal_rms_m = 0.0, causal_max_m = 0.0;  ///< causal output to smoothed [m]
    double input_rms_m = 0.0;                       ///< input to smoothed [m]
    bool disagree = false;
    double floor_apart_share = 0.0;      ///< [-] poses in runs a floor apart, of all poses
    double floor_apart_longest_s = 0.0;  ///< [s] the longest such run
    double floor_apart_max_m = 0.0;      ///< [m] the largest height difference in those runs
};

/// Precondition: the three trajectories have the same poses (same size, > 0). `heights`: the
/// height check's thresholds (height_disagree_m, level_window_s); null: no height check (2D,
/// where the heights are not corrected).
CausalCheck CheckCausalOutput(const PlanarTrajectory& input, const PlanarTrajectory& causal,
                              const PlanarTrajectory& smoothed,
                              const VerdictConfig* heights = nullptr);

/// The verdict on an online run and the check behind it.
struct OnlineVerdict {
    Verdict verdict;
    CausalCheck check;
};

/// The verdict on an online run (the stream, eval's online method, the Python Stream): its
/// `smoothed` result judged as a correction of `input` (JudgeCorrection: the start given, the
/// scale estimated), with CheckCausalOutput's findings on its `causal` outputs; a disagreement
/// fails both, outputs a floor apart degrade or fail both (CausalCheck). Precondition: `smoothed`
/// is usable and has the poses of `input` and `causal`.
OnlineVerdict JudgeOnline(const PlanarTrajectory& input, const PlanarTrajectory& causal,
                          const TraversableField* field, const ModelConfig& model,
                          const CorrectionResult& smoothed, const VerdictConfig& config);

}  // namespace driftcorr
