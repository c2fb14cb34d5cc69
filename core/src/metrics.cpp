// The definitions of what driftcorr/core/metrics.h declares.
#include "driftcorr/core/metrics.h"

#include <algorithm>
#include <cmath>

#include "driftcorr/core/check.h"
#include "driftcorr/core/observables.h"

namespace driftcorr {

std::vector<double> HorizontalErrors(const PlanarTrajectory& traj, const PlanarTrajectory& gt) {
    DRIFTCORR_CHECK(traj.size() == gt.size(), "trajectories must have one pose per timestamp");
    std::vector<double> e(traj.size());
    for (std::size_t i = 0; i < e.size(); ++i) e[i] = (traj.p_en[i] - gt.p_en[i]).norm();
    return e;
}

double PathLength(const PlanarTrajectory& t) {
    double path_m = 0.0;
    for (std::size_t i = 1; i < t.p_en.size(); ++i) path_m += (t.p_en[i] - t.p_en[i - 1]).norm();
    return path_m;
}

std::vector<double> DistanceTravelled(const PlanarTrajectory& gt) {
    std::vector<double> s(gt.size(), 0.0);
    for (std::size_t i = 1; i < s.size(); ++i)
        s[i] = s[i - 1] + (gt.p_en[i] - gt.p_en[i - 1]).norm();
    return s;
}

namespace {

// KITTI devkit style: segments of 100..800 m starting every 10th pose; error of the relative
// displacement expressed in the start pose's heading frame, divided by the segment length.
double KittiDrift(const PlanarTrajectory& traj, const PlanarTrajectory& gt,
                  const std::vector<double>& dist) {
    const std::vector<double> yaw = UnwrappedHeadings(traj), yaw_gt = UnwrappedHeadings(gt);
    double sum = 0.0;
    int count = 0;
    for (double len = 100.0; len <= 800.0; len += 100.0) {
        std::size_t j = 0;
        for (std::size_t i = 0; i < gt.size(); i += 10) {
            j = std::max(j, i);
            while (j < gt.size() && dist[j] - dist[i] < len) ++j;
            if (j >= gt.size()) break;
            const Eigen::Rotation2Dd r(-yaw[i]), r_gt(-yaw_gt[i]);
            const Eigen::Vector2d d = r * (traj.p_en[j] - traj.p_en[i]);
            const Eigen::Vector2d d_gt = r_gt * (gt.p_en[j] - gt.p_en[i]);
            sum += (d - d_gt).norm() / len;
            ++count;
        }
    }
    return count > 0 ? 100.0 * sum / count : 0.0;
}

}  // namespace

ErrorMetrics ComputeMetrics(const PlanarTrajectory& traj, const PlanarTrajectory& gt) {
    ErrorMetrics m;
    const std::vector<double> e = HorizontalErrors(traj, gt);
    m.poses = e.size();
    if (e.empty()) return m;
    double sq = 0.0, sum = 0.0, up_sq = 0.0;
    std::size_t on_floor = 0;
    for (std::size_t i = 0; i < e.size(); ++i) {
        sq += e[i] * e[i];
        sum += e[i];
        m.max_m = std::max(m.max_m, e[i]);
        const double up_error = traj.up_m[i] - gt.up_m[i];
        if (std::abs(up_error) <= 1.5) ++on_floor;
        up_sq += up_error * up_error;
    }
    m.vertical_rms_m = std::sqrt(up_sq / e.size());
    m.ate_m = std::sqrt(sq / e.size());
    m.mean_m = sum / e.size();
    m.final_m = e.back();
    std::vector<double> sorted = e;
    const std::size_t k =
        std::min(sorted.size() - 1, std::size_t(std::ceil(0.9 * sorted.size())) - 1);
    std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
    m.p90_m = sorted[k];
    m.floor_accuracy = double(on_floor) / e.size();
    const std::vector<double> dist = DistanceTravelled(gt);
    m.path_length_m = dist.back();
    m.drift_pct = KittiDrift(traj, gt, dist);
    return m;
}

}  // namespace driftcorr
