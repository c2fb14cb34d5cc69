#pragma once
// A scalar field on a GridSpec, interpolated by a uniform cubic B-spline whose control points are
// the samples: value, gradient and Hessian are continuous everywhere inside (C2), which is what a
// Newton-type solver needs. A raw voxel/pixel distance grid is a staircase; this is not.
// Linear functions are reproduced exactly, so away from kinks (the centre line, the medial axis)
// the distance is exact; at a kink the V is rounded over about two cells.
#include <optional>
#include <vector>

#include "driftcorr/mapping/grid.h"

namespace driftcorr {

/// Value, gradient [1/m * unit] and Hessian of a field at a point (world frame, metres).
/// For a planar field the z row/column of gradient and Hessian are zero.
struct FieldSample {
    double value = 0.0;
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
    Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
};

class InterpolatedField {
public:
    InterpolatedField() = default;
    /// Precondition: values.size() == spec.size(), all finite.
    InterpolatedField(const GridSpec& spec, std::vector<float> values);

    /// The interpolated sample at p, or std::nullopt where the B-spline support leaves the grid
    /// (p closer than one cell to the border) or the grid is empty. For planar grids p.z() is
    /// ignored.
    std::optional<FieldSample> Query(const Eigen::Vector3d& p) const;
    /// Query's value alone (the same number), without the derivatives.
    std::optional<double> Value(const Eigen::Vector3d& p) const;
    /// Query of two fields sharing one spec (the same numbers), with one set of weights; false
    /// where Query of `a` has none.
    static bool QueryPair(const InterpolatedField& a, const InterpolatedField& b,
                          const Eigen::Vector3d& p, FieldSample& out_a, FieldSample& out_b);
    /// The samples interpolated (bi)linearly instead of by the B-spline: bilinear in (x, y) for a
    /// planar grid (p.z() ignored), trilinear otherwise. The value is continuous, the gradient is
    /// piecewise constant (it jumps at cell borders) and the Hessian is returned as zero. This is
    /// the plain grid interpolation of the paper's reference method (optim/paper_solver.h), not
    /// meant for Newton-type solvers. std::nullopt outside [origin, origin + (n - 1) * res] or for
    /// an empty grid.
    std::optional<FieldSample> QueryBilinear(const Eigen::Vector3d& p) const;

    const GridSpec& spec() const { return spec_; }
    const std::vector<float>& values() const { return values_; }

private:
    GridSpec spec_;
    std::vector<float> values_;
};

}  // namespace driftcorr
