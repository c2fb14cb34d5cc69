#pragma once
// The ground-truth walk through the synthetic building and its drifting PDR-like estimate.
// Deterministic for a seed: std::mt19937_64 and an own Box-Muller sampler (the output of
// std::normal_distribution differs between standard libraries).
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "building.h"
#include "synth_common.h"

namespace driftcorr::synth {

/// One pose a step: position in the local East-North-Up frame [m] (z = floor height, no device
/// offset) and heading about Up [rad, counter-clockwise from East].
struct WalkPose {
    double t_s = 0.0;
    Eigen::Vector3d p_enu = Eigen::Vector3d::Zero();
    double yaw_rad = 0.0;
};

struct WalkConfig {
    double step_m = 0.7;        ///< nominal step length; each straight leg is cut into equal steps
    double step_rate_hz = 1.8;  ///< one pose a step (and a pose every 1/rate while standing)
    double lift_speed_mps = 1.0;  ///< vertical speed of the lift cabin
    double t0_s = 1000.0;         ///< timestamp of the first pose
};

/// The walk: corridors and two rooms on floor 0, stairs up to floor 1, corridors and two rooms,
/// the lift up to floor 2 (standing in the cabin; z changes with no horizontal motion), a
/// corridor and a room, then both flights down and back along the corridor of floor 0.
std::vector<WalkPose> SimulateWalk(const BuildingLayout& b, const WalkConfig& config);

struct PdrDriftConfig {
    std::uint64_t seed = 7;  ///< seed of the noise; building and ground truth do not depend on it
    double scale_error = 0.95;     ///< factor on every step length (0.95: steps measured 5 % short)
    double step_noise_rel = 0.03;  ///< relative white noise on each step length (1 sigma)
    double heading_bias0_deg_per_s = 0.03;  ///< initial heading-rate (gyro) bias [deg/s]
    /// Random walk of the heading-rate bias b [deg/s]: each pose b += x sqrt(dt) n, n ~ N(0, 1).
    double heading_bias_deg_per_sqrt_s = 0.003;
    double heading_noise_deg = 0.3;  ///< white noise on each pose's heading change [deg]
    /// Random walk of the height offset (barometer drift) [m per sqrt(s)].
    double height_drift_m_per_sqrt_s = 0.02;

    /// Empty when valid, else the name of the first bad field and why.
    std::string Validate() const;
};

/// The ground truth's per-pose motion (body-frame horizontal step, height change, heading
/// change) integrated again with the errors of `config`. Starts exactly at the first
/// ground-truth pose, same timestamps. The heading bias acts at every pose (a gyro drifts
/// standing still, too); the scale error only on horizontal steps.
std::vector<WalkPose> IntegrateDriftingPdr(const std::vector<WalkPose>& ground_truth,
                                           const PdrDriftConfig& config);

}  // namespace driftcorr::synth
