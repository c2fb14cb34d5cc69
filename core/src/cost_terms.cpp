// The definitions of what driftcorr/core/cost_terms.h declares.
#include "driftcorr/core/cost_terms.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace driftcorr {
namespace {

// The loss of a Gaussian term on the form's residual: 0.5 * w * (r / sigma)^2.
template <int N>
void GaussianLoss(double sigma, double weight, ResidualForm<N>& f) {
    const double k = weight / (sigma * sigma);
    f.g = k * f.r;
    f.a = k;
    f.cost = 0.5 * k * f.r * f.r;
}

// The loss of a Cauchy term on the form's residual: w * k^2 / 2 * log(1 + (r / sigma)^2 / k^2).
template <int N>
void CauchyLoss(double sigma, double k, double weight, ResidualForm<N>& f) {
    const double z = f.r / sigma, k2 = k * k, q = 1.0 + z * z / k2;
    const double rho_z = weight * z / q;                          // d rho / d z
    const double rho_zz = weight * (1.0 - z * z / k2) / (q * q);  // d2 rho / d z2
    f.g = rho_z / sigma;
    f.a = rho_zz / (sigma * sigma);
    f.cost = 0.5 * weight * k2 * std::log(q);
}

// The form's cost, with its gradient and Hessian dense on request.
template <int N>
double Dense(const ResidualForm<N>& f, Eigen::Matrix<double, N, 1>* grad,
             Eigen::Matrix<double, N, N>* hess) {
    if (grad) *grad = f.g * f.j;
    if (hess) {
        *hess = f.a * f.j * f.j.transpose();
        if (f.has_hr) *hess += f.g * f.hr;
    }
    return f.cost;
}

// A linear residual r = x[b] - x[a] - offset over N variables.
template <int N>
ResidualForm<N> Difference(const Eigen::Matrix<double, N, 1>& x, int a, int b, double offset) {
    ResidualForm<N> f;
    f.r = x[b] - x[a] - offset;
    f.j.setZero();
    f.j[b] = 1.0;
    f.j[a] = -1.0;
    return f;
}

// The Gauss-Newton linearisation of a Gaussian term (see Linearisation).
template <int N>
Linearisation<N> LinearGaussian(double r, const Eigen::Matrix<double, N, 1>& j, double sigma,
                                double weight) {
    const double k = weight / (sigma * sigma);
    return {r, j, k, k * r * r};
}

// The IRLS linearisation of a Cauchy term: the weight rho'(z) / z of the normalised residual z.
template <int N>
Linearisation<N> LinearCauchy(double r, const Eigen::Matrix<double, N, 1>& j, double sigma,
                              double k, double weight) {
    const double z = r / sigma, q = 1.0 + z * z / (k * k);
    const double info = weight / (q * sigma * sigma);
    return {r, j, info, info * r * r};
}

// Displacement and direction angle of a step block.
struct StepGeometry {
    double dx, dy, c, s;
};

StepGeometry Geometry(const StepVector& x, double direction_rad) {
    const double phi = x[kYawA] + direction_rad;
    return {x[kXb] - x[kXa], x[kYb] - x[kYa], std::cos(phi), std::sin(phi)};
}

// The step's residual with its Jacobian J and, when asked for, its Hessian Hr.
ResidualForm<9> StepLengthResidual(const StepVector& x, double length_m, double direction_rad,
                                   bool with_hr) {
    const StepGeometry g = Geometry(x, direction_rad);
    const double along = g.c * g.dx + g.s * g.dy;  // projection of the displacement
    const double side = -g.s * g.dx + g.c * g.dy;
    ResidualForm<9> res;
    res.r = along - x[kScale] * length_m;
    StepVector& j = res.j;
    j.setZero();
    j[kXa] = -g.c, j[kYa] = -g.s, j[kXb] = g.c, j[kYb] = g.s;
    j[kYawA] = side;
    j[kScale] = -length_m;
    if (!with_hr) return res;
    res.has_hr = true;
    StepMatrix& hr = res.hr;
    hr.setZero();
    // d2 along / d yaw_a^2 = -along; d2 along / d yaw_a d(x_b, y_b) = (-s, c) = -(d2/d(x_a, y_a)).
    hr(kYawA, kYawA) = -along;
    hr(kYawA, kXb) = hr(kXb, kYawA) = -g.s;
    hr(kYawA, kYb) = hr(kYb, kYawA) = g.c;
    hr(kYawA, kXa) = hr(kXa, kYawA) = g.s;
    hr(kYawA, kYa) = hr(kYa, kYawA) = -g.c;
    return res;
}

ResidualForm<9> StepDirectionResidual(const StepVector& x, double direction_rad, bool with_hr) {
    const StepGeometry g = Geometry(x, direction_rad);
    const double along = g.c * g.dx + g.s * g.dy;
    ResidualForm<9> res;
    res.r = -g.s * g.dx + g.c * g.dy;
    StepVector& j = res.j;
    j.setZero();
    j[kXa] = g.s, j[kYa] = -g.c, j[kXb] = -g.s, j[kYb] = g.c;
    j[kYawA] = -along;
    if (!with_hr) return res;
    res.has_hr = true;
    StepMatrix& hr = res.hr;
    hr.setZero();
    hr(kYawA, kYawA) = -res.r;
    hr(kYawA, kXb) = hr(kXb, kYawA) = -g.c;
    hr(kYawA, kYb) = hr(kYb, kYawA) = -g.s;
    hr(kYawA, kXa) = hr(kXa, kYawA) = g.c;
    hr(kYawA, kYa) = hr(kYa, kYawA) = g.s;
    return res;
}

// r = v[b] - v[a] - offset, linear.
Linearisation<9> LinearDifference(const StepVector& x, int a, int b, double offset, double sigma,
                                  double weight) {
    const ResidualForm<9> f = Difference(x, a, b, offset);
    return LinearGaussian<9>(f.r, f.j, sigma, weight);
}

}  // namespace

