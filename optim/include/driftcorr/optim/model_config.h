#pragma once
// The parameters of the weighted NLL: one sigma and one weight per term. Sigmas are given in
// sampling-independent units so the same values serve 10 Hz cars and 2 Hz pedestrian steps.
// The terms and their equations: docs/method.md.
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/params.h"

namespace driftcorr {

/// Bounds of the step-length scale variables: a scale at a bound means the map and the odometry
/// disagree (a wrong anchor, a map of another place, an estimate that is not odometry).
constexpr double kScaleMin = 0.25, kScaleMax = 4.0;

struct ModelConfig {
    // Step length: sigma = step_sigma_m + step_sigma_rel * L.
    double step_sigma_m = 0.02;    ///< [m]
    double step_sigma_rel = 0.01;  ///< [-] share of the step length
    /// A pedestrian step model's lengths are read about their median: a moving step of length L
    /// is observed as median^(1 - step_length_exponent) * L^step_length_exponent (core
    /// ReadAtGait; the batch takes the median over the whole estimate, online the steps so
    /// far). 1: as the odometry read them (metric odometry, whose step lengths are its speed).
    double step_length_exponent = 1.0;
    // Sideways motion against the observed step direction: sigma = lateral_sigma_m + rel * L.
    double lateral_sigma_m = 0.02;    ///< [m]
    double lateral_sigma_rel = 0.02;  ///< [-]
    /// Heavy-tailed step-length likelihood (docs/method.md, Eq. 2 and 4): the Cauchy width in
    /// sigmas [-], >= 0; 0 = Gaussian. A step the odometry dropped (near zero while moving) then
    /// becomes an outlier instead of a hard pull.
    /// Speed continuity (Eq. 10): the along-track speed of consecutive steps differs by a Gaussian
    /// with sigma = accel_sigma_mps2 * dt [m/s]; accel_sigma_mps2 [m/s^2], >= 0; 0 disables the
    /// term. speed_weight in (0, 1]: its weight. Both off by default (measured: docs/results.md,
    /// "Heavy-tailed step and scale terms on the KITTI drives").
    double step_robust_k = 0.0;
    double accel_sigma_mps2 = 0.0;
    double speed_weight = 1.0;
    /// Explicit outlier handling of dropped or doubled odometry steps (core RepairSpeedEpisodes,
    /// batch correction): an episode the odometry enters and leaves with a speed change faster
    /// than outlier_accel_mps2 (about 1 g: no road vehicle brakes harder, no pedestrian
    /// changes pace so fast) has its off-speed steps replaced by the speed around it, observed
    /// with sigma step_sigma_m + outlier_sigma_rel * L instead of the odometry's own. 0: off.
    double outlier_accel_mps2 = 10.0;  ///< [m/s^2]
    double outlier_sigma_rel = 0.2;    ///< [-]
    /// Steps faster than this are discontinuities of the estimate (not scaled, no speed term).
    double max_speed_mps = 70.0;
    // Heading change: sigma^2 = heading_rw^2 * dt + (heading_sigma_rel * |dheading|)^2.
    double heading_rw_rad_per_sqrt_s = 0.004;  ///< heading random walk [rad/sqrt(s)]
    double heading_sigma_rel = 0.02;           ///< [-] gyro scale error share of a turn
    double heading_sigma_min_rad = 1e-4;       ///< floor [rad]
    /// Heading-rate bias: the odometry's heading drifts at a slowly varying rate (a gyro bias, a
    /// visual / lidar odometry's systematic yaw error), one unknown bias [rad/s] per
    /// heading_bias_segment_s of time, a random walk of heading_bias_rw_rad_s between segments and
    /// a prior of heading_bias_prior_rad_s around 0 on the first. A steady drift then costs the
    /// prior once, not every step's heading sigma, so following the roads stays cheaper than
    /// bending the scale. heading_bias_segment_s = 0: no bias.
    double heading_bias_segment_s = 30.0;      ///< [s]
    double heading_bias_prior_rad_s = 0.0087;  ///< [rad/s] (0.5 deg/s)
    double heading_bias_rw_rad_s = 0.0017;     ///< [rad/s] per segment (0.1 deg/s)
    // Heading preservation prior (turns are small), per step.
    double preservation_sigma_rad = 1.0;  ///< [rad]; large = weak
    // Height change (indoor3d): sigma = height_sigma_m + height_sigma_rel * |dup|.
    double height_sigma_m = 0.05;    ///< [m]
    double height_sigma_rel = 0.05;  ///< [-]
    /// Floors (indoor3d): a pose where the estimate's height stays level (within
    /// floor_level_height_m over the floor_level_window_s around it: LevelSpans) stands on a
    /// floor, so its height is drawn to the one of the map's floors (TraversableField::
    /// floor_heights_m) nearest to it when the window is built: sigma floor_sigma_m, Cauchy
    /// beyond floor_robust_k sigmas (0: Gaussian). Stair halls and lift shafts are traversable
    /// at every height between their floors: without it a walk whose barometer misreads a climb
    /// walks on, level, between floors there. floor_sigma_m = 0 or a map without floors: no
    /// such term.
    double floor_sigma_m = 0.0;          ///< [m]
    double floor_robust_k = 3.0;         ///< [-]
    double floor_level_window_s = 20.0;  ///< [s]
    double floor_level_height_m = 1.0;   ///< [m]
    /// Roads climb and fall at bounded grades. Where the solve holds the heights (road2d), each
    /// stretch of grade_stretch_m of the corrected path whose estimated height change is steeper
    /// than max_grade (rise over run) has it limited to that grade (core BoundGrades); the
    /// heights are otherwise the estimate's. 0: the estimate's heights as they are.
    double max_grade = 0.10;        ///< [-]
    double grade_stretch_m = 25.0;  ///< [m]
    // Map distance to the nearest traversable centre: Gaussian with sigma, gives up beyond ~giveup.
    double map_sigma_m = 2.0;   ///< [m]
    double map_giveup_m = 8.0;  ///< [m]
    /// Lift rides (a map with lift shafts, TraversableField::lift_shafts): a pose where the walker
    /// stands while the height changes (RideSpans: ride_min_s, ride_min_height_m; no step for
    /// ride_gap_s counts as standing; ride_lag_s of barometer lag) is in a lift: its horizontal
    /// distance to the nearest shaft has the map term's form with lift_sigma_m and
    /// lift_giveup_m. The walkway term alone lets such a pose go where the walk around it
    /// lands (a stairwell, a corridor), since a few poses off the walkways cost little.
    /// lift_sigma_m = 0: no such term.
    double lift_sigma_m = 0.0;       ///< [m]
    double lift_giveup_m = 10.0;     ///< [m]
    double ride_min_s = 5.0;         ///< [s]
    double ride_min_height_m = 2.0;  ///< [m]
    double ride_gap_s = 3.0;         ///< [s]
    double ride_lag_s = 5.0;         ///< [s]
    /// Stair treads (indoor3d, batch; off by default: docs/results.md, "Stair treads"): a
    /// walking step amid a height change of tread_rate_mps or more over the tread_window_s
    /// around it (core MarkStairTreads) runs a tread of tread_m, sigma tread_sigma_m, whatever
    /// length the odometry read and unscaled. tread_m = 0: every step as read.
    double tread_m = 0.0;          ///< [m]
    double tread_sigma_m = 0.15;   ///< [m]
    double tread_window_s = 4.0;   ///< [s]
    double tread_rate_mps = 0.15;  ///< [m/s]
    // Step-length scale: one variable per scale_segment_m of estimated path, random walk between
    // segments, prior around scale_prior_mean on the first.
    double scale_segment_m = 150.0;  ///< [m]
    double scale_prior_sigma = 0.1;  ///< [-]
    /// The scale every scored NLL's prior is about (by default 1, the odometry's own scale; online,
    /// the start nearest it gives the first outputs); the windows of a start scale hypothesis
    /// hold it at the start (CorrectorConfig::start_scales; online, the FixedLagSmoother's
    /// start_scale).
    double scale_prior_mean = 1.0;  ///< [-]
    double scale_rw_sigma = 0.01;   ///< [-] per segment
    /// The plausible scale range as a prior: no cost within [scale_range_min, scale_range_max],
    /// Gaussian with scale_range_sigma beyond (metric odometry is a few percent off; pedestrian
    /// step models tens of percent). scale_range_sigma = 0: no range prior (the bounds kScaleMin,
    /// kScaleMax stay hard).
    double scale_range_min = 0.8, scale_range_max = 1.25;  ///< [-]
    double scale_range_sigma = 0.05;                       ///< [-]
    /// Cauchy width of the scale walk in sigmas (Eq. 2 and 14) [-], >= 0; 0 = Gaussian, the
    /// default (measured: docs/results.md, "Heavy-tailed step and scale terms on the KITTI
    /// drives").
    double scale_rw_robust_k = 0.0;
    // Weights w in (0, 1] of each term family.
    double step_weight = 1.0, heading_weight = 1.0, preservation_weight = 1.0, map_weight = 1.0,
           height_weight = 1.0;
    // Hard corridor: every pose whose start point is within corridor_gate_m of the traversable
    // corridor must end inside it (signed corridor distance <= corridor_slack_m).
    bool hard_corridor = true;
    double corridor_gate_m = 3.0;   ///< [m]
    double corridor_slack_m = 0.0;  ///< [m]

