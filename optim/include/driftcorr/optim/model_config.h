#pragma once
// The parameters of the weighted NLL: one sigma and one weight per term. Sigmas are given in
// sampling-independent units so the same values serve 10 Hz cars and 2 Hz pedestrian steps.
#include <string>

namespace driftcorr {

struct ModelConfig {
    // Step length: sigma = step_sigma_m + step_sigma_rel * L.
    double step_sigma_m = 0.02;       ///< [m]
    double step_sigma_rel = 0.01;     ///< [-] share of the step length
    // Sideways motion against the observed step direction: sigma = lateral_sigma_m + rel * L.
    double lateral_sigma_m = 0.02;    ///< [m]
    double lateral_sigma_rel = 0.02;  ///< [-]
    /// Heavy-tailed step-length likelihood (Cauchy width in sigmas; 0 = Gaussian): a step the
    /// odometry dropped (near zero while moving) becomes an outlier instead of a hard pull.
    /// Speed continuity: the along-track speed of consecutive steps differs by a Gaussian with
    /// sigma = accel_sigma_mps2 * dt [m/s]; 0 disables the term.
    /// Both off by default. Measured on KITTI (ATE, gicp00 / gicp07 / cvo05): defaults 6.8 / 8.2 /
    /// 7.0 m; step_robust_k 3 + accel 2: 256 / 118 / 8.3 m (steps become free, windows fall into
    /// wrong basins); accel 2 alone: 307 / 118 / 8.3 m (the tight Gaussian steps of dropped
    /// frames and the smooth-speed prior fight); step_robust_k 10: 6.8 / 8.2 / 7.2 m.
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
    /// heading_bias_segment_s of time, a random walk of heading_bias_rw_rad_s between segments and a
    /// prior of heading_bias_prior_rad_s around 0 on the first. A steady drift then costs the
    /// prior once, not every step's heading sigma, so following the roads stays cheaper than
    /// bending the scale. heading_bias_segment_s = 0: no bias.
    double heading_bias_segment_s = 30.0;      ///< [s]
    double heading_bias_prior_rad_s = 0.0087;  ///< [rad/s] (0.5 deg/s)
    double heading_bias_rw_rad_s = 0.0017;     ///< [rad/s] per segment (0.1 deg/s)
    // Heading preservation prior (turns are small), per step.
    double preservation_sigma_rad = 1.0;  ///< [rad]; large = weak
    // Height change (indoor3d): sigma = height_sigma_m + height_sigma_rel * |dup|.
    double height_sigma_m = 0.05;     ///< [m]
    double height_sigma_rel = 0.05;   ///< [-]
    // Map distance to the nearest traversable centre: Gaussian with sigma, gives up beyond ~giveup.
    double map_sigma_m = 2.0;         ///< [m]
    double map_giveup_m = 8.0;        ///< [m]
    // Step-length scale: one variable per scale_segment_m of estimated path, random walk between
    // segments, prior around 1 on the first.
    double scale_segment_m = 150.0;   ///< [m]
    double scale_prior_sigma = 0.1;   ///< [-]
    double scale_rw_sigma = 0.01;     ///< [-] per segment
    /// The plausible scale range as a prior: no cost within [scale_range_min, scale_range_max],
    /// Gaussian with scale_range_sigma beyond (metric odometry is a few percent off; pedestrian
    /// step models tens of percent). scale_range_sigma = 0: no range prior (the bounds kScaleMin,
    /// kScaleMax stay hard).
    double scale_range_min = 0.8, scale_range_max = 1.25;  ///< [-]
    double scale_range_sigma = 0.05;                       ///< [-]
    /// Cauchy width of the walk in sigmas; 0 = Gaussian. Measured on KITTI: k = 3 or 10 lets the
    /// scale jump into wrong basins (kitti00 gicp ATE 6.8 -> 190 m), so the default is Gaussian.
    double scale_rw_robust_k = 0.0;
    // Weights w in (0, 1] of each term family.
    double step_weight = 1.0, heading_weight = 1.0, preservation_weight = 1.0, map_weight = 1.0,
           height_weight = 1.0;
    // Hard corridor: every pose whose start point is within corridor_gate_m of the traversable
    // corridor must end inside it (signed corridor distance <= corridor_slack_m).
    bool hard_corridor = true;
    double corridor_gate_m = 3.0;     ///< [m]
    double corridor_slack_m = 0.0;    ///< [m]

    /// Empty if valid, else a message naming the first bad field.
    std::string Validate() const;
};

}  // namespace driftcorr
