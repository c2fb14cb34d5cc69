#include "driftcorr/core/observables.h"

#include <cassert>
#include <cmath>

#include "driftcorr/core/angles.h"

namespace driftcorr {
namespace {

// Heading of each pose from the step directions: pose i looks along the next moving step; poses
// after the last moving step keep the last direction; no moving step at all gives heading 0.
std::vector<double> HeadingsFromSteps(const PlanarTrajectory& traj, double stationary_m) {
    const std::size_t n = traj.size();
    std::vector<double> yaw(n, 0.0);
    bool have = false;
    double next = 0.0;
    for (std::size_t k = n - 1; k-- > 0;) {
        const Eigen::Vector2d d = traj.p_en[k + 1] - traj.p_en[k];
        if (d.norm() > stationary_m) {
            next = std::atan2(d.y(), d.x());
            have = true;
        }
        yaw[k] = next;
    }
    yaw[n - 1] = n >= 2 ? yaw[n - 2] : 0.0;
    for (std::size_t k = n - 1; k > 0 && have; --k) {
        if ((traj.p_en[k] - traj.p_en[k - 1]).norm() > stationary_m) {
            yaw[n - 1] = std::atan2((traj.p_en[k] - traj.p_en[k - 1]).y(),
                                    (traj.p_en[k] - traj.p_en[k - 1]).x());
            break;
        }
    }
    return yaw;
}

}  // namespace

std::vector<double> UnwrappedHeadings(const PlanarTrajectory& traj, double stationary_m) {
    std::vector<double> yaw = traj.HasYaw() ? traj.yaw_rad : HeadingsFromSteps(traj, stationary_m);
    for (std::size_t i = 1; i < yaw.size(); ++i) yaw[i] = yaw[i - 1] + AngleDiff(yaw[i], yaw[i - 1]);
    return yaw;
}

std::vector<StepObservation> ComputeObservations(const PlanarTrajectory& traj,
                                                 double stationary_m) {
    assert(traj.size() >= 2 && "a trajectory needs at least two poses");
    const std::vector<double> yaw = UnwrappedHeadings(traj, stationary_m);
    std::vector<StepObservation> obs(traj.size());
    for (std::size_t i = 1; i < traj.size(); ++i) {
        StepObservation& o = obs[i];
        const Eigen::Vector2d d = traj.p_en[i] - traj.p_en[i - 1];
        o.dt_s = traj.t_s[i] - traj.t_s[i - 1];
        o.length_m = d.norm();
        o.stationary = o.length_m <= stationary_m;
        o.direction_rad =
            o.stationary ? 0.0 : AngleDiff(std::atan2(d.y(), d.x()), yaw[i - 1]);
        o.dheading_rad = yaw[i] - yaw[i - 1];
        o.dup_m = traj.up_m[i] - traj.up_m[i - 1];
        if (o.stationary) o.length_m = 0.0;
    }
    return obs;
}

}  // namespace driftcorr
