// The definitions of what stress_transforms.h declares.
#include "stress_transforms.h"

#include <algorithm>
#include <cmath>

#include "driftcorr/core/check.h"

namespace driftcorr::stress {

std::size_t IndexIn(UniformSource& random, std::size_t lo, std::size_t hi) {
    DRIFTCORR_CHECK(lo <= hi, "empty interval");
    return lo + random.Index(hi - lo + 1);
}

std::string DropStepsConfig::Validate() const {
    if (min_episodes < 1 || min_episodes > max_episodes) {
        return "min_episodes/max_episodes: need 1 <= min <= max";
    }
    if (min_steps < 1 || min_steps > max_steps) return "min_steps/max_steps: need 1 <= min <= max";
    if (!(min_ratio >= 0.0 && min_ratio <= max_ratio && max_ratio <= 1.0)) {
        return "min_ratio/max_ratio: need 0 <= min <= max <= 1";
    }
    if (!(max_share > 0.0 && max_share <= 1.0)) return "max_share: must be in (0, 1]";
    return "";
}

std::vector<DropEpisode> PlanDropEpisodes(std::size_t poses, const DropStepsConfig& config,
                                          UniformSource& random) {
    DRIFTCORR_CHECK(config.Validate().empty(), "invalid DropStepsConfig");
    const std::size_t steps = poses > 1 ? poses - 1 : 0;
    const auto fits = static_cast<std::size_t>(std::floor(
        config.max_share * static_cast<double>(steps) / static_cast<double>(config.max_steps)));
    const std::size_t count =
        std::min(IndexIn(random, config.min_episodes, config.max_episodes), fits);
    std::vector<DropEpisode> episodes;
    if (count == 0) return episodes;
    // Segment k holds steps [1 + k * steps / count, 1 + (k + 1) * steps / count); it is at least
    // max_steps / max_share >= max_steps long, so an episode always fits inside it.
    for (std::size_t k = 0; k < count; ++k) {
        const std::size_t begin = 1 + k * steps / count;
        const std::size_t end = 1 + (k + 1) * steps / count;
        DropEpisode e;
        e.steps = IndexIn(random, config.min_steps, config.max_steps);
        e.first_step = IndexIn(random, begin, end - e.steps);
        e.ratio = random.Range(config.min_ratio, config.max_ratio);
        episodes.push_back(e);
    }
    return episodes;
}

Trajectory ShortenSteps(const Trajectory& traj, const std::vector<DropEpisode>& episodes) {
    std::vector<double> ratio(traj.size(), 1.0);
    for (const DropEpisode& e : episodes) {
        DRIFTCORR_CHECK(e.first_step >= 1 && e.first_step + e.steps <= traj.size(),
                        "episode off the trajectory");
        std::fill_n(ratio.begin() + static_cast<std::ptrdiff_t>(e.first_step), e.steps, e.ratio);
    }
    Trajectory out = traj;
    for (std::size_t i = 1; i < traj.size(); ++i) {
        const Eigen::Vector3d step_frame = traj.p_frame[i] - traj.p_frame[i - 1];
        if (!traj.HasOrientation()) {
            out.p_frame[i] = out.p_frame[i - 1] + ratio[i] * step_frame;
            continue;
        }
        // Relative pose of step i: rotation q_rel, translation t_rel (in body i-1).
        const Eigen::Quaterniond q_prev_inv = traj.q_frame_body[i - 1].conjugate();
        const Eigen::Quaterniond q_rel = q_prev_inv * traj.q_frame_body[i];
        const Eigen::Vector3d t_rel = q_prev_inv * step_frame;
        out.p_frame[i] = out.p_frame[i - 1] + out.q_frame_body[i - 1] * (ratio[i] * t_rel);
        out.q_frame_body[i] = (out.q_frame_body[i - 1] * q_rel).normalized();
    }
    return out;
}

Eigen::Quaterniond UpRotation(FrameAxes axes, double angle_rad) {
    return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, FrameUpAxis(axes)));
}

Trajectory ApplyHeadingBias(const Trajectory& traj, FrameAxes axes, double bias_rad_per_s) {
    Trajectory out = traj;
    if (traj.size() == 0) return out;
    const auto psi_rad = [&](std::size_t i) {
        return bias_rad_per_s * (traj.t_s[i] - traj.t_s[0]);
    };
    for (std::size_t i = 1; i < traj.size(); ++i) {
        const Eigen::Vector3d step_frame = traj.p_frame[i] - traj.p_frame[i - 1];
        out.p_frame[i] = out.p_frame[i - 1] + UpRotation(axes, psi_rad(i - 1)) * step_frame;
    }
    if (traj.HasOrientation()) {
        for (std::size_t i = 0; i < traj.size(); ++i) {
            out.q_frame_body[i] =
                (UpRotation(axes, psi_rad(i)) * traj.q_frame_body[i]).normalized();
        }
    }
    return out;
}

Trajectory ScaleLikeMonocular(const Trajectory& traj, double global_scale, double drift_per_100m,
                              synth::NormalSampler& normal, std::vector<double>* scales) {
    Trajectory out = traj;
    if (scales) scales->assign(traj.size(), global_scale);
    if (traj.size() == 0) return out;
    out.p_frame[0] = global_scale * traj.p_frame[0];
    double w = 0.0;
    for (std::size_t i = 1; i < traj.size(); ++i) {
        const Eigen::Vector3d step = traj.p_frame[i] - traj.p_frame[i - 1];
        w += drift_per_100m * std::sqrt(step.norm() / 100.0) * normal.Next();
        const double s = global_scale * std::exp(w);
        out.p_frame[i] = out.p_frame[i - 1] + s * step;
        if (scales) (*scales)[i] = s;
    }
    return out;
}

Trajectory RotateAboutUp(const Trajectory& traj, FrameAxes axes, double angle_rad) {
    const Eigen::Quaterniond r = UpRotation(axes, angle_rad);
    Trajectory out = traj;
    for (std::size_t i = 0; i < traj.size(); ++i) {
        out.p_frame[i] = r * traj.p_frame[i];
        if (traj.HasOrientation()) out.q_frame_body[i] = (r * traj.q_frame_body[i]).normalized();
    }
    return out;
}

Trajectory TranslateHorizontal(const Trajectory& traj, FrameAxes axes,
                               const Eigen::Vector2d& delta_uv) {
    const Eigen::Vector3d delta_frame =
        UvhToFrame(axes, Eigen::Vector3d(delta_uv.x(), delta_uv.y(), 0));
    Trajectory out = traj;
    for (Eigen::Vector3d& p : out.p_frame) p += delta_frame;
    return out;
}

}  // namespace driftcorr::stress
