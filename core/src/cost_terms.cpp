#include "driftcorr/core/cost_terms.h"

#include <cmath>

namespace driftcorr {
namespace {

// Accumulates 0.5 * w * (r / sigma)^2 given r, its gradient J and Hessian Hr.
template <int N>
double Gaussian(double r, const Eigen::Matrix<double, N, 1>& j,
                const Eigen::Matrix<double, N, N>* hr, double sigma, double weight,
                Eigen::Matrix<double, N, 1>* grad, Eigen::Matrix<double, N, N>* hess) {
    const double k = weight / (sigma * sigma);
    if (grad) *grad = k * r * j;
    if (hess) {
        *hess = k * j * j.transpose();
        if (hr) *hess += k * r * (*hr);
    }
    return 0.5 * k * r * r;
}

// Displacement and direction angle of a step block.
struct StepGeometry {
    double dx, dy, c, s;
};

StepGeometry Geometry(const StepVector& x, double direction_rad) {
    const double phi = x[kYawA] + direction_rad;
    return {x[kXb] - x[kXa], x[kYb] - x[kYa], std::cos(phi), std::sin(phi)};
}

double LinearYawDifference(const StepVector& x, double offset, double sigma, double weight,
                           StepVector* grad, StepMatrix* hess) {
    StepVector j = StepVector::Zero();
    j[kYawB] = 1.0;
    j[kYawA] = -1.0;
    return Gaussian<9>(x[kYawB] - x[kYawA] - offset, j, nullptr, sigma, weight, grad, hess);
}

}  // namespace

double StepLengthTerm::Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const {
    const StepGeometry g = Geometry(x, direction_rad);
    const double along = g.c * g.dx + g.s * g.dy;  // projection of the displacement
    const double side = -g.s * g.dx + g.c * g.dy;
    const double r = along - x[kScale] * length_m;
    StepVector j = StepVector::Zero();
    j[kXa] = -g.c, j[kYa] = -g.s, j[kXb] = g.c, j[kYb] = g.s;
    j[kYawA] = side;
    j[kScale] = -length_m;
    StepMatrix hr = StepMatrix::Zero();
    // d2 along / d yaw_a^2 = -along; d2 along / d yaw_a d(x_b, y_b) = (-s, c) = -(d2/d(x_a, y_a)).
    hr(kYawA, kYawA) = -along;
    hr(kYawA, kXb) = hr(kXb, kYawA) = -g.s;
    hr(kYawA, kYb) = hr(kYb, kYawA) = g.c;
    hr(kYawA, kXa) = hr(kXa, kYawA) = g.s;
    hr(kYawA, kYa) = hr(kYa, kYawA) = -g.c;
    return Gaussian<9>(r, j, &hr, sigma_m, weight, grad, hess);
}

double StepDirectionTerm::Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const {
    const StepGeometry g = Geometry(x, direction_rad);
    const double along = g.c * g.dx + g.s * g.dy;
    const double r = -g.s * g.dx + g.c * g.dy;
    StepVector j = StepVector::Zero();
    j[kXa] = g.s, j[kYa] = -g.c, j[kXb] = -g.s, j[kYb] = g.c;
    j[kYawA] = -along;
    StepMatrix hr = StepMatrix::Zero();
    hr(kYawA, kYawA) = -r;
    hr(kYawA, kXb) = hr(kXb, kYawA) = -g.c;
    hr(kYawA, kYb) = hr(kYb, kYawA) = -g.s;
    hr(kYawA, kXa) = hr(kXa, kYawA) = g.c;
    hr(kYawA, kYa) = hr(kYa, kYawA) = g.s;
    return Gaussian<9>(r, j, &hr, sigma_m, weight, grad, hess);
}

double HeadingChangeTerm::Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const {
    return LinearYawDifference(x, dheading_rad, sigma_rad, weight, grad, hess);
}

double HeadingPreservationTerm::Evaluate(const StepVector& x, StepVector* grad,
                                         StepMatrix* hess) const {
    return LinearYawDifference(x, 0.0, sigma_rad, weight, grad, hess);
}

double HeightChangeTerm::Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const {
    StepVector j = StepVector::Zero();
    j[kZb] = 1.0;
    j[kZa] = -1.0;
    return Gaussian<9>(x[kZb] - x[kZa] - dup_m, j, nullptr, sigma_m, weight, grad, hess);
}

double ScaleRandomWalkTerm::Evaluate(const Eigen::Vector2d& x, Eigen::Vector2d* grad,
                                     Eigen::Matrix2d* hess) const {
    const Eigen::Vector2d j(-1.0, 1.0);
    if (robust_k <= 0.0) return Gaussian<2>(x[1] - x[0], j, nullptr, sigma, weight, grad, hess);
    const double r = (x[1] - x[0]) / sigma, k2 = robust_k * robust_k;
    const double q = 1.0 + r * r / k2;
    const double rho_r = weight * r / q;                         // d rho / d r
    const double rho_rr = weight * (1.0 - r * r / k2) / (q * q);  // d2 rho / d r2
    if (grad) *grad = (rho_r / sigma) * j;
    if (hess) *hess = (rho_rr / (sigma * sigma)) * j * j.transpose();
    return 0.5 * weight * k2 * std::log(q);
}

double ScalePriorTerm::Evaluate(double s, double* grad, double* hess) const {
    const double k = weight / (sigma * sigma);
    if (grad) *grad = k * (s - 1.0);
    if (hess) *hess = k;
    return 0.5 * k * (s - 1.0) * (s - 1.0);
}

double MapDistanceTerm::Evaluate(double d, const Eigen::Vector3d& grad_d,
                                 const Eigen::Matrix3d& hess_d, Eigen::Vector3d* grad,
                                 Eigen::Matrix3d* hess) const {
    const double c2 = giveup_m * giveup_m;
    const double k = weight / (sigma_m * sigma_m);
    const double e = std::exp(-d * d / (2.0 * c2));
    const double rho_d = k * d * e;                         // d rho / d d
    const double rho_dd = k * e * (1.0 - d * d / c2);       // d2 rho / d d2
    if (grad) *grad = rho_d * grad_d;
    if (hess) *hess = rho_dd * grad_d * grad_d.transpose() + rho_d * hess_d;
    return k * c2 * (1.0 - e);
}

}  // namespace driftcorr
