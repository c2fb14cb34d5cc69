#pragma once
// One term of the window's NLL as a unit WindowProblem assembles without knowing what it is: the
// window variables it reads (or the values it holds fixed where a variable lies outside the
// window), its cost with the exact gradient and Hessian over those local variables, and its
// linearisation for the covariance (core Linearisation). Objective, gradient, Hessian structure
// and values, and LineariseTerms are generic loops over a window's blocks, so a new term is one
// block (usually a core term wrapped in CoreTermBlock) plus its derivative tests.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include "driftcorr/core/cost_terms.h"
#include "driftcorr/mapping/traversable_field.h"

namespace driftcorr {

/// The families of the NLL's terms (core/cost_terms.h).
enum class TermFamily : int {
    kStepLength,
    kStepDirection,
    kHeadingChange,
    kHeadingPreservation,
    kHeightChange,
    kSpeedChange,
    kMapDistance,
    kScaleWalk,  ///< the random walk between scale segments and the prior on the first
    kScaleRange,  ///< the plausible range of the step-length scale (a prior, not a bound)
    kHeadingBiasWalk,  ///< the heading-rate bias's random walk and the prior on the first
    kBoundaryPrior,    ///< the prior on a fixed-lag window's boundary pose (its marginalised past)
    /// The map's offset process of the covariance's model (optim/covariance.h); not a
    /// term of the objective.
    kMapOffset,
};
constexpr int kTermFamilies = 12;
const char* ToString(TermFamily family);

/// The most local variables a block has (the speed change term: three poses).
constexpr int kMaxBlockVars = 12;
using BlockVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxBlockVars, 1>;
using BlockMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor,
                                  kMaxBlockVars, kMaxBlockVars>;

/// One term of the objective linearised at a point (core Linearisation), over the window's
/// variables: jacobian[k] = dr / d(variable var[k]), k < size (for a map term within a centre
/// line's rounding band the line's unit normal, see MapDistanceBlock); variables held fixed
/// outside the window are left out, as are entries whose derivative is zero.
struct LinearisedTerm {
    TermFamily family = TermFamily::kStepLength;
    int pose = -1;  ///< the pose of a map distance or boundary prior term; -1 for the others
    int size = 0;
    std::array<int, kMaxBlockVars> var{};
    std::array<double, kMaxBlockVars> jacobian{};
    double residual = 0.0, information = 0.0, chi2 = 0.0;
};

/// What a block may read besides its variables: the map field, and its sample at every window
/// pose for the current point (queried once per point by WindowProblem).
struct BlockContext {
    const TraversableField* field = nullptr;
    const std::vector<std::optional<TraversableSample>>* samples = nullptr;
    std::size_t first_pose = 0;  ///< the window's first pose: samples[pose - first_pose]
};

class TermBlock {
public:
    TermBlock(TermFamily family, int size) : family_(family), size_(size) {}
    virtual ~TermBlock() = default;

    TermFamily family() const { return family_; }
    int size() const { return size_; }
    /// The pose a per-pose term (map distance) belongs to; -1 for the others.
    int pose() const { return pose_; }
    void set_pose(int pose) { pose_ = pose; }
    /// Window variable of local variable k, or -1 when it is held fixed at fixed(k).
    int var(int k) const { return var_[k]; }
    double fixed(int k) const { return fixed_[k]; }
    void Bind(int k, int window_var, double fixed_value) {
        var_[k] = window_var;
        fixed_[k] = fixed_value;
    }
    /// The local values at the window point x (fixed values where var(k) < 0).
    BlockVector Gather(const double* x) const {
        BlockVector v(size_);
        for (int k = 0; k < size_; ++k) v[k] = var_[k] >= 0 ? x[var_[k]] : fixed_[k];
        return v;
    }

    /// Cost at the local values x (size()), and on request its gradient and Hessian over them.
    virtual double Evaluate(const BlockContext& ctx, const BlockVector& x, BlockVector* grad,
                            BlockMatrix* hess) const = 0;
    /// The term's linearisation at x appended to `out` (usually one residual; none when the
    /// term contributes nothing at x, e.g. a map term off the field), over local variables:
    /// LinearisedTerm::var holds local indices here; WindowProblem maps them to window
    /// variables and drops fixed ones.
    virtual void Linearise(const BlockContext& ctx, const BlockVector& x,
                           std::vector<LinearisedTerm>& out) const = 0;

private:
    TermFamily family_;
    int size_;
    int pose_ = -1;
    std::array<int, kMaxBlockVars> var_{};
    std::array<double, kMaxBlockVars> fixed_{};
};

/// A core Linearisation as a LinearisedTerm over local variables 0..N-1.
template <int N>
LinearisedTerm FromLinearisation(const Linearisation<N>& lin) {
    LinearisedTerm t;
    t.size = N;
    for (int k = 0; k < N; ++k) t.var[k] = k, t.jacobian[k] = lin.jacobian[k];
    t.residual = lin.residual, t.information = lin.information, t.chi2 = lin.chi2;
    return t;
}

/// A core term (core/cost_terms.h) over N local variables whose Evaluate takes an N-vector and
/// whose Linearise returns a Linearisation<N>.
template <class Term, int N>
class CoreTermBlock final : public TermBlock {
public:
    using Vector = Eigen::Matrix<double, N, 1>;
    using Matrix = Eigen::Matrix<double, N, N>;
    CoreTermBlock(TermFamily family, const Term& term) : TermBlock(family, N), term_(term) {}

