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
#include <cstdint>
#include <optional>
#include <type_traits>
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
    kScaleWalk,        ///< the random walk between scale segments and the prior on the first
    kScaleRange,       ///< the plausible range of the step-length scale (a prior, not a bound)
    kHeadingBiasWalk,  ///< the heading-rate bias's random walk and the prior on the first
    kBoundaryPrior,    ///< the prior on a fixed-lag window's boundary pose (its marginalised past)
    kFloorHeight,      ///< a level pose's height about its floor (ModelConfig::floor_sigma_m)
    kLiftDistance,     ///< a pose in a lift ride from the nearest shaft (ModelConfig::lift_sigma_m)
    /// The map's offset process of the covariance's model (optim/covariance.h); not a
    /// term of the objective.
    kMapOffset,
    /// The step length's slowly varying error of the covariance's model (optim/covariance.h);
    /// not a term of the objective.
    kStepError,
};
constexpr int kTermFamilies = 15;
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
    int pose = -1;  ///< the pose of a map distance or boundary prior term, the step into pose of a
                    ///< step length term; -1 for the others
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

/// A Hessian entry a block adds to: `local` indexes the block's local Hessian (column-major,
/// size() rows), `slot` the problem's Hessian values.
struct BlockEntry {
    int local, slot;
};

class TermBlock {
public:
    /// `reads`: the local variables the cost depends on (core ReadsOf); its gradient and Hessian
    /// are exact zeros elsewhere, which WindowProblem then does not add up.
    TermBlock(TermFamily family, int size, std::uint16_t reads = 0xFFFF)
        : family_(family), size_(size), reads_(std::uint16_t(reads & ((1u << size) - 1))) {}
    virtual ~TermBlock() = default;

    TermFamily family() const { return family_; }
    int size() const { return size_; }
    /// Bit k set: the cost depends on local variable k.
    std::uint16_t reads() const { return reads_; }
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
        GatherInto(x, v);
        return v;
    }
    /// Gather into a vector of size() entries (a fixed-size one too).
    template <class Vector>
    void GatherInto(const double* x, Vector& v) const {
        for (int k = 0; k < size_; ++k) v[k] = var_[k] >= 0 ? x[var_[k]] : fixed_[k];
    }

    /// Cost at the local values x (size()), and on request its gradient and Hessian over them.
    virtual double Evaluate(const BlockContext& ctx, const BlockVector& x, BlockVector* grad,
                            BlockMatrix* hess) const = 0;
    /// Evaluates the block at the window point x and adds what is asked for: the gradient over
    /// the variables it reads into `grad` (by window variable; none if null), obj_factor times
    /// its Hessian into `values` at the entries [begin, end) (none if null). Returns the cost.
    /// The same sums as Evaluate on Gather(x), added entry by entry.
    virtual double Accumulate(const BlockContext& ctx, const double* x, double obj_factor,
                              double* grad, double* values, const BlockEntry* begin,
                              const BlockEntry* end) const {
        BlockVector g;
        BlockMatrix h;
        const double cost = Evaluate(ctx, Gather(x), grad ? &g : nullptr, values ? &h : nullptr);
        if (grad) AddGradient(g.data(), grad);
        if (values) AddHessian(h.data(), obj_factor, values, begin, end);
        return cost;
    }
    /// The term's linearisation at x appended to `out` (usually one residual; none when the
    /// term contributes nothing at x, e.g. a map term off the field), over local variables:
    /// LinearisedTerm::var holds local indices here; WindowProblem maps them to window
    /// variables and drops fixed ones.
    virtual void Linearise(const BlockContext& ctx, const BlockVector& x,
                           std::vector<LinearisedTerm>& out) const = 0;

protected:
    // What a block does not read has exact zeros (+-0) in its gradient and Hessian, and adding
    // them would change no sum (a sum from +0 is never -0, and x + (+-0) = x otherwise): only
    // the variables it reads are added.
    void AddGradient(const double* g, double* grad) const {
        for (unsigned bits = reads_; bits != 0; bits &= bits - 1) {
            const int k = __builtin_ctz(bits);
            if (var_[k] >= 0) grad[var_[k]] += g[k];
        }
    }
    static void AddHessian(const double* h, double obj_factor, double* values,
                           const BlockEntry* begin, const BlockEntry* end) {
        for (const BlockEntry* e = begin; e != end; ++e)
            values[e->slot] += obj_factor * h[e->local];
    }

private:
    TermFamily family_;
    int size_;
    std::uint16_t reads_;
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

/// The variables a core term reads: its kReads where it declares them, else all N.
template <class Term, int N, class = void>
struct TermReads {
    static constexpr std::uint16_t value = std::uint16_t((1u << N) - 1);
};
template <class Term, int N>
struct TermReads<Term, N, std::void_t<decltype(Term::kReads)>> {
    static constexpr std::uint16_t value = Term::kReads;
};

/// A core term (core/cost_terms.h) of one residual over N local variables: its Form, Evaluate and
/// Linearise take an N-vector (Form gives a ResidualForm<N>, Linearise a Linearisation<N>).
template <class Term, int N>
class CoreTermBlock final : public TermBlock {
public:
    using Vector = Eigen::Matrix<double, N, 1>;
    using Matrix = Eigen::Matrix<double, N, N>;
    CoreTermBlock(TermFamily family, const Term& term)
        : TermBlock(family, N, TermReads<Term, N>::value), term_(term) {}

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
    /// Evaluate's sums from the term's residual form (core ResidualForm), on its own fixed-size
    /// vectors: only the gradient entries of the variables it reads and the Hessian entries
    /// [begin, end) lists, not all N x N.
    double Accumulate(const BlockContext&, const double* x, double obj_factor, double* grad,
                      double* values, const BlockEntry* begin,
                      const BlockEntry* end) const override {
        Vector v;
        GatherInto(x, v);
        const ResidualForm<N> f = term_.Form(v, values != nullptr);
        for (unsigned bits = grad ? reads() : 0u; bits != 0; bits &= bits - 1) {
            const int k = __builtin_ctz(bits);
            if (var(k) >= 0) grad[var(k)] += f.g * f.j[k];
        }
        if (values) {
            for (const BlockEntry* e = begin; e != end; ++e)
                values[e->slot] += obj_factor * f.Hessian(e->local % N, e->local / N);
        }
        return f.cost;
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

/// The lift term of one pose in a lift ride, over its position [x, y, z] (reads x, y): core
/// MapDistanceTerm on the horizontal distance to the nearest of the context field's lift shafts
/// (DistanceToShafts: 0 inside, where the pose may stand anywhere).
class LiftDistanceBlock final : public TermBlock {
public:
    LiftDistanceBlock(const MapDistanceTerm& term, int pose)
        : TermBlock(TermFamily::kLiftDistance, 3, 0b011), term_(term) {
        set_pose(pose);
    }
    double Evaluate(const BlockContext& ctx, const BlockVector& x, BlockVector* grad,
                    BlockMatrix* hess) const override;
    void Linearise(const BlockContext& ctx, const BlockVector& x,
                   std::vector<LinearisedTerm>& out) const override;

private:
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
