// The definitions of what driftcorr/optim/term_block.h declares.
#include "driftcorr/optim/term_block.h"

#include <Eigen/Eigenvalues>

#include "driftcorr/core/check.h"

namespace driftcorr {
namespace {

// Where the interpolated centre distance is the exact distance its gradient has unit length; it
// is shorter within the interpolation's rounding of a centre line (and where the field is flat).
// Measured on a straight road at 0.5 m resolution: |grad d| 0.87..0.98 and its direction up to
// 1.7 deg off the normal at 0.5 m from the line, 0.98..1 and 0.14 deg at 0.75 m, 1 and 0 from 1 m.
constexpr double kExactGradient = 0.99;
// A probe's gradient this long is taken as a distance's gradient (not a crease, not flat).
constexpr double kProbeGradient = 0.9;

}  // namespace

const char* ToString(TermFamily family) {
    switch (family) {
        case TermFamily::kStepLength:
            return "step length";
        case TermFamily::kStepDirection:
            return "step direction";
        case TermFamily::kHeadingChange:
            return "heading change";
        case TermFamily::kHeadingPreservation:
            return "heading preservation";
        case TermFamily::kHeightChange:
            return "height change";
        case TermFamily::kSpeedChange:
            return "speed change";
        case TermFamily::kMapDistance:
            return "map distance";
        case TermFamily::kScaleWalk:
            return "scale walk";
        case TermFamily::kScaleRange:
            return "scale range";
        case TermFamily::kHeadingBiasWalk:
            return "heading bias walk";
        case TermFamily::kBoundaryPrior:
            return "boundary prior";
        case TermFamily::kFloorHeight:
            return "floor height";
        case TermFamily::kLiftDistance:
            return "lift distance";
        case TermFamily::kMapOffset:
            return "map offset";
        case TermFamily::kStepError:
            return "step error";
    }
    return "?";
}

const std::optional<TraversableSample>& MapDistanceBlock::Sample(const BlockContext& ctx) const {
    DRIFTCORR_CHECK(ctx.samples && pose() >= static_cast<int>(ctx.first_pose),
                    "map block outside window");
    return (*ctx.samples)[static_cast<std::size_t>(pose()) - ctx.first_pose];
}

namespace {

// A map-distance term on a distance sample: cost, and on request its gradient and Hessian over
// the pose's [x, y, z].
double EvaluateOnSample(const MapDistanceTerm& term, const FieldSample& d, BlockVector* grad,
                        BlockMatrix* hess) {
    Eigen::Vector3d g;
    Eigen::Matrix3d h;
    const double cost =
        term.Evaluate(d.value, d.gradient, d.hessian, grad ? &g : nullptr, hess ? &h : nullptr);
    if (grad) *grad = g;
    if (hess) *hess = h;
    return cost;
}

FieldSample DistanceToLift(const BlockContext& ctx, const BlockVector& x) {
    DRIFTCORR_CHECK(ctx.field && !ctx.field->lift_shafts().empty(), "lift block without shafts");
    return DistanceToShafts(ctx.field->lift_shafts(), x.head<3>());
}

}  // namespace

double MapDistanceBlock::Evaluate(const BlockContext& ctx, const BlockVector&, BlockVector* grad,
                                  BlockMatrix* hess) const {
    const auto& s = Sample(ctx);
    if (!s) {
        if (grad) grad->setZero(3);
        if (hess) hess->setZero(3, 3);
        return 0.0;
    }
    return EvaluateOnSample(term_, s->centre, grad, hess);
}

void MapDistanceBlock::Linearise(const BlockContext& ctx, const BlockVector& x,
                                 std::vector<LinearisedTerm>& out) const {
    const auto& s = Sample(ctx);
    if (!s) return;
    const Eigen::Vector3d j = MapJacobian(*ctx.field, x.head<3>(), s->centre);
    out.push_back(FromLinearisation(term_.Linearise(s->centre.value, j)));
}

double LiftDistanceBlock::Evaluate(const BlockContext& ctx, const BlockVector& x, BlockVector* grad,
                                   BlockMatrix* hess) const {
    return EvaluateOnSample(term_, DistanceToLift(ctx, x), grad, hess);
}

// Inside a shaft the pose may be anywhere in it: no residual.
void LiftDistanceBlock::Linearise(const BlockContext& ctx, const BlockVector& x,
                                  std::vector<LinearisedTerm>& out) const {
    const FieldSample d = DistanceToLift(ctx, x);
    if (d.value > 0.0) out.push_back(FromLinearisation(term_.Linearise(d.value, d.gradient)));
}

Eigen::Vector3d MapJacobian(const TraversableField& field, const Eigen::Vector3d& p,
                            const FieldSample& s) {
    if (s.gradient.norm() >= kExactGradient) return s.gradient;
    // The crease runs across the direction of the field's largest curvature; probes 4 cells to
    // either side of p (at least 2.5 cells from the line) read the exact distance, whose
    // gradients point away from the line.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(s.hessian);
    const Eigen::Vector3d u = eigen.eigenvectors().col(2);
    const double delta_m = 4.0 * field.spec().resolution_m;
    const auto a = field.Query(p + delta_m * u), b = field.Query(p - delta_m * u);
    if (!a || !b) return s.gradient;
    const Eigen::Vector3d& ga = a->centre.gradient;
    const Eigen::Vector3d& gb = b->centre.gradient;
    const bool across_one_line = ga.norm() >= kProbeGradient && gb.norm() >= kProbeGradient &&
                                 ga.dot(gb) < -0.5 * ga.norm() * gb.norm();
    return across_one_line ? Eigen::Vector3d((ga - gb).normalized()) : s.gradient;
}

}  // namespace driftcorr
