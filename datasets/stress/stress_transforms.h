#pragma once
// The trajectory perturbations of the stress variants (see datasets/README.md, "Stress variants").
// Pure functions on trajectories in their own frame; no I/O.
//
// Conventions: pose i is T_frame_body(i) = (q_frame_body[i], p_frame[i]); step i (1 <= i < n) is
// the motion from pose i-1 to pose i, its relative pose T(i-1)^-1 T(i). "About Up" is a rotation
// about the frame's Up axis (FrameUpAxis: -y for kitti_camera, z for enu), counter-clockwise seen
// from above, i.e. the rotation R(angle) of the frame's horizontal (u, v) plane in frames.h.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "driftcorr/core/frames.h"
#include "driftcorr/core/types.h"
#include "synth_common.h"

namespace driftcorr::stress {

/// Uniform numbers of one seeded stream (the generators' shared sampler, bit-identical for a seed
/// everywhere). `stream` separates the variants, so that drawing more numbers in one variant
/// never changes another.
using UniformSource = synth::UniformSampler;
/// In [lo, hi], both included.
std::size_t IndexIn(UniformSource& random, std::size_t lo, std::size_t hi);

/// One stretch of consecutive steps whose translations are shortened.
struct DropEpisode {
    std::size_t first_step = 1;  ///< index of the first shortened step (>= 1)
    std::size_t steps = 0;       ///< number of consecutive shortened steps
    double ratio = 1.0;          ///< new length / old length of each of these steps
};

/// Parameters of the drop_steps variant; defaults written once here.
struct DropStepsConfig {
    std::size_t min_episodes = 5;  ///< seeded count in [min_episodes, max_episodes] ...
    std::size_t max_episodes = 20;
    std::size_t min_steps = 15;  ///< ... each of [min_steps, max_steps] consecutive steps ...
    std::size_t max_steps = 25;
    double min_ratio = 0.2;  ///< ... shortened to a ratio in [min_ratio, max_ratio)
    double max_ratio = 0.6;
    /// The count is lowered until count * max_steps <= max_share * (number of steps).
    double max_share = 0.2;
    /// Empty when valid, else the name of the bad field and why.
    std::string Validate() const;
};

/// Seeded, non-overlapping episodes for a trajectory of `poses` poses: the steps are cut into
/// `count` equal segments and one episode is placed at a random offset inside each. Returns an
/// empty list when not even one episode fits (fewer than max_steps / max_share steps).
std::vector<DropEpisode> PlanDropEpisodes(std::size_t poses, const DropStepsConfig& config,
                                          UniformSource& random);

/// Re-integrates the trajectory from its relative poses with the translation of every step
/// inside an episode multiplied by the episode's ratio; relative rotations are unchanged, so the
/// orientations stay those of the input, and every pose after an episode is shifted by what the
/// episode lost (as after a real odometry failure). Pose 0 is unchanged.
Trajectory ShortenSteps(const Trajectory& traj, const std::vector<DropEpisode>& episodes);

/// A steady heading-rate bias: the relative motion of each step is turned about Up by the
/// accumulated bias psi(t) = bias_rad_per_s * (t - t_0) and re-integrated:
///   q'_i = R_up(psi_i) q_i,   p'_i = p'_{i-1} + R_up(psi_{i-1}) (p_i - p_{i-1}),
/// i.e. each step keeps its body-frame translation, and its relative rotation gains
/// bias * (t_i - t_{i-1}) about Up. The heading of pose i is therefore off by exactly psi_i.
Trajectory ApplyHeadingBias(const Trajectory& traj, FrameAxes axes, double bias_rad_per_s);

/// A monocular tracker's trajectory: each step's translation multiplied by
///   s_i = global_scale * exp(w_i),   w_i = w_{i-1} + drift_per_100m * sqrt(L_i / 100 m) * n_i,
/// with L_i the step's length and n_i standard normal (w_0 = 0), and the poses re-integrated from
/// global_scale * p_0; orientations unchanged. `scales`, when given, receives s_i (index 0: the
/// global scale).
Trajectory ScaleLikeMonocular(const Trajectory& traj, double global_scale, double drift_per_100m,
                              synth::NormalSampler& normal, std::vector<double>* scales = nullptr);

/// Every pose turned about Up by angle_rad about the frame's origin (positions and orientations).
Trajectory RotateAboutUp(const Trajectory& traj, FrameAxes axes, double angle_rad);

/// Every position moved by `delta_uv` in the frame's horizontal (u, v) plane; heights and
/// orientations unchanged.
Trajectory TranslateHorizontal(const Trajectory& traj, FrameAxes axes,
                               const Eigen::Vector2d& delta_uv);

/// The rotation about the frame's Up axis by angle_rad.
Eigen::Quaterniond UpRotation(FrameAxes axes, double angle_rad);

}  // namespace driftcorr::stress
