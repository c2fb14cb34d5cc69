#pragma once
// What a drifting trajectory measures well, per step i (from pose i-1 to pose i): the step length,
// the step's direction relative to the heading, the heading change and the height change.
#include <vector>

#include "driftcorr/core/types.h"

namespace driftcorr {

struct StepObservation {
    double dt_s = 0.0;             ///< t_i - t_{i-1} [s]
    double length_m = 0.0;         ///< horizontal step length [m]
    double direction_rad = 0.0;    ///< step direction minus heading of pose i-1 [rad] (0 if stationary)
    double dheading_rad = 0.0;     ///< heading change yaw_i - yaw_{i-1}, wrapped [rad]
    double dup_m = 0.0;            ///< height change [m]
    bool stationary = false;       ///< length below the stationary threshold
};

/// Observations of a planar trajectory: result[i] describes the step into pose i; result[0] is
/// all zeros. Headings come from `traj.yaw_rad` when present; otherwise from the step directions
/// (the heading of pose i is the direction of the next moving step, carried across stops).
/// Precondition: traj.size() >= 2.
std::vector<StepObservation> ComputeObservations(const PlanarTrajectory& traj,
                                                 double stationary_m = 1e-3);

/// Headings used by ComputeObservations, unwrapped (continuous, no 2*pi jumps) [rad].
std::vector<double> UnwrappedHeadings(const PlanarTrajectory& traj, double stationary_m = 1e-3);

}  // namespace driftcorr
