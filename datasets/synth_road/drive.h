#pragma once
// The ground-truth car drive of driftcorr_make_road_scenario: a fixed route through the synthetic
// network, corners rounded by circular fillets, driven 1.5 m right of the centre line with a
// speed profile limited by road class, lateral acceleration and longitudinal acceleration.
// Deterministic: it does not depend on the seed.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "road_network.h"

namespace driftcorr::synth {

struct DriveConfig {
    /// Length of the recording [s]; poses at start_time_s + k / rate_hz for k = 0..duration*rate.
    double duration_s = 420.0;
    /// Pose rate [Hz].
    double rate_hz = 10.0;
    /// Timestamp of the first pose [s].
    double start_time_s = 1000.0;
    /// Distance of the driven line right of the road's centre line [m] (right-hand traffic).
    double lateral_offset_m = 1.5;
    /// Length of the one stop (at a junction about 1.8 km into the route) [s].
    double stop_duration_s = 20.0;

    /// Empty when valid, else the name of the first bad field and why.
    std::string Validate() const;
};

/// A ground-truth pose in the East-North plane; yaw is the heading of travel, CCW from East,
/// unwrapped (continuous over the drive).
struct DrivePose {
    double t_s = 0.0;
    Eigen::Vector2d p_en = Eigen::Vector2d::Zero();
    double yaw_rad = 0.0;
};

/// Drives the fixed route through `net` (vehicle roads only). The route is a closed loop of about
/// 5.5 km; the first lap holds the stop, further laps are driven when the duration needs them.
/// Aborts (programming error) if the route does not fit the network.
std::vector<DrivePose> SimulateDrive(const RoadNetwork& net, const DriveConfig& config);

}  // namespace driftcorr::synth
