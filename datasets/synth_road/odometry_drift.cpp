// The definitions of what odometry_drift.h declares.
#include "odometry_drift.h"

#include <cmath>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"

namespace driftcorr::synth {

std::string DriftConfig::Validate() const {
    if (!(heading_bias_deg_per_sqrt_s >= 0.0 && heading_bias_deg_per_sqrt_s <= 1.0)) {
        return "heading_bias_deg_per_sqrt_s: must be in [0, 1]";
    }
    if (!(scale_error >= 0.5 && scale_error <= 1.5)) return "scale_error: must be in [0.5, 1.5]";
    if (!(step_noise_rel >= 0.0 && step_noise_rel <= 0.2)) {
        return "step_noise_rel: must be in [0, 0.2]";
    }
    if (!(heading_noise_deg >= 0.0 && heading_noise_deg <= 5.0)) {
        return "heading_noise_deg: must be in [0, 5]";
    }
    return "";
}

std::vector<DrivePose> IntegrateDriftingOdometry(const std::vector<DrivePose>& ground_truth,
                                                 const DriftConfig& config) {
    DRIFTCORR_CHECK(config.Validate().empty() && !ground_truth.empty(),
                    "IntegrateDriftingOdometry: invalid config or empty input");
    NormalSampler normal(config.seed);
    std::vector<DrivePose> estimate = {ground_truth.front()};
    double bias_deg_per_s = 0.0;
    for (std::size_t k = 0; k + 1 < ground_truth.size(); ++k) {
        const DrivePose& a = ground_truth[k];
        const DrivePose& b = ground_truth[k + 1];
        const double dt_s = b.t_s - a.t_s;
        const Eigen::Vector2d step_body = Rotate(-a.yaw_rad, b.p_en - a.p_en);
        // Three draws every step, moving or not, so the noise stream stays aligned with time.
        const double n_bias = normal.Next(), n_step = normal.Next(), n_heading = normal.Next();
        bias_deg_per_s += config.heading_bias_deg_per_sqrt_s * std::sqrt(dt_s) * n_bias;
        DrivePose next = estimate.back();
        next.t_s = b.t_s;
        if (step_body.squaredNorm() > 0.0) {
            const double scale = config.scale_error * (1.0 + config.step_noise_rel * n_step);
            const double heading_error_deg =
                bias_deg_per_s * dt_s + config.heading_noise_deg * n_heading;
            next.p_en += scale * Rotate(next.yaw_rad, step_body);
            next.yaw_rad += DegToRad(heading_error_deg);
        }
        next.yaw_rad += b.yaw_rad - a.yaw_rad;
        estimate.push_back(next);
    }
    return estimate;
}

}  // namespace driftcorr::synth