ResidualForm<9> StepLengthTerm::Form(const StepVector& x, bool with_hessian) const {
    ResidualForm<9> f = StepLengthResidual(x, length_m, direction_rad, with_hessian);
    if (robust_k <= 0.0) {
        GaussianLoss(sigma_m, weight, f);
    } else {
        CauchyLoss(sigma_m, robust_k, weight, f);
    }
    return f;
}

double StepLengthTerm::Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<9> StepLengthTerm::Linearise(const StepVector& x) const {
    const ResidualForm<9> res = StepLengthResidual(x, length_m, direction_rad, false);
    if (robust_k <= 0.0) return LinearGaussian<9>(res.r, res.j, sigma_m, weight);
    return LinearCauchy<9>(res.r, res.j, sigma_m, robust_k, weight);
}

namespace {

// Along-track displacement of one step, with gradient and Hessian over 8 variables
// [x_a, y_a, z_a, yaw_a, x_b, y_b, z_b, yaw_b] (only x, y, yaw_a enter).
struct Along {
    double value;
    Eigen::Matrix<double, 8, 1> j;
    Eigen::Matrix<double, 8, 8> h;
};

Along AlongTrack(const double* v, double direction_rad) {
    const double phi = v[3] + direction_rad, c = std::cos(phi), s = std::sin(phi);
    const double dx = v[4] - v[0], dy = v[5] - v[1];
    Along a;
    a.value = c * dx + s * dy;
    const double side = -s * dx + c * dy;
    a.j.setZero();
    a.j[0] = -c, a.j[1] = -s, a.j[4] = c, a.j[5] = s, a.j[3] = side;
    a.h.setZero();
    a.h(3, 3) = -a.value;
    a.h(3, 4) = a.h(4, 3) = -s;
    a.h(3, 5) = a.h(5, 3) = c;
    a.h(3, 0) = a.h(0, 3) = s;
    a.h(3, 1) = a.h(1, 3) = -c;
    return a;
}

// r = along_bc / dt_bc - along_ab / dt_ab with its Jacobian and Hessian.
void SpeedResidual(const SpeedChangeTerm& t, const SpeedVector& x, double* r, SpeedVector* j,
                   SpeedMatrix* hr) {
    const Along ab = AlongTrack(x.data(), t.direction_ab_rad);
    const Along bc = AlongTrack(x.data() + 4, t.direction_bc_rad);
    *r = bc.value / t.dt_bc_s - ab.value / t.dt_ab_s;
    j->setZero();
    j->segment<8>(0) -= ab.j / t.dt_ab_s;
    j->segment<8>(4) += bc.j / t.dt_bc_s;
    if (!hr) return;
    hr->setZero();
    hr->block<8, 8>(0, 0) -= ab.h / t.dt_ab_s;
    hr->block<8, 8>(4, 4) += bc.h / t.dt_bc_s;
}

}  // namespace

