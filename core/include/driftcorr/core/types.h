#pragma once
// Trajectory types shared by every module. Eigen only.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

namespace driftcorr {

/// A timed sequence of poses T_frame_body in a trajectory's own frame (the SLAM system's frame).
/// Positions in metres, timestamps in seconds, strictly increasing (enforced by the readers).
/// `q_frame_body` is empty when the source format carries no orientation.
struct Trajectory {
    std::vector<double> t_s;
    std::vector<Eigen::Vector3d> p_frame;
    std::vector<Eigen::Quaterniond> q_frame_body;

    std::size_t size() const { return t_s.size(); }
    bool HasOrientation() const { return !q_frame_body.empty(); }
};

/// A trajectory expressed in the world's local East-North-Up plane (the map frame).
/// `yaw_rad` is the heading of the body's forward axis, counter-clockwise from East
/// (empty when the source has no orientation).
struct PlanarTrajectory {
    std::vector<double> t_s;
    std::vector<Eigen::Vector2d> p_en;  ///< East, North [m]
    std::vector<double> up_m;           ///< height above the map datum [m]
    std::vector<double> yaw_rad;        ///< heading, CCW from East [rad]; empty if unknown

    std::size_t size() const { return t_s.size(); }
    bool HasYaw() const { return !yaw_rad.empty(); }
};

}  // namespace driftcorr
