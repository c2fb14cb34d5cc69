#pragma once
// The terms of the weighted negative log-likelihood (NLL). Each term is one small unit whose
// Evaluate returns its cost and, on request, the exact gradient and Hessian with respect to its
// local variables. A Gaussian term with residual r, standard deviation sigma and weight w in (0, 1]
// costs 0.5 * w * (r / sigma)^2 (Eq. 1 of our method notes: the NLL of a Gaussian observation).
//
// Step block layout (the variables a step term sees), poses a = i-1 and b = i:
//   [x_a, y_a, z_a, yaw_a, x_b, y_b, z_b, yaw_b, s]
// positions in the East-North-Up map frame [m], yaw CCW from East [rad], s the step-length scale.
#include <Eigen/Core>

namespace driftcorr {

using StepVector = Eigen::Matrix<double, 9, 1>;
using StepMatrix = Eigen::Matrix<double, 9, 9>;

enum StepVar : int { kXa = 0, kYa, kZa, kYawA, kXb, kYb, kZb, kYawB, kScale, kStepVars };

/// Step length along the observed step direction: r = u(yaw_a + direction) . (p_b - p_a) - s * L.
/// Smooth at zero length, so stationary steps (L = 0) need no special case.
/// With robust_k > 0 the likelihood is heavy-tailed (Cauchy, width k sigmas):
///   rho = w * k^2 / 2 * log(1 + (r / sigma)^2 / k^2),
/// so a step the odometry dropped (frame-to-frame registration returning ~0 while the platform
/// moved) is an outlier the other terms can overrule, instead of a hard pull to zero.
struct StepLengthTerm {
    double length_m, direction_rad, sigma_m, weight;
    double robust_k = 0.0;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
};

/// Speed continuity over two consecutive steps (poses a, b, c): the along-track speed changes
/// little from one step to the next, r = along_bc / dt_bc - along_ab / dt_ab [m/s], Gaussian
/// with sigma_mps. Variables [x_a, y_a, z_a, yaw_a, x_b, y_b, z_b, yaw_b, x_c, y_c, z_c, yaw_c];
/// along_ab = u(yaw_a + direction_ab) . (p_b - p_a), likewise along_bc.
using SpeedVector = Eigen::Matrix<double, 12, 1>;
using SpeedMatrix = Eigen::Matrix<double, 12, 12>;
struct SpeedChangeTerm {
    double direction_ab_rad, dt_ab_s, direction_bc_rad, dt_bc_s, sigma_mps, weight;
    double Evaluate(const SpeedVector& x, SpeedVector* grad, SpeedMatrix* hess) const;
};

/// Sideways motion relative to the observed step direction: r = n(yaw_a + direction) . (p_b - p_a),
/// n the left normal. Ties the heading variables to the direction the positions move in.
struct StepDirectionTerm {
    double direction_rad, sigma_m, weight;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
};

/// Heading change: r = yaw_b - yaw_a - dheading (headings unwrapped).
struct HeadingChangeTerm {
    double dheading_rad, sigma_rad, weight;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
};

/// Heading preservation prior (turns are small): r = yaw_b - yaw_a.
struct HeadingPreservationTerm {
    double sigma_rad, weight;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
};

/// Height change: r = z_b - z_a - dup.
struct HeightChangeTerm {
    double dup_m, sigma_m, weight;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
};

/// Scale random walk between consecutive scale segments, variables [s_prev, s_next]:
/// r = (s_next - s_prev) / sigma. With robust_k > 0 the walk is heavy-tailed (Cauchy),
///   rho(r) = w * k^2 / 2 * log(1 + r^2 / k^2),
/// quadratic for |r| << k, so the scale of a steady odometry stays steady, but a jump that the map
/// supports (frame-to-frame ICP shortening its steps along a straight street) costs only
/// logarithmically. robust_k = 0: Gaussian, 0.5 * w * r^2. And the prior on the first segment's
/// scale, r = s - 1.
struct ScaleRandomWalkTerm {
    double sigma, weight;
    double robust_k = 0.0;
    double Evaluate(const Eigen::Vector2d& x, Eigen::Vector2d* grad, Eigen::Matrix2d* hess) const;
};
struct ScalePriorTerm {
    double sigma, weight;
    double Evaluate(double s, double* grad, double* hess) const;
};

/// Map distance term on one pose: the distance d(p) to the nearest traversable centre should be
/// near zero (Gaussian with sigma_m), but a pose far from every road gives up: the cost saturates,
///   rho(d) = w * (c / sigma)^2 * (1 - exp(-d^2 / (2 c^2))),   c = giveup_m,
/// which is 0.5 * w * (d / sigma)^2 for d << c and flat (no pull) for d >> c.
/// The distance, its gradient and Hessian come from the map field at p (world ENU).
struct MapDistanceTerm {
    double sigma_m, giveup_m, weight;
    double Evaluate(double d, const Eigen::Vector3d& grad_d, const Eigen::Matrix3d& hess_d,
                    Eigen::Vector3d* grad, Eigen::Matrix3d* hess) const;
};

}  // namespace driftcorr
