// The definitions of what driftcorr/mapping/interpolated_field.h declares.
#include "driftcorr/mapping/interpolated_field.h"

#include <algorithm>
#include <cmath>

#include "driftcorr/core/check.h"

namespace driftcorr {
namespace {

// Uniform cubic B-spline basis at fractional offset t in [0, 1): weights of samples
// i-1, i, i+1, i+2 and their first and second derivatives with respect to t.
struct Basis {
    double w[4], dw[4], ddw[4];
};

Basis CubicBSpline(double t) {
    const double t2 = t * t, t3 = t2 * t, u = 1.0 - t;
    Basis b;
    b.w[0] = u * u * u / 6.0;
    b.w[1] = (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0;
    b.w[2] = (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0;
    b.w[3] = t3 / 6.0;
    b.dw[0] = -0.5 * u * u;
    b.dw[1] = 0.5 * (3.0 * t2 - 4.0 * t);
    b.dw[2] = 0.5 * (-3.0 * t2 + 2.0 * t + 1.0);
    b.dw[3] = 0.5 * t2;
    b.ddw[0] = u;
    b.ddw[1] = 3.0 * t - 2.0;
    b.ddw[2] = -3.0 * t + 1.0;
    b.ddw[3] = t;
    return b;
}

// Locates the support of p along one axis; false if it leaves [0, n).
bool Locate(double coord, double origin, double res, int n, int& i0, double& t) {
    const double g = (coord - origin) / res;
    if (!(g >= 1.0) || !(g < n - 2.0)) return false;
    const double fl = std::floor(g);
    i0 = static_cast<int>(fl) - 1;
    t = g - fl;
    return true;
}

struct Stencil {
    int i0 = 0, j0 = 0, k0 = 0;
    Basis bx, by, bz;
    bool planar = true;
};

bool MakeStencil(const GridSpec& s, const Eigen::Vector3d& p, Stencil& st) {
    double tx, ty, tz = 0.0;
    if (s.nx == 0 || !Locate(p.x(), s.origin_m.x(), s.resolution_m, s.nx, st.i0, tx) ||
        !Locate(p.y(), s.origin_m.y(), s.resolution_m, s.ny, st.j0, ty)) {
        return false;
    }
    st.planar = s.planar();
    if (!st.planar && !Locate(p.z(), s.origin_m.z(), s.dz(), s.nz, st.k0, tz)) {
        return false;
    }
    st.bx = CubicBSpline(tx);
    st.by = CubicBSpline(ty);
    if (!st.planar) st.bz = CubicBSpline(tz);  // a planar field reads one layer, unweighted
    return true;
}

// Accumulates value, gradient (in grid units) and Hessian (grid units) of one field. The planar
// instance leaves out the products with a unit weight and the zero derivatives along z of the
// general one, which come to the same bits: the z components +0, the others unchanged (x * 1).
template <bool kPlanar>
void AccumulateLayers(const GridSpec& s, const std::vector<float>& v, const Stencil& st,
                      FieldSample& out) {
    double val = 0, gx = 0, gy = 0, gz = 0, hxx = 0, hxy = 0, hyy = 0, hxz = 0, hyz = 0, hzz = 0;
    for (int c = 0; c < (kPlanar ? 1 : 4); ++c) {
        for (int b = 0; b < 4; ++b) {
            const float* row = &v[s.Index(st.i0, st.j0 + b, st.k0 + c)];
            double r = 0, rd = 0, rdd = 0;
            for (int a = 0; a < 4; ++a) {
                r += st.bx.w[a] * row[a];
                rd += st.bx.dw[a] * row[a];
                rdd += st.bx.ddw[a] * row[a];
            }
            const double wy = st.by.w[b], dy = st.by.dw[b], ddy = st.by.ddw[b];
            if constexpr (kPlanar) {
                val += r * wy;
                gx += rd * wy;
                gy += r * dy;
                hxx += rdd * wy;
                hxy += rd * dy;
                hyy += r * ddy;
            } else {
                const double wz = st.bz.w[c], dz = st.bz.dw[c], ddz = st.bz.ddw[c];
                val += r * wy * wz;
                gx += rd * wy * wz;
                gy += r * dy * wz;
                gz += r * wy * dz;
                hxx += rdd * wy * wz;
                hxy += rd * dy * wz;
                hyy += r * ddy * wz;
                hxz += rd * wy * dz;
                hyz += r * dy * dz;
                hzz += r * wy * ddz;
            }
        }
    }
    const double inv = 1.0 / s.resolution_m, invz = 1.0 / s.dz(), inv2 = inv * inv;
    out.value = val;
    out.gradient = Eigen::Vector3d(gx * inv, gy * inv, gz * invz);
    out.hessian << hxx * inv2, hxy * inv2, hxz * inv * invz, hxy * inv2, hyy * inv2,
        hyz * inv * invz, hxz * inv * invz, hyz * inv * invz, hzz * invz * invz;
}

void Accumulate(const GridSpec& s, const std::vector<float>& v, const Stencil& st,
                FieldSample& out) {
    if (st.planar) {
        AccumulateLayers<true>(s, v, st, out);
    } else {
        AccumulateLayers<false>(s, v, st, out);
    }
}

// The value alone, summed as Accumulate sums it (the same bits).
double AccumulateValue(const GridSpec& s, const std::vector<float>& v, const Stencil& st) {
    double val = 0;
    const int nk = st.planar ? 1 : 4;
    for (int c = 0; c < nk; ++c) {
        const double wz = st.planar ? 1.0 : st.bz.w[c];
        for (int b = 0; b < 4; ++b) {
            const float* row = &v[s.Index(st.i0, st.j0 + b, st.k0 + (st.planar ? 0 : c))];
            double r = 0;
            for (int a = 0; a < 4; ++a) r += st.bx.w[a] * row[a];
            val += r * st.by.w[b] * wz;
        }
    }
    return val;
}

}  // namespace

InterpolatedField::InterpolatedField(const GridSpec& spec, std::vector<float> values)
    : spec_(spec), values_(std::move(values)) {
    DRIFTCORR_CHECK(values_.size() == spec_.size(), "field values do not match the grid");
}

std::optional<FieldSample> InterpolatedField::Query(const Eigen::Vector3d& p) const {
    Stencil st;
    if (!MakeStencil(spec_, p, st)) return std::nullopt;
    FieldSample out;
    Accumulate(spec_, values_, st, out);
    return out;
}

std::optional<double> InterpolatedField::Value(const Eigen::Vector3d& p) const {
    Stencil st;
    if (!MakeStencil(spec_, p, st)) return std::nullopt;
    return AccumulateValue(spec_, values_, st);
}

bool InterpolatedField::QueryPair(const InterpolatedField& a, const InterpolatedField& b,
                                  const Eigen::Vector3d& p, FieldSample& out_a,
                                  FieldSample& out_b) {
    Stencil st;
    if (!MakeStencil(a.spec_, p, st)) return false;
    Accumulate(a.spec_, a.values_, st, out_a);
    Accumulate(b.spec_, b.values_, st, out_b);
    return true;
}

namespace {

// Cell and fraction of a coordinate for linear interpolation; false outside [0, n - 1].
bool LocateLinear(double coord, double origin, double res, int n, int& i0, double& t) {
    const double g = (coord - origin) / res;
    if (n < 2 || !(g >= 0.0) || !(g <= n - 1.0)) return false;
    i0 = std::min(static_cast<int>(std::floor(g)), n - 2);
    t = g - i0;
    return true;
}

}  // namespace

std::optional<FieldSample> InterpolatedField::QueryBilinear(const Eigen::Vector3d& p) const {
    const GridSpec& s = spec_;
    int i0 = 0, j0 = 0, k0 = 0;
    double tx = 0.0, ty = 0.0, tz = 0.0;
    if (s.size() == 0 || !LocateLinear(p.x(), s.origin_m.x(), s.resolution_m, s.nx, i0, tx) ||
        !LocateLinear(p.y(), s.origin_m.y(), s.resolution_m, s.ny, j0, ty)) {
        return std::nullopt;
    }
    const bool planar = s.planar();
    if (!planar && !LocateLinear(p.z(), s.origin_m.z(), s.dz(), s.nz, k0, tz)) {
        return std::nullopt;
    }
    double val = 0.0;
    Eigen::Vector3d grad = Eigen::Vector3d::Zero();
    for (int c = 0; c < (planar ? 1 : 2); ++c) {
        const double wz = planar ? 1.0 : (c ? tz : 1.0 - tz), dz = planar ? 0.0 : (c ? 1.0 : -1.0);
        for (int b = 0; b < 2; ++b) {
            const double wy = b ? ty : 1.0 - ty, dy = b ? 1.0 : -1.0;
            for (int a = 0; a < 2; ++a) {
                const double wx = a ? tx : 1.0 - tx, dx = a ? 1.0 : -1.0;
                const double v = values_[s.Index(i0 + a, j0 + b, k0 + c)];
                val += wx * wy * wz * v;
                grad += v * Eigen::Vector3d(dx * wy * wz, wx * dy * wz, wx * wy * dz);
            }
        }
    }
    FieldSample out;
    out.value = val;
    out.gradient =
        Eigen::Vector3d(grad.x() / s.resolution_m, grad.y() / s.resolution_m, grad.z() / s.dz());
    return out;
}

}  // namespace driftcorr
