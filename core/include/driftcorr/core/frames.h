#pragma once
// The axes conventions of trajectory frames (docs/FORMAT.md `frame:`) and the anchor that places a
// trajectory frame in the world's East-North-Up tangent plane.
#include <optional>
#include <string>

#include "driftcorr/core/types.h"

namespace driftcorr {

/// Axes of a trajectory's own frame.
///  - kKittiCamera: x right, y down, z forward; horizontal plane (x, z), up = -y; the body's
///    forward axis is its z axis.
///  - kEnu: x, y horizontal, z up; the body's forward axis is its x axis.
enum class FrameAxes { kKittiCamera, kEnu };

/// Parses "kitti_camera" or "enu"; std::nullopt for anything else.
std::optional<FrameAxes> ParseFrameAxes(const std::string& name);
std::string ToString(FrameAxes axes);

/// Rigid placement of a trajectory frame in the local East-North-Up plane:
/// [E, N] = R(yaw_rad) * [u, v] + origin_en, Up = h + origin_up, where (u, v, h) are the
/// frame's horizontal coordinates and height (see FrameAxes).
struct PlanarAnchor {
    double yaw_rad = 0.0;
    Eigen::Vector2d origin_en = Eigen::Vector2d::Zero();  ///< [m]
    double origin_up_m = 0.0;                             ///< [m]
};

/// Splits a frame position into horizontal (u, v) and height h (a right-handed u, v, h triple).
Eigen::Vector3d FrameToUvh(FrameAxes axes, const Eigen::Vector3d& p_frame);
Eigen::Vector3d UvhToFrame(FrameAxes axes, const Eigen::Vector3d& uvh);
/// The body axis that points forward (unit vector in the body frame).
Eigen::Vector3d BodyForwardAxis(FrameAxes axes);
/// The frame's Up axis (unit vector in the trajectory frame).
Eigen::Vector3d FrameUpAxis(FrameAxes axes);

/// Places a trajectory in the world plane. Heading comes from the orientation when there is one
/// (forward axis projected on the horizontal plane); otherwise yaw_rad stays empty.
PlanarTrajectory ToPlanar(const Trajectory& traj, FrameAxes axes, const PlanarAnchor& anchor);

/// Inverse of ToPlanar for a corrected planar trajectory: positions come from `corrected` (height
/// from `corrected.up_m`), orientations are the `original` ones turned about Up by the heading
/// correction `corrected.yaw_rad[i] - reference.yaw_rad[i]` (or left unchanged without yaw).
/// When `original` has no orientation and `corrected` has yaw, each pose gets a rotation about the
/// frame's Up axis alone that points the body's forward axis (BodyForwardAxis) along that yaw: the
/// heading the corrector solved for, no roll or pitch. Neither: no orientation.
Trajectory FromPlanar(const PlanarTrajectory& corrected, const PlanarTrajectory& reference,
                      const Trajectory& original, FrameAxes axes, const PlanarAnchor& anchor);

}  // namespace driftcorr
