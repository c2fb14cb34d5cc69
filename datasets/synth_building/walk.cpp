// The definitions of what walk.h declares.
#include "walk.h"

#include <cmath>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"

namespace driftcorr::synth {
namespace {

// A leg of the route: walk straight to `to` (z interpolated along the leg: stairs), or ride the
// lift to to.z() (no horizontal motion), or stand for `count` poses.
struct Leg {
    enum Kind { kWalk, kRide, kStand } kind;
    Eigen::Vector3d to = Eigen::Vector3d::Zero();
    int count = 0;
};

Leg W(double x, double y, double z) { return {Leg::kWalk, {x, y, z}, 0}; }
Leg Ride(double z) { return {Leg::kRide, {0.0, 0.0, z}, 0}; }
Leg Stand(int n) { return {Leg::kStand, Eigen::Vector3d::Zero(), n}; }

// Visit the room behind the door at x = door_x: in through the door, a loop, back out.
void AddRoomVisit(double door_x, bool north, double z, std::vector<Leg>& legs) {
    const double s = north ? 1.0 : -1.0, yc = 15.0;
    legs.push_back(W(door_x, yc, z));
    legs.push_back(W(door_x, yc + s * 4.0, z));
    legs.push_back(W(door_x - 2.0, yc + s * 7.0, z));
    legs.push_back(W(door_x + 2.0, yc + s * 10.0, z));
    legs.push_back(W(door_x + 2.5, yc + s * 6.0, z));
    legs.push_back(W(door_x, yc + s * 4.0, z));
    legs.push_back(W(door_x, yc, z));
}

// Up flight f: from the passage to the lower landing, up the flight, onto the upper landing and
// back into the passage.
void AddStairsUp(const BuildingLayout& b, int f, std::vector<Leg>& legs) {
    const double z0 = b.floor_z_m[f], z1 = b.floor_z_m[f + 1], y = 9.75;
    legs.push_back(W(46.2, 15.0, z0));  // from the corridor, clear of the wall corner
    legs.push_back(W(46.2, y, z0));
    legs.push_back(W(b.stair.x0, y, z0));
    legs.push_back(W(b.stair.x1, y, z1));
    legs.push_back(W(56.0, y, z1));
    legs.push_back(W(56.0, 12.0, z1));
}

void AddStairsDown(const BuildingLayout& b, int f, std::vector<Leg>& legs) {
    const double z0 = b.floor_z_m[f], z1 = b.floor_z_m[f + 1], y = 9.75;
    legs.push_back(W(56.0, 12.0, z1));
    legs.push_back(W(56.0, y, z1));
    legs.push_back(W(b.stair.x1, y, z1));
    legs.push_back(W(b.stair.x0, y, z0));
    legs.push_back(W(46.2, y, z0));
    legs.push_back(W(46.2, 12.0, z0));
}

std::vector<Leg> Route(const BuildingLayout& b) {
    const double z0 = b.floor_z_m[0], z1 = b.floor_z_m[1], z2 = b.floor_z_m[2];
    std::vector<Leg> legs;
    AddRoomVisit(11.25, false, z0, legs);  // door of south room 1
    AddRoomVisit(26.25, true, z0, legs);   // north room 3
    AddStairsUp(b, 0, legs);
    legs.push_back(W(44.0, 15.0, z1));
    AddRoomVisit(33.75, false, z1, legs);  // south room 4
    AddRoomVisit(3.75, true, z1, legs);    // north room 0
    legs.push_back(W(51.0, 15.0, z1));
    legs.push_back(W(51.0, 18.5, z1));  // into the cabin
    legs.push_back(Stand(3));
    legs.push_back(Ride(z2));
    legs.push_back(Stand(3));
    legs.push_back(W(51.0, 15.0, z2));
    AddRoomVisit(18.75, false, z2, legs);  // south room 2
    legs.push_back(W(46.2, 15.0, z2));
    AddStairsDown(b, 1, legs);
    AddStairsDown(b, 0, legs);
    legs.push_back(W(46.2, 15.0, z0));
    legs.push_back(W(2.0, 15.0, z0));
    return legs;
}

}  // namespace

std::vector<WalkPose> SimulateWalk(const BuildingLayout& b, const WalkConfig& config) {
    const double dt = 1.0 / config.step_rate_hz;
    std::vector<WalkPose> poses(1);
    poses[0].p_enu = Eigen::Vector3d(2.0, 15.0, b.floor_z_m[0]);
    auto add = [&](const Eigen::Vector3d& p, double yaw_rad) {
        WalkPose next;
        next.t_s = config.t0_s + dt * double(poses.size());
        next.p_enu = p;
        next.yaw_rad = yaw_rad;
        poses.push_back(next);
    };
    for (const Leg& leg : Route(b)) {
        const WalkPose from = poses.back();
        if (leg.kind == Leg::kStand) {
            for (int n = 0; n < leg.count; ++n) add(from.p_enu, from.yaw_rad);
        } else if (leg.kind == Leg::kRide) {
            const double rise = leg.to.z() - from.p_enu.z();
            const int n =
                std::max(1, int(std::ceil(std::abs(rise) / (config.lift_speed_mps * dt))));
            for (int k = 1; k <= n; ++k) {
                add(from.p_enu + Eigen::Vector3d(0.0, 0.0, rise * k / n), from.yaw_rad);
            }
        } else {
            const Eigen::Vector3d d = leg.to - from.p_enu;
            const double length = d.head<2>().norm();
            if (length < 1e-9) continue;
            const int n = std::max(1, int(std::lround(length / config.step_m)));
            const double yaw = std::atan2(d.y(), d.x());
            for (int k = 1; k <= n; ++k) add(from.p_enu + d * (double(k) / n), yaw);
        }
    }
    poses[0].t_s = config.t0_s;
    poses[0].yaw_rad = poses.size() > 1 ? poses[1].yaw_rad : 0.0;
    return poses;
}

std::string PdrDriftConfig::Validate() const {
    if (!(scale_error >= 0.5 && scale_error <= 1.5)) return "scale_error: must be in [0.5, 1.5]";
    if (!(step_noise_rel >= 0.0 && step_noise_rel <= 0.2)) {
        return "step_noise_rel: must be in [0, 0.2]";
    }
    if (!(std::abs(heading_bias0_deg_per_s) <= 1.0)) {
        return "heading_bias0_deg_per_s: must be in [-1, 1]";
    }
    if (!(heading_bias_deg_per_sqrt_s >= 0.0 && heading_bias_deg_per_sqrt_s <= 1.0)) {
        return "heading_bias_deg_per_sqrt_s: must be in [0, 1]";
    }
    if (!(heading_noise_deg >= 0.0 && heading_noise_deg <= 5.0)) {
        return "heading_noise_deg: must be in [0, 5]";
    }
    if (!(height_drift_m_per_sqrt_s >= 0.0 && height_drift_m_per_sqrt_s <= 1.0)) {
        return "height_drift_m_per_sqrt_s: must be in [0, 1]";
    }
    return "";
}

std::vector<WalkPose> IntegrateDriftingPdr(const std::vector<WalkPose>& ground_truth,
                                           const PdrDriftConfig& config) {
    DRIFTCORR_CHECK(config.Validate().empty() && !ground_truth.empty(),
                    "IntegrateDriftingPdr: invalid config or empty input");
    NormalSampler normal(config.seed);
    std::vector<WalkPose> estimate = {ground_truth.front()};
    double bias_deg_per_s = config.heading_bias0_deg_per_s;
    for (std::size_t k = 0; k + 1 < ground_truth.size(); ++k) {
        const WalkPose& a = ground_truth[k];
        const WalkPose& b = ground_truth[k + 1];
        const double dt_s = b.t_s - a.t_s;
        const Eigen::Vector2d step_body = Rotate(-a.yaw_rad, (b.p_enu - a.p_enu).head<2>().eval());
        // Four draws every pose, moving or not, so the noise stream stays aligned with time.
        const double n_bias = normal.Next(), n_step = normal.Next();
        const double n_heading = normal.Next(), n_height = normal.Next();
        bias_deg_per_s += config.heading_bias_deg_per_sqrt_s * std::sqrt(dt_s) * n_bias;
        WalkPose next = estimate.back();
        next.t_s = b.t_s;
        if (step_body.squaredNorm() > 0.0) {
            const double scale = config.scale_error * (1.0 + config.step_noise_rel * n_step);
            next.p_enu.head<2>() += scale * Rotate(next.yaw_rad, step_body);
        }
        next.p_enu.z() += (b.p_enu.z() - a.p_enu.z()) +
                          config.height_drift_m_per_sqrt_s * std::sqrt(dt_s) * n_height;
        next.yaw_rad += WrapAngle(b.yaw_rad - a.yaw_rad) +
                        DegToRad(bias_deg_per_s * dt_s + config.heading_noise_deg * n_heading);
        estimate.push_back(next);
    }
    return estimate;
}

}  // namespace driftcorr::synth
