#pragma once
// Accuracy of a trajectory against ground truth, pose by pose (same index = same timestamp), in
// the world's horizontal East-North plane (and the height's RMS error apart), with no
// re-alignment (docs/FORMAT.md, "Judging").
#include <vector>

#include "driftcorr/core/types.h"

namespace driftcorr {

struct ErrorMetrics {
    std::size_t poses = 0;
    double ate_m = 0.0;    ///< RMS horizontal position error
    double final_m = 0.0;  ///< horizontal error of the last pose
    double max_m = 0.0;    ///< largest horizontal error
    double p90_m = 0.0;    ///< 90th percentile of the horizontal error
    double mean_m = 0.0;
    double drift_pct = 0.0;       ///< KITTI-style translational drift [%] over 100..800 m
                                  ///< segments of ground-truth path (0 if the path is shorter)
    double floor_accuracy = 1.0;  ///< share of poses with |up - up_gt| <= 1.5 m
    double vertical_rms_m = 0.0;  ///< RMS of up - up_gt (the height's error)
    double path_length_m = 0.0;   ///< ground-truth horizontal path length
};

/// Per-pose horizontal errors [m]. Precondition: same size.
std::vector<double> HorizontalErrors(const PlanarTrajectory& traj, const PlanarTrajectory& gt);

/// Horizontal path length of a trajectory [m] (0 for fewer than two poses).
double PathLength(const PlanarTrajectory& t);

/// Cumulative horizontal distance travelled along the ground truth [m], one entry per pose.
std::vector<double> DistanceTravelled(const PlanarTrajectory& gt);

/// All metrics. Precondition: same size, >= 2 poses. Headings for the drift metric come from the
/// trajectories' yaw when present, else from their step directions.
ErrorMetrics ComputeMetrics(const PlanarTrajectory& traj, const PlanarTrajectory& gt);

}  // namespace driftcorr