ResidualForm<12> SpeedChangeTerm::Form(const SpeedVector& x, bool with_hessian) const {
    ResidualForm<12> f;
    SpeedResidual(*this, x, &f.r, &f.j, with_hessian ? &f.hr : nullptr);
    f.has_hr = with_hessian;
    GaussianLoss(sigma_mps, weight, f);
    return f;
}

double SpeedChangeTerm::Evaluate(const SpeedVector& x, SpeedVector* grad, SpeedMatrix* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<12> SpeedChangeTerm::Linearise(const SpeedVector& x) const {
    const ResidualForm<12> f = Form(x, false);
    return LinearGaussian<12>(f.r, f.j, sigma_mps, weight);
}

ResidualForm<9> StepDirectionTerm::Form(const StepVector& x, bool with_hessian) const {
    ResidualForm<9> f = StepDirectionResidual(x, direction_rad, with_hessian);
    GaussianLoss(sigma_m, weight, f);
    return f;
}

double StepDirectionTerm::Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<9> StepDirectionTerm::Linearise(const StepVector& x) const {
    const ResidualForm<9> res = StepDirectionResidual(x, direction_rad, false);
    return LinearGaussian<9>(res.r, res.j, sigma_m, weight);
}

ResidualForm<9> HeadingChangeTerm::Form(const StepVector& x, bool) const {
    ResidualForm<9> f = Difference(x, kYawA, kYawB, dheading_rad);
    GaussianLoss(sigma_rad, weight, f);
    return f;
}

double HeadingChangeTerm::Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<9> HeadingChangeTerm::Linearise(const StepVector& x) const {
    return LinearDifference(x, kYawA, kYawB, dheading_rad, sigma_rad, weight);
}

ResidualForm<3> HeadingChangeBiasTerm::Form(const Eigen::Vector3d& x, bool) const {
    ResidualForm<3> f;
    f.r = x[1] - x[0] - dheading_rad - x[2] * dt_s;
    f.j = Eigen::Vector3d(-1.0, 1.0, -dt_s);
    GaussianLoss(sigma_rad, weight, f);
    return f;
}

double HeadingChangeBiasTerm::Evaluate(const Eigen::Vector3d& x, Eigen::Vector3d* grad,
                                       Eigen::Matrix3d* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<3> HeadingChangeBiasTerm::Linearise(const Eigen::Vector3d& x) const {
    const ResidualForm<3> f = Form(x, false);
    return LinearGaussian<3>(f.r, f.j, sigma_rad, weight);
}

// Outside the range: r and dr/ds = +-1; inside: r = 0, dr/ds = 0.
ResidualForm<1> ScaleRangeTerm::Form(const Vector1d& x, bool) const {
    const double s = x[0];
    ResidualForm<1> f;
    f.r = s > max ? s - max : (s < min ? min - s : 0.0);
    f.j = Vector1d(s > max ? 1.0 : (s < min ? -1.0 : 0.0));
    GaussianLoss(sigma, weight, f);
    return f;
}

double ScaleRangeTerm::Evaluate(const Vector1d& x, Vector1d* grad, Vector1d* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<1> ScaleRangeTerm::Linearise(const Vector1d& x) const {
    const ResidualForm<1> f = Form(x, false);
    return LinearGaussian<1>(f.r, f.j, sigma, weight);
}

ResidualForm<9> HeadingPreservationTerm::Form(const StepVector& x, bool) const {
    ResidualForm<9> f = Difference(x, kYawA, kYawB, 0.0);
    GaussianLoss(sigma_rad, weight, f);
    return f;
}

double HeadingPreservationTerm::Evaluate(const StepVector& x, StepVector* grad,
                                         StepMatrix* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<9> HeadingPreservationTerm::Linearise(const StepVector& x) const {
    return LinearDifference(x, kYawA, kYawB, 0.0, sigma_rad, weight);
}

ResidualForm<9> HeightChangeTerm::Form(const StepVector& x, bool) const {
    ResidualForm<9> f = Difference(x, kZa, kZb, dup_m);
    GaussianLoss(sigma_m, weight, f);
    return f;
}

double HeightChangeTerm::Evaluate(const StepVector& x, StepVector* grad, StepMatrix* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<9> HeightChangeTerm::Linearise(const StepVector& x) const {
    return LinearDifference(x, kZa, kZb, dup_m, sigma_m, weight);
}

ResidualForm<2> RandomWalkTerm::Form(const Eigen::Vector2d& x, bool) const {
    ResidualForm<2> f = Difference(x, 0, 1, 0.0);
    if (robust_k <= 0.0) {
        GaussianLoss(sigma, weight, f);
    } else {
        CauchyLoss(sigma, robust_k, weight, f);
    }
    return f;
}

double RandomWalkTerm::Evaluate(const Eigen::Vector2d& x, Eigen::Vector2d* grad,
                                Eigen::Matrix2d* hess) const {
    return Dense(Form(x, hess != nullptr), grad, hess);
}

Linearisation<2> RandomWalkTerm::Linearise(const Eigen::Vector2d& x) const {
    const ResidualForm<2> f = Difference(x, 0, 1, 0.0);
    if (robust_k <= 0.0) return LinearGaussian<2>(f.r, f.j, sigma, weight);
    return LinearCauchy<2>(f.r, f.j, sigma, robust_k, weight);
}

double ScalePriorTerm::Evaluate(double s, double* grad, double* hess) const {
    const double k = weight / (sigma * sigma);
    if (grad) *grad = k * (s - 1.0);
    if (hess) *hess = k;
    return 0.5 * k * (s - 1.0) * (s - 1.0);
}

Linearisation<1> ScalePriorTerm::Linearise(double s) const {
    return LinearGaussian<1>(s - 1.0, Eigen::Matrix<double, 1, 1>(1.0), sigma, weight);
}

double MapDistanceTerm::Evaluate(double d, const Eigen::Vector3d& grad_d,
                                 const Eigen::Matrix3d& hess_d, Eigen::Vector3d* grad,
                                 Eigen::Matrix3d* hess) const {
    const double c2 = giveup_m * giveup_m;
    const double k = weight / (sigma_m * sigma_m);
    const double e = std::exp(-d * d / (2.0 * c2));
    const double rho_d = k * d * e;                    // d rho / d d
    const double rho_dd = k * e * (1.0 - d * d / c2);  // d2 rho / d d2
    if (grad) *grad = rho_d * grad_d;
    if (hess) *hess = rho_dd * grad_d * grad_d.transpose() + rho_d * hess_d;
    return k * c2 * (1.0 - e);
}

Linearisation<3> MapDistanceTerm::Linearise(double d, const Eigen::Vector3d& grad_d) const {
    const double c2 = giveup_m * giveup_m;
    const double k = weight / (sigma_m * sigma_m);
    const double e = std::exp(-d * d / (2.0 * c2));
    const double rho_dd = k * e * (1.0 - d * d / c2);  // d2 rho / d d2
    return {d, grad_d, std::max(rho_dd, 0.0), k * e * d * d};
}

JointVector PosePriorTerm::JointMean() const {
    JointVector m;
    m << mean, HasScale() ? scale_mean : 0.0;
    return m;
}

JointMatrix PosePriorTerm::JointInformation() const {
    JointMatrix i = JointMatrix::Zero();
    i.topLeftCorner<4, 4>() = information;
    if (HasScale()) {
        i.topRightCorner<4, 1>() = cross;
        i.bottomLeftCorner<1, 4>() = cross.transpose();
        i(4, 4) = scale_information;
    }
    return i;
}

// Without a scale the joint information's fifth row and column are zero: x[4] plays no part.
double PosePriorTerm::Evaluate(const JointVector& x, JointVector* grad, JointMatrix* hess) const {
    const JointVector e = x - JointMean();
    const JointMatrix info = JointInformation();
    const JointVector ie = info * e;
    if (grad) *grad = ie;
    if (hess) *hess = info;
    return 0.5 * e.dot(ie);
}

std::array<Linearisation<5>, 5> PosePriorTerm::Linearise(const JointVector& x) const {
    const JointVector e = x - JointMean();
    const Eigen::SelfAdjointEigenSolver<JointMatrix> eigen(JointInformation());
    std::array<Linearisation<5>, 5> out;
    for (int k = 0; k < 5; ++k) {
        Linearisation<5>& l = out[k];
        l.jacobian = eigen.eigenvectors().col(k);
        if (!HasScale()) l.jacobian[4] = 0.0;
        l.residual = l.jacobian.dot(e);
        l.information = std::max(eigen.eigenvalues()[k], 0.0);
        l.chi2 = l.information * l.residual * l.residual;
    }
    return out;
}

}  // namespace driftcorr