    /// The first value kModelParams or scale_range_min <= scale_range_max does not allow.
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "model.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;

    /// The model of a pedestrian's dead reckoning indoors (the members' initialisers are the
    /// road model of a car's metric odometry): steps of ~0.7 m at ~2 Hz from a step model that
    /// can be tens of percent off, their lengths erring with the gait and read about the walk's
    /// median step; a heading that errs by offsets and jumps (a heading walk, no rate bias); a
    /// barometer's height changes; walkways a few metres wide; poses drawn to a lift shaft during
    /// a ride and to the nearest of the map's floors where the walk is level. How each value
    /// was chosen: docs/results.md, "Indoor parameters".
    static ModelConfig Pedestrian();
};

/// Params.yaml section `model` (and `indoor_model`); the defaults are the members' initialisers
/// (`indoor_model`: ModelConfig::Pedestrian()).
inline constexpr Param<ModelConfig> kModelParamRows[] = {
    {"step_sigma_m", Field<&ModelConfig::step_sigma_m>(), kPositive,
     "step length sigma = step_sigma_m + step_sigma_rel * L"},
    {"step_sigma_rel", Field<&ModelConfig::step_sigma_rel>(), kNonNegative,
     "step length sigma, share of the step length"},
    {"step_length_exponent", Field<&ModelConfig::step_length_exponent>(), kShare,
     "a step's length read as median^(1 - e) * L^e; 1: as read, 0: the median step (PDR)"},
    {"lateral_sigma_m", Field<&ModelConfig::lateral_sigma_m>(), kPositive,
     "sideways motion sigma = lateral_sigma_m + lateral_sigma_rel * L"},
    {"lateral_sigma_rel", Field<&ModelConfig::lateral_sigma_rel>(), kNonNegative,
     "sideways motion sigma, share of the step length"},
    {"step_robust_k", Field<&ModelConfig::step_robust_k>(), kNonNegative,
     "Cauchy width of the step-length term in sigmas; 0: Gaussian"},
    {"accel_sigma_mps2", Field<&ModelConfig::accel_sigma_mps2>(), kNonNegative,
     "speed continuity between steps, sigma = accel_sigma_mps2 * dt; 0: off"},
    {"speed_weight", Field<&ModelConfig::speed_weight>(), kWeight, "weight of the speed term"},
    {"outlier_accel_mps2", Field<&ModelConfig::outlier_accel_mps2>(), kNonNegative,
     "dropped-step episodes (speed falls and recovers faster) observed at the speed around them; "
     "0: off"},
    {"outlier_sigma_rel", Field<&ModelConfig::outlier_sigma_rel>(), kNonNegative,
     "step sigma share of a repaired step"},
    {"max_speed_mps", Field<&ModelConfig::max_speed_mps>(), kPositive,
     "faster steps are discontinuities of the estimate (not scaled, no speed term)"},
    {"heading_rw_rad_per_sqrt_s", Field<&ModelConfig::heading_rw_rad_per_sqrt_s>(), kNonNegative,
     "heading random walk"},
    {"heading_sigma_rel", Field<&ModelConfig::heading_sigma_rel>(), kNonNegative,
     "gyro scale error, share of a turn"},
    {"heading_sigma_min_rad", Field<&ModelConfig::heading_sigma_min_rad>(), kPositive,
     "floor of the heading-change sigma"},
    {"heading_bias_segment_s", Field<&ModelConfig::heading_bias_segment_s>(), kNonNegative,
     "one heading-rate bias unknown per this much time; 0: no bias"},
    {"heading_bias_prior_rad_s", Field<&ModelConfig::heading_bias_prior_rad_s>(), kPositive,
     "prior of the first heading-rate bias around 0"},
    {"heading_bias_rw_rad_s", Field<&ModelConfig::heading_bias_rw_rad_s>(), kPositive,
     "random walk of the heading-rate bias per segment"},
    {"preservation_sigma_rad", Field<&ModelConfig::preservation_sigma_rad>(), kPositive,
     "heading preservation prior per step; large: weak"},
    {"height_sigma_m", Field<&ModelConfig::height_sigma_m>(), kPositive,
     "height change sigma = height_sigma_m + height_sigma_rel * |dup| (indoor3d)"},
    {"height_sigma_rel", Field<&ModelConfig::height_sigma_rel>(), kNonNegative,
     "height change sigma, share of the height change"},
    {"floor_sigma_m", Field<&ModelConfig::floor_sigma_m>(), kNonNegative,
     "sigma of a level pose's height about the nearest floor (indoor3d plans); 0: no such term"},
    {"floor_robust_k", Field<&ModelConfig::floor_robust_k>(), kNonNegative,
     "Cauchy width of that term in sigmas; 0: Gaussian"},
    {"floor_level_window_s", Field<&ModelConfig::floor_level_window_s>(), kPositive,
     "a pose is level when the estimate's height stays within floor_level_height_m over this span"},
    {"floor_level_height_m", Field<&ModelConfig::floor_level_height_m>(), kPositive,
     "see floor_level_window_s"},
    {"max_grade", Field<&ModelConfig::max_grade>(), kShare,
     "road2d: a stretch of corrected path climbs or falls at most this grade; 0: heights as "
     "estimated"},
    {"grade_stretch_m", Field<&ModelConfig::grade_stretch_m>(), kPositive,
     "the length of those stretches"},
    {"map_sigma_m", Field<&ModelConfig::map_sigma_m>(), kPositive,
     "pull towards the nearest traversable centre"},
    {"map_giveup_m", Field<&ModelConfig::map_giveup_m>(), kPositive,
     "beyond about this distance from the map the map term lets go"},
    {"lift_sigma_m", Field<&ModelConfig::lift_sigma_m>(), kNonNegative,
     "pull of a pose in a lift ride towards the nearest lift shaft; 0: none"},
    {"lift_giveup_m", Field<&ModelConfig::lift_giveup_m>(), kPositive,
     "beyond about this distance from every lift shaft the lift term lets go"},
    {"ride_min_s", Field<&ModelConfig::ride_min_s>(), kPositive,
     "a lift ride: the walker stands at least this long..."},
    {"ride_min_height_m", Field<&ModelConfig::ride_min_height_m>(), kPositive,
     "...while the height changes by at least this"},
    {"ride_gap_s", Field<&ModelConfig::ride_gap_s>(), kPositive,
     "no step for this long counts as standing"},
    {"ride_lag_s", Field<&ModelConfig::ride_lag_s>(), kNonNegative,
     "the ride's height change is read up to this long after it (barometer lag)"},
    {"tread_m", Field<&ModelConfig::tread_m>(), kNonNegative,
     "horizontal run of a step amid a stair climb or descent (indoor3d); 0: steps as read"},
    {"tread_sigma_m", Field<&ModelConfig::tread_sigma_m>(), kPositive, "sigma of a tread's run"},
    {"tread_window_s", Field<&ModelConfig::tread_window_s>(), kPositive,
     "a step is a tread when the walking steps within this span around it..."},
    {"tread_rate_mps", Field<&ModelConfig::tread_rate_mps>(), kPositive,
     "...change height at least this fast"},
    {"scale_segment_m", Field<&ModelConfig::scale_segment_m>(), kPositive,
     "one step-length scale unknown per this much estimated path"},
    {"scale_prior_mean", Field<&ModelConfig::scale_prior_mean>(), Between(kScaleMin, kScaleMax),
     "mean of the first scale's prior"},
    {"scale_prior_sigma", Field<&ModelConfig::scale_prior_sigma>(), kPositive,
     "prior of the first scale around scale_prior_mean"},
    {"scale_rw_sigma", Field<&ModelConfig::scale_rw_sigma>(), kPositive,
     "random walk of the scale per segment"},
    {"scale_rw_robust_k", Field<&ModelConfig::scale_rw_robust_k>(), kNonNegative,
     "Cauchy width of the scale walk in sigmas; 0: Gaussian"},
    {"scale_range_min", Field<&ModelConfig::scale_range_min>(), kPositive,
     "plausible scale range: free inside, Gaussian with scale_range_sigma outside"},
    {"scale_range_max", Field<&ModelConfig::scale_range_max>(), kPositive,
     "upper end of the plausible scale range"},
    {"scale_range_sigma", Field<&ModelConfig::scale_range_sigma>(), kNonNegative,
     "sigma outside the plausible scale range; 0: no range prior"},
    {"step_weight", Field<&ModelConfig::step_weight>(), kWeight, "weight of the step terms"},
    {"heading_weight", Field<&ModelConfig::heading_weight>(), kWeight,
     "weight of the heading-change terms"},
    {"preservation_weight", Field<&ModelConfig::preservation_weight>(), kWeight,
     "weight of the heading preservation terms"},
    {"map_weight", Field<&ModelConfig::map_weight>(), kWeight, "weight of the map terms"},
    {"height_weight", Field<&ModelConfig::height_weight>(), kWeight,
     "weight of the height-change terms"},
    {"hard_corridor", Field<&ModelConfig::hard_corridor>(), kNoRange,
     "final solve: every pose near the map ends inside its corridor"},
    {"corridor_gate_m", Field<&ModelConfig::corridor_gate_m>(), kNonNegative,
     "poses starting within this distance of the corridor are held inside it"},
    {"corridor_slack_m", Field<&ModelConfig::corridor_slack_m>(), kNonNegative,
     "allowed signed corridor distance of a held pose"},
};
inline constexpr ParamTable<ModelConfig> kModelParams{"model", kModelParamRows};

}  // namespace driftcorr
