#pragma once
// The terms of the weighted negative log-likelihood (NLL). Each term is one small unit whose
// Evaluate returns its cost and, on request, the exact gradient and Hessian with respect to its
// local variables. A Gaussian term with residual r, standard deviation sigma and weight w in (0, 1]
// costs 0.5 * w * (r / sigma)^2 (docs/method.md, Eq. 1: the NLL of a Gaussian observation).
// The equation each term implements is cited at the term (docs/method.md, Eq. n).
//
// For the curvature of the NLL at a solution (optim/covariance.h) each term also linearises:
// Linearise returns its residual, the residual's Jacobian and a curvature weight (Linearisation).
//
// Step block layout (the variables a step term sees), poses a = i-1 and b = i:
//   [x_a, y_a, z_a, yaw_a, x_b, y_b, z_b, yaw_b, s]
// positions in the East-North-Up map frame [m], yaw CCW from East [rad], s the step-length scale.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <initializer_list>

namespace driftcorr {

using StepVector = Eigen::Matrix<double, 9, 1>;
using StepMatrix = Eigen::Matrix<double, 9, 9>;

/// A term linearised at a point, for the Gauss-Newton curvature of the NLL: residual r, its
/// Jacobian J = dr/dx over the term's variables, and a curvature weight `information` such that
/// information * J J^T (positive semi-definite) approximates the term's Hessian. What is dropped
/// is r times the residual's own Hessian and the derivative of a robust down-weighting, so the
/// approximation equals the exact Hessian where r = 0.
///  - Gaussian terms: information = w / sigma^2.
///  - Cauchy terms: the IRLS weight w / (sigma^2 (1 + (r / sigma)^2 / k^2)).
///  - The map distance term (r = d, J = grad d): max(rho''(d), 0).
/// `chi2` is the term's squared normalised residual as IRLS weighs it: information * r^2 for
/// Gaussian and Cauchy terms, w exp(-d^2 / (2 c^2)) (d / sigma)^2 for the map term; summed over
/// the terms it is twice the NLL of the Gaussian model those weights describe (a posteriori
/// variance factors).
template <int N>
struct Linearisation {
    double residual = 0.0;
    Eigen::Matrix<double, N, 1> jacobian = Eigen::Matrix<double, N, 1>::Zero();
    double information = 0.0;
    double chi2 = 0.0;
};

/// A term of one scalar residual r(x) under its loss rho (Gaussian or Cauchy), held as the pieces
/// its cost and derivatives are made of: g = rho'(r), a = rho''(r), J = dr/dx and Hr the
/// residual's own Hessian (has_hr: computed, when the Hessian was asked for and r is not linear),
///   cost = rho(r),  gradient = g J,  Hessian = a J J^T + g Hr.
/// A term's Evaluate returns these sums dense; a caller that needs a few entries of the Hessian
/// (optim's term blocks) takes them from the form.
template <int N>
struct ResidualForm {
    double r = 0.0;
    Eigen::Matrix<double, N, 1> j;
    Eigen::Matrix<double, N, N> hr;
    bool has_hr = false;
    double cost = 0.0, g = 0.0, a = 0.0;
    /// Hessian entry (row, col), the same sum as the dense Hessian's.
    double Hessian(int row, int col) const {
        const double h = (a * j[row]) * j[col];
        return has_hr ? h + g * hr(row, col) : h;
    }
};

enum StepVar : int { kXa = 0, kYa, kZa, kYawA, kXb, kYb, kZb, kYawB, kScale, kStepVars };

/// The variables a term's value depends on, one bit per variable (bit k: variable k). A term
/// that declares `kReads` computes its gradient and Hessian as exact zeros (+-0) outside them.
constexpr std::uint16_t ReadsOf(std::initializer_list<int> vars) {
    std::uint16_t bits = 0;
    for (int v : vars) bits = std::uint16_t(bits | (1u << v));
    return bits;
}

/// Step length along the observed step direction (docs/method.md, Eq. 4):
/// r = u(yaw_a + direction) . (p_b - p_a) - s * L.
/// Smooth at zero length, so stationary steps (L = 0) need no special case.
/// With robust_k > 0 the likelihood is heavy-tailed (Cauchy, width k sigmas; Eq. 2):
///   rho = w * k^2 / 2 * log(1 + (r / sigma)^2 / k^2),
/// so a step the odometry dropped (frame-to-frame registration returning ~0 while the platform
/// moved) is an outlier the other terms can overrule, instead of a hard pull to zero.
struct StepLengthTerm {
    static constexpr std::uint16_t kReads = ReadsOf({kXa, kYa, kYawA, kXb, kYb, kScale});
    double length_m, direction_rad, sigma_m, weight;
    double robust_k = 0.0;
    ResidualForm<9> Form(const StepVector& x, bool with_hessian) const;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
    Linearisation<9> Linearise(const StepVector& x) const;
};

/// Speed continuity over two consecutive steps (poses a, b, c; Eq. 10): the along-track speed
/// changes little from one step to the next, r = along_bc / dt_bc - along_ab / dt_ab [m/s],
/// Gaussian with sigma_mps. Variables
/// [x_a, y_a, z_a, yaw_a, x_b, y_b, z_b, yaw_b, x_c, y_c, z_c, yaw_c];
/// along_ab = u(yaw_a + direction_ab) . (p_b - p_a), likewise along_bc.
using SpeedVector = Eigen::Matrix<double, 12, 1>;
using SpeedMatrix = Eigen::Matrix<double, 12, 12>;
struct SpeedChangeTerm {
    static constexpr std::uint16_t kReads = ReadsOf({0, 1, 3, 4, 5, 7, 8, 9});
    double direction_ab_rad, dt_ab_s, direction_bc_rad, dt_bc_s, sigma_mps, weight;
    ResidualForm<12> Form(const SpeedVector& x, bool with_hessian) const;
    double Evaluate(const SpeedVector& x, SpeedVector* grad, SpeedMatrix* hess) const;
    Linearisation<12> Linearise(const SpeedVector& x) const;
};

/// Sideways motion relative to the observed step direction (Eq. 6):
/// r = n(yaw_a + direction) . (p_b - p_a),
/// n the left normal. Ties the heading variables to the direction the positions move in.
struct StepDirectionTerm {
    static constexpr std::uint16_t kReads = ReadsOf({kXa, kYa, kYawA, kXb, kYb});
    double direction_rad, sigma_m, weight;
    ResidualForm<9> Form(const StepVector& x, bool with_hessian) const;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
    Linearisation<9> Linearise(const StepVector& x) const;
};

/// Heading change (Eq. 7 without a bias): r = yaw_b - yaw_a - dheading (headings unwrapped).
struct HeadingChangeTerm {
    static constexpr std::uint16_t kReads = ReadsOf({kYawA, kYawB});
    double dheading_rad, sigma_rad, weight;
    ResidualForm<9> Form(const StepVector& x, bool with_hessian) const;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
    Linearisation<9> Linearise(const StepVector& x) const;
};

/// Heading change with a heading-rate bias (Eq. 7), variables [yaw_a, yaw_b, bias]:
/// r = yaw_b - yaw_a - dheading - bias * dt, bias [rad/s] the odometry's slowly varying heading
/// drift (one unknown per stretch of time, tied by a RandomWalkTerm), so a steady drift costs the
/// bias's prior once instead of every step's heading sigma.
struct HeadingChangeBiasTerm {
    double dheading_rad, dt_s, sigma_rad, weight;
    ResidualForm<3> Form(const Eigen::Vector3d& x, bool with_hessian) const;
    double Evaluate(const Eigen::Vector3d& x, Eigen::Vector3d* grad, Eigen::Matrix3d* hess) const;
    Linearisation<3> Linearise(const Eigen::Vector3d& x) const;
};

/// The plausible range of the step-length scale as a prior, not a cliff (Eq. 15): zero cost within
/// [min, max], Gaussian with sigma beyond it, r = s - max above, min - s below (continuous with
/// its gradient; the Hessian steps from 0 to w / sigma^2 at the ends).
using Vector1d = Eigen::Matrix<double, 1, 1>;
struct ScaleRangeTerm {
    double min, max, sigma, weight;
    ResidualForm<1> Form(const Vector1d& x, bool with_hessian) const;
    double Evaluate(const Vector1d& x, Vector1d* grad, Vector1d* hess) const;
    Linearisation<1> Linearise(const Vector1d& x) const;
};

/// Heading preservation prior (turns are small; Eq. 8): r = yaw_b - yaw_a.
struct HeadingPreservationTerm {
    static constexpr std::uint16_t kReads = ReadsOf({kYawA, kYawB});
    double sigma_rad, weight;
    ResidualForm<9> Form(const StepVector& x, bool with_hessian) const;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
    Linearisation<9> Linearise(const StepVector& x) const;
};

/// Height change (Eq. 9): r = z_b - z_a - dup.
struct HeightChangeTerm {
    static constexpr std::uint16_t kReads = ReadsOf({kZa, kZb});
    double dup_m, sigma_m, weight;
    ResidualForm<9> Form(const StepVector& x, bool with_hessian) const;
    double Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const;
    Linearisation<9> Linearise(const StepVector& x) const;
};

/// Random walk between consecutive segments of a slowly varying quantity (the step-length scale,
/// the heading-rate bias), variables [v_prev, v_next]: r = (v_next - v_prev) / sigma. With
/// robust_k > 0 the walk is heavy-tailed (Cauchy),
///   rho(r) = w * k^2 / 2 * log(1 + r^2 / k^2),
/// quadratic for |r| << k, so the scale of a steady odometry stays steady, but a jump that the map
/// supports (frame-to-frame ICP shortening its steps along a straight street) costs only
/// logarithmically. robust_k = 0: Gaussian, 0.5 * w * r^2. With v_prev held fixed at the prior's
/// mean it is the prior on the first segment (Eq. 13, 14, 16; a floor's pull, Eq. 17).
struct RandomWalkTerm {
    double sigma, weight;
    double robust_k = 0.0;
    ResidualForm<2> Form(const Eigen::Vector2d& x, bool with_hessian) const;
    double Evaluate(const Eigen::Vector2d& x, Eigen::Vector2d* grad, Eigen::Matrix2d* hess) const;
    Linearisation<2> Linearise(const Eigen::Vector2d& x) const;
};
struct ScalePriorTerm {
    double sigma, weight;
    double Evaluate(double s, double* grad, double* hess) const;
    Linearisation<1> Linearise(double s) const;
};

/// Map distance term on one pose: the distance d(p) to the nearest traversable centre should be
/// near zero (Gaussian with sigma_m), but a pose far from every road gives up: the cost saturates,
///   rho(d) = w * (c / sigma)^2 * (1 - exp(-d^2 / (2 c^2))),   c = giveup_m,
/// which is 0.5 * w * (d / sigma)^2 for d << c and flat (no pull) for d >> c (Eq. 3, 11; a lift
/// shaft's pull, Eq. 18).
/// The distance, its gradient and Hessian come from the map field at p (world ENU).
struct MapDistanceTerm {
    double sigma_m, giveup_m, weight;
    double Evaluate(double d, const Eigen::Vector3d& grad_d, const Eigen::Matrix3d& hess_d,
                    Eigen::Vector3d* grad, Eigen::Matrix3d* hess) const;
    /// r = d, J = grad_d (see Linearisation; the field's Hessian of d is not needed).
    Linearisation<3> Linearise(double d, const Eigen::Vector3d& grad_d) const;
};

/// Gaussian prior on one pose (Eq. 19), variables [x, y, z, yaw] (ENU [m], unwrapped yaw [rad]):
/// what the poses before a fixed-lag window say about its boundary pose once they are marginalised
/// (the Schur complement of their Gauss-Newton information onto that pose, optim/fixed_lag.h),
///   cost = 0.5 (x - mean)^T I (x - mean),
/// I symmetric positive semi-definite [1/m^2, 1/(m rad), 1/rad^2]; rows and columns of a variable
/// the prior says nothing about (a fixed height) are zero. Quadratic: the Hessian is I everywhere.
using PoseVector = Eigen::Matrix<double, 4, 1>;
using PoseMatrix = Eigen::Matrix<double, 4, 4>;
/// With scale_segment >= 0 the prior is joint with the step-length scale of that segment (the one
/// the boundary pose's step belongs to): variables [x, y, z, yaw, scale], mean (mean, scale_mean),
/// information [[information, cross], [cross^T, scale_information]] (JointInformation). The
/// scale's marginal then travels with the pose: a window that learns the scale was wrong can
/// move it, and the boundary with it along the track.
using JointVector = Eigen::Matrix<double, 5, 1>;
using JointMatrix = Eigen::Matrix<double, 5, 5>;
struct PosePriorTerm {
    PoseVector mean = PoseVector::Zero();
    PoseMatrix information = PoseMatrix::Zero();
    int scale_segment = -1;  ///< -1: a prior on the pose alone
    double scale_mean = 1.0;
    PoseVector cross = PoseVector::Zero();
    double scale_information = 0.0;

    bool HasScale() const { return scale_segment >= 0; }
    int Size() const { return HasScale() ? 5 : 4; }
    JointVector JointMean() const;
    JointMatrix JointInformation() const;
    /// Over the first Size() entries of x (the pose, then the scale when HasScale()).
    double Evaluate(const JointVector& x, JointVector* grad, JointMatrix* hess) const;
    /// I = V diag(lambda) V^T: one residual per eigenvector, r_k = v_k . (x - mean), with
    /// information max(lambda_k, 0); the sum of information_k J_k J_k^T is I (up to a negative
    /// eigenvalue from round-off, dropped). Size() entries; with a pose prior alone the fifth
    /// entry is empty (zero information) and its jacobians' fifth component zero.
    std::array<Linearisation<5>, 5> Linearise(const JointVector& x) const;
};

}  // namespace driftcorr
