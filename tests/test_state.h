#pragma once
// The trajectory state of an estimate as the window tests build it: observations, one scale
// segment per model.scale_segment_m (all scales 1), one heading-rate bias segment per
// model.heading_bias_segment_s (all biases 0), poses at the estimate.
#include <vector>

#include "driftcorr/core/observables.h"
#include "driftcorr/optim/window_problem.h"

namespace driftcorr::test {

inline TrajectoryState StateFrom(const PlanarTrajectory& est, const ModelConfig& m,
                                 bool fix_height) {
    TrajectoryState s;
    s.obs = ComputeObservations(est);
    s.scale_segment = ScaleSegments(s.obs, m.scale_segment_m);
    s.scales.assign(s.scale_segment.back() + 1, 1.0);
    s.bias_segment = BiasSegments(s.obs, m.heading_bias_segment_s);
    if (!s.bias_segment.empty()) s.biases.assign(s.bias_segment.back() + 1, 0.0);
    const std::vector<double> yaw = UnwrappedHeadings(est);
    for (std::size_t i = 0; i < est.size(); ++i) {
        s.poses.push_back(
            PoseState{Eigen::Vector3d(est.p_en[i].x(), est.p_en[i].y(), est.up_m[i]), yaw[i]});
    }
    s.fix_height = fix_height;
    return s;
}

}  // namespace driftcorr::test
