#pragma once
// The drifting odometry estimate of driftcorr_make_road_scenario: the ground truth's per-step
// motion integrated again with a step-length scale error, a random-walking heading-rate bias and
// small white noise. Deterministic for a seed: std::mt19937_64 and an own Box-Muller sampler (the
// output of std::normal_distribution differs between standard libraries).
#include <cstdint>
#include <string>
#include <vector>

#include "drive.h"
#include "synth_common.h"

namespace driftcorr::synth {

struct DriftConfig {
    /// Seed of the noise; the map and the ground truth do not depend on it.
    std::uint64_t seed = 42;
    /// Random-walk intensity of the heading-rate bias b [deg/s]: b grows by
    /// N(0, (x * sqrt(dt))^2) each step, i.e. x has units deg/s per sqrt(s). b starts at 0.
    double heading_bias_deg_per_sqrt_s = 0.0015;
    /// Factor applied to every step length (0.97 = the odometry measures 3 % short).
    double scale_error = 0.97;
    /// Relative white noise on each step length (1 sigma).
    double step_noise_rel = 0.01;
    /// White noise on each step's heading change [deg] (1 sigma).
    double heading_noise_deg = 0.01;

    /// Empty when valid, else the name of the first bad field and why.
    std::string Validate() const;
};

/// Integrates the ground truth's per-step motion (body-frame step, heading change) with errors.
/// The estimate starts exactly at the first ground-truth pose and has the same timestamps. A step
/// of zero length (the car standing still) changes neither position nor heading.
std::vector<DrivePose> IntegrateDriftingOdometry(const std::vector<DrivePose>& ground_truth,
                                                 const DriftConfig& config);

}  // namespace driftcorr::synth
