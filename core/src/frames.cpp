// The definitions of what driftcorr/core/frames.h declares.
#include "driftcorr/core/frames.h"

#include <cmath>

namespace driftcorr {

std::optional<FrameAxes> ParseFrameAxes(const std::string& name) {
    if (name == "kitti_camera") return FrameAxes::kKittiCamera;
    if (name == "enu") return FrameAxes::kEnu;
    return std::nullopt;
}

std::string ToString(FrameAxes axes) {
    return axes == FrameAxes::kKittiCamera ? "kitti_camera" : "enu";
}

// kitti_camera: (u, v, h) = (x, z, -y); x cross z = -y, so the triple is right-handed.
Eigen::Vector3d FrameToUvh(FrameAxes axes, const Eigen::Vector3d& p) {
    if (axes == FrameAxes::kKittiCamera) return {p.x(), p.z(), -p.y()};
    return p;
}

Eigen::Vector3d UvhToFrame(FrameAxes axes, const Eigen::Vector3d& uvh) {
    if (axes == FrameAxes::kKittiCamera) return {uvh.x(), -uvh.z(), uvh.y()};
    return uvh;
}

Eigen::Vector3d BodyForwardAxis(FrameAxes axes) {
    return axes == FrameAxes::kKittiCamera ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
}

Eigen::Vector3d FrameUpAxis(FrameAxes axes) {
    return axes == FrameAxes::kKittiCamera ? Eigen::Vector3d(0, -1, 0) : Eigen::Vector3d::UnitZ();
}

static Eigen::Matrix2d Rot2(double yaw_rad) {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    Eigen::Matrix2d r;
    r << c, -s, s, c;
    return r;
}

PlanarTrajectory ToPlanar(const Trajectory& traj, FrameAxes axes, const PlanarAnchor& anchor) {
    PlanarTrajectory out;
    const std::size_t n = traj.size();
    out.t_s = traj.t_s;
    out.p_en.resize(n);
    out.up_m.resize(n);
    const Eigen::Matrix2d r = Rot2(anchor.yaw_rad);
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d uvh = FrameToUvh(axes, traj.p_frame[i]);
        out.p_en[i] = r * uvh.head<2>() + anchor.origin_en;
        out.up_m[i] = uvh.z() + anchor.origin_up_m;
    }
    if (traj.HasOrientation()) {
        out.yaw_rad.resize(n);
        const Eigen::Vector3d fwd_body = BodyForwardAxis(axes);
        for (std::size_t i = 0; i < n; ++i) {
            const Eigen::Vector3d f = FrameToUvh(axes, traj.q_frame_body[i] * fwd_body);
            // A forward axis pointing straight up or down has no heading; keep the previous one.
            const double yaw_frame = (f.head<2>().norm() > 1e-9)
                                         ? std::atan2(f.y(), f.x())
                                         : (i > 0 ? out.yaw_rad[i - 1] - anchor.yaw_rad : 0.0);
            out.yaw_rad[i] = yaw_frame + anchor.yaw_rad;
        }
    }
    return out;
}

Trajectory FromPlanar(const PlanarTrajectory& corrected, const PlanarTrajectory& reference,
                      const Trajectory& original, FrameAxes axes, const PlanarAnchor& anchor) {
    Trajectory out;
    const std::size_t n = corrected.size();
    out.t_s = corrected.t_s;
    out.p_frame.resize(n);
    const Eigen::Matrix2d r_inv = Rot2(-anchor.yaw_rad);
    for (std::size_t i = 0; i < n; ++i) {
        Eigen::Vector3d uvh;
        uvh.head<2>() = r_inv * (corrected.p_en[i] - anchor.origin_en);
        uvh.z() = corrected.up_m[i] - anchor.origin_up_m;
        out.p_frame[i] = UvhToFrame(axes, uvh);
    }
    if (!original.HasOrientation() && corrected.HasYaw()) {
        // No orientation to turn: a rotation about Up alone, the forward axis along the heading.
        out.q_frame_body.resize(n);
        const Eigen::Vector3d rest = FrameToUvh(axes, BodyForwardAxis(axes));
        const double rest_yaw_rad = std::atan2(rest.y(), rest.x());
        for (std::size_t i = 0; i < n; ++i) {
            const double yaw_frame_rad = corrected.yaw_rad[i] - anchor.yaw_rad;
            out.q_frame_body[i] = Eigen::Quaterniond(
                Eigen::AngleAxisd(yaw_frame_rad - rest_yaw_rad, FrameUpAxis(axes)));
        }
    } else if (original.HasOrientation()) {
        out.q_frame_body.resize(n);
        const Eigen::Vector3d up = FrameUpAxis(axes);
        const bool turn = corrected.HasYaw() && reference.HasYaw();
        for (std::size_t i = 0; i < n; ++i) {
            const double delta = turn ? corrected.yaw_rad[i] - reference.yaw_rad[i] : 0.0;
            out.q_frame_body[i] =
                (Eigen::AngleAxisd(delta, up) * original.q_frame_body[i]).normalized();
        }
    }
    return out;
}

}  // namespace driftcorr