    double Evaluate(const BlockContext&, const BlockVector& x, BlockVector* grad,
                    BlockMatrix* hess) const override {
        const Vector v = x;
        Vector g;
        Matrix h;
        const double cost = term_.Evaluate(v, grad ? &g : nullptr, hess ? &h : nullptr);
        if (grad) *grad = g;
        if (hess) *hess = h;
        return cost;
    }
    void Linearise(const BlockContext&, const BlockVector& x,
                   std::vector<LinearisedTerm>& out) const override {
        out.push_back(FromLinearisation(term_.Linearise(Vector(x))));
    }
    const Term& term() const { return term_; }

private:
    Term term_;
};

/// The map distance term (core MapDistanceTerm) of one pose, over its position [x, y, z]; the
/// distance comes from the context's field sample of the pose (no sample: no cost).
/// Linearisation: the interpolated distance rounds its V within about one cell of a centre line,
/// so there grad d shrinks to zero and turns along the line (65-78 % of the corrected KITTI poses
/// lie in that band). On such a grad d the Gauss-Newton curvature would lose the road's
/// cross-track information and gain along-track information that is not in the map. There the
/// Jacobian is the line's unit normal, read from grad d at two probes across the line where the
/// field is exact (MapJacobian): the curvature the Gaussian on the true distance has. Where the
/// probes do not find one line (a junction, a field smoothed more widely, as the indoor field
/// over its 0.5 m layers) grad d stays.
class MapDistanceBlock final : public TermBlock {
public:
    MapDistanceBlock(const MapDistanceTerm& term, int pose)
        : TermBlock(TermFamily::kMapDistance, 3), term_(term) {
        set_pose(pose);
    }
    double Evaluate(const BlockContext& ctx, const BlockVector& x, BlockVector* grad,
                    BlockMatrix* hess) const override;
    void Linearise(const BlockContext& ctx, const BlockVector& x,
                   std::vector<LinearisedTerm>& out) const override;

private:
    const std::optional<TraversableSample>& Sample(const BlockContext& ctx) const;
    MapDistanceTerm term_;
};

/// The prior on a fixed-lag window's boundary pose (core PosePriorTerm) over its [x, y, z, yaw],
/// and the scale of its segment when the prior carries one; linearised as one residual per
/// eigenvector of its information.
class BoundaryPriorBlock final : public TermBlock {
public:
    BoundaryPriorBlock(const PosePriorTerm& term, int pose)
        : TermBlock(TermFamily::kBoundaryPrior, term.Size()), term_(term) {
        set_pose(pose);
    }
    double Evaluate(const BlockContext&, const BlockVector& x, BlockVector* grad,
                    BlockMatrix* hess) const override {
        const int n = size();
        JointVector xj = JointVector::Zero();
        xj.head(n) = x.head(n);
        JointVector g;
        JointMatrix h;
        const double cost = term_.Evaluate(xj, grad ? &g : nullptr, hess ? &h : nullptr);
        if (grad) *grad = g.head(n);
        if (hess) *hess = h.topLeftCorner(n, n);
        return cost;
    }
    void Linearise(const BlockContext&, const BlockVector& x,
                   std::vector<LinearisedTerm>& out) const override {
        const int n = size();
        JointVector xj = JointVector::Zero();
        xj.head(n) = x.head(n);
        for (const Linearisation<5>& l : term_.Linearise(xj)) {
            if (l.jacobian.head(n).squaredNorm() < 0.5) continue;  // the absent scale's axis
            LinearisedTerm t = FromLinearisation(l);
            t.size = n;
            out.push_back(t);
        }
    }

private:
    PosePriorTerm term_;
};

/// The Jacobian of the map distance at p for the covariance (see MapDistanceBlock).
Eigen::Vector3d MapJacobian(const TraversableField& field, const Eigen::Vector3d& p,
                            const FieldSample& centre);

}  // namespace driftcorr
