#include "driftcorr/optim/window_problem.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <unordered_map>

namespace driftcorr {
namespace {

constexpr double kInfBound = 1e19;

// Where the interpolated centre distance is the exact distance its gradient has unit length; it
// is shorter within the interpolation's rounding of a centre line (and where the field is flat).
// Measured on a straight road at 0.5 m resolution: |grad d| 0.87..0.98 and its direction up to
// 1.7 deg off the normal at 0.5 m from the line, 0.98..1 and 0.14 deg at 0.75 m, 1 and 0 from 1 m.
constexpr double kExactGradient = 0.99;
// A probe's gradient this long is taken as a distance's gradient (not a crease, not flat).
constexpr double kProbeGradient = 0.9;

// A core Linearisation over variables `var` (-1: held fixed) as a LinearisedTerm.
template <int N>
void Append(TermFamily family, const Linearisation<N>& lin, const int* var,
            std::vector<LinearisedTerm>& terms) {
    LinearisedTerm t;
    t.family = family;
    for (int k = 0; k < N; ++k) {
        if (var[k] < 0 || lin.jacobian[k] == 0.0) continue;
        t.var[t.size] = var[k];
        t.jacobian[t.size++] = lin.jacobian[k];
    }
    t.residual = lin.residual, t.information = lin.information, t.chi2 = lin.chi2;
    terms.push_back(t);
}

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
        case TermFamily::kMapOffset:
            return "map offset";
        case TermFamily::kBoundaryPrior:
            return "boundary prior";
    }
    return "?";
}

std::vector<int> ScaleSegments(const std::vector<StepObservation>& obs, double segment_m) {
    std::vector<int> seg(obs.size(), 0);
    double dist = 0.0;
    for (std::size_t i = 1; i < obs.size(); ++i) {
        seg[i] = static_cast<int>(dist / segment_m);
        dist += obs[i].length_m;
    }
    if (!seg.empty()) seg[0] = seg.size() > 1 ? seg[1] : 0;
    return seg;
}

WindowProblem::WindowProblem(TrajectoryState& state, const TraversableField* field,
                             const ModelConfig& cfg, std::size_t first, std::size_t last,
                             std::vector<std::uint8_t> constrained, WindowUse use,
                             std::optional<PosePriorTerm> boundary_prior)
    : state_(state),
      field_(field),
      cfg_(cfg),
      first_(first),
      last_(last),
      prior_(std::move(boundary_prior)),
      var_first_(prior_ ? first - 1 : first) {
    assert(first >= 1 && first <= last && last < state.poses.size() && "bad window");
    assert(constrained.size() == last - first + 1 && "one constraint flag per window pose");
    seg_first_ = state.scale_segment[first];
    seg_last_ = state.scale_segment[last];
    n_vars_ = 4 * static_cast<int>(last - var_first_ + 1) + (seg_last_ - seg_first_ + 1);
    for (std::size_t k = 0; k < constrained.size(); ++k) {
        if (constrained[k] && field_) constraint_pose_.push_back(first + k);
    }
    BuildStructure(use);
}

int WindowProblem::PoseVar(std::size_t pose, int component) const {
    if (pose < var_first_) return -1;
    return 4 * static_cast<int>(pose - var_first_) + component;
}

int WindowProblem::ScaleVar(int segment) const {
    if (segment < seg_first_) return -1;
    return 4 * static_cast<int>(last_ - var_first_ + 1) + (segment - seg_first_);
}

int WindowProblem::Slot(std::unordered_map<std::int64_t, int>& slots, int r, int c) {
    if (r < c) std::swap(r, c);
    const std::int64_t key = (std::int64_t(r) << 32) | std::int64_t(c);
    auto [it, inserted] = slots.emplace(key, static_cast<int>(hess_.size()));
    if (inserted) hess_.emplace_back(r, c);
    return it->second;
}

bool WindowProblem::IsJump(std::size_t i) const {
    const StepObservation& o = state_.obs[i];
    return o.length_m > cfg_.max_speed_mps * std::max(o.dt_s, 1e-9);
}

bool WindowProblem::HasSpeedTerm(std::size_t i) const {
    return cfg_.accel_sigma_mps2 > 0.0 && i >= 2 && !IsJump(i) && !IsJump(i - 1);
}

SpeedChangeTerm WindowProblem::SpeedTerm(std::size_t i) const {
    const StepObservation &a = state_.obs[i - 1], &b = state_.obs[i];
    const double sigma = cfg_.accel_sigma_mps2 * 0.5 * (a.dt_s + b.dt_s);
    return SpeedChangeTerm{a.direction_rad, a.dt_s, b.direction_rad, b.dt_s, sigma,
                           cfg_.speed_weight};
}

SpeedVector WindowProblem::GatherSpeed(const double* x, std::size_t i) const {
    SpeedVector v;
    for (int k = 0; k < 3; ++k) {
        const std::size_t pose = i - 2 + k;
        const PoseState& fixed = state_.poses[pose];
        const double values[4] = {fixed.p.x(), fixed.p.y(), fixed.p.z(), fixed.yaw_rad};
        for (int c = 0; c < 4; ++c) {
            const int var = PoseVar(pose, c);
            v[4 * k + c] = var >= 0 ? x[var] : values[c];
        }
    }
    return v;
}

void WindowProblem::BuildStructure(WindowUse use) {
    std::unordered_map<std::int64_t, int> slots;
    auto slot = [&](int r, int c) { return use == WindowUse::kSolve ? Slot(slots, r, c) : -1; };
    steps_.resize(last_ - first_ + 1);
    for (std::size_t i = first_; i <= last_; ++i) {
        StepSlots& s = steps_[i - first_];
        for (int c = 0; c < 4; ++c) {
            s.var[c] = PoseVar(i - 1, c);
            s.var[4 + c] = PoseVar(i, c);
        }
        s.var[kScale] = IsJump(i) ? -1 : ScaleVar(state_.scale_segment[i]);
        for (int r = 0; r < kStepVars; ++r) {
            for (int c = 0; c <= r; ++c) {
                s.hess_slot[r][c] = (s.var[r] >= 0 && s.var[c] >= 0) ? slot(s.var[r], s.var[c]) : -1;
            }
        }
    }
    speeds_.resize(last_ - first_ + 1);
    for (std::size_t i = first_; i <= last_; ++i) {
        if (!HasSpeedTerm(i)) continue;
        SpeedSlots& s = speeds_[i - first_];
        for (int k = 0; k < 3; ++k) {
            for (int c = 0; c < 4; ++c) s.var[4 * k + c] = PoseVar(i - 2 + k, c);
        }
        for (int r = 0; r < 12; ++r) {
            for (int c = 0; c <= r; ++c) {
                s.hess_slot[r][c] = (s.var[r] >= 0 && s.var[c] >= 0) ? slot(s.var[r], s.var[c]) : -1;
            }
        }
    }
    pose_hess_slot_.resize(last_ - first_ + 1);
    for (std::size_t i = first_; i <= last_; ++i) {
        const int x = PoseVar(i, 0), y = PoseVar(i, 1), z = PoseVar(i, 2);
        pose_hess_slot_[i - first_] = {slot(x, x), slot(y, x), slot(y, y),
                                       slot(z, x), slot(z, y), slot(z, z)};
    }
    if (prior_) {
        for (int r = 0, k = 0; r < 4; ++r) {
            for (int c = 0; c <= r; ++c) {
                prior_hess_slot_[k++] = slot(PoseVar(first_ - 1, r), PoseVar(first_ - 1, c));
            }
        }
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) {
        const int a = ScaleVar(sgm - 1), b = ScaleVar(sgm);
        scale_hess_slot_.push_back({a >= 0 ? slot(a, a) : -1, a >= 0 ? slot(b, a) : -1, slot(b, b)});
    }
    for (std::size_t k = 0; k < constraint_pose_.size(); ++k) {
        for (int c = 0; c < 3; ++c) jac_.emplace_back(static_cast<int>(k), PoseVar(constraint_pose_[k], c));
    }
}

void WindowProblem::InitialPoint(double* x) const {
    for (std::size_t i = var_first_; i <= last_; ++i) {
        const PoseState& p = state_.poses[i];
        double* v = x + PoseVar(i, 0);
        v[0] = p.p.x(), v[1] = p.p.y(), v[2] = p.p.z(), v[3] = p.yaw_rad;
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) x[ScaleVar(sgm)] = state_.scales[sgm];
}

void WindowProblem::Bounds(double* x_l, double* x_u, double* g_l, double* g_u) const {
    for (int k = 0; k < n_vars_; ++k) x_l[k] = -kInfBound, x_u[k] = kInfBound;
    for (std::size_t i = var_first_; i <= last_; ++i) {
        if (state_.fix_height) x_l[PoseVar(i, 2)] = x_u[PoseVar(i, 2)] = state_.poses[i].p.z();
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) {
        x_l[ScaleVar(sgm)] = kScaleMin, x_u[ScaleVar(sgm)] = kScaleMax;
    }
    for (std::size_t k = 0; k < constraint_pose_.size(); ++k) {
        g_l[k] = -kInfBound;
        g_u[k] = cfg_.corridor_slack_m;
    }
}

StepVector WindowProblem::GatherStep(const double* x, std::size_t i) const {
    const StepSlots& s = steps_[i - first_];
    StepVector v;
    const PoseState& a = state_.poses[i - 1];
    const double fixed_a[4] = {a.p.x(), a.p.y(), a.p.z(), a.yaw_rad};
    for (int c = 0; c < 4; ++c) v[c] = s.var[c] >= 0 ? x[s.var[c]] : fixed_a[c];
    for (int c = 4; c < 8; ++c) v[c] = x[s.var[c]];
    v[kScale] = s.var[kScale] >= 0 ? x[s.var[kScale]]
                : (IsJump(i) ? 1.0 : state_.scales[state_.scale_segment[i]]);
    return v;
}

// The terms of step i: step length, direction, heading change, heading preservation and (heights
// free) height change.
WindowProblem::StepTerms WindowProblem::TermsOfStep(std::size_t i) const {
    const StepObservation& o = state_.obs[i];
    const double len_sigma = cfg_.step_sigma_m + cfg_.step_sigma_rel * o.length_m;
    const double lat_sigma = cfg_.lateral_sigma_m + cfg_.lateral_sigma_rel * o.length_m;
    const double rw = cfg_.heading_rw_rad_per_sqrt_s, rel = cfg_.heading_sigma_rel * o.dheading_rad;
    const double head_sigma = std::max(cfg_.heading_sigma_min_rad,
                                       std::sqrt(rw * rw * std::max(o.dt_s, 0.0) + rel * rel));
    const double robust_k = IsJump(i) ? 0.0 : cfg_.step_robust_k;
    const double hs = cfg_.height_sigma_m + cfg_.height_sigma_rel * std::abs(o.dup_m);
    return {StepLengthTerm{o.length_m, o.direction_rad, len_sigma, cfg_.step_weight, robust_k},
            StepDirectionTerm{o.direction_rad, lat_sigma, cfg_.step_weight},
            HeadingChangeTerm{o.dheading_rad, head_sigma, cfg_.heading_weight},
            HeadingPreservationTerm{cfg_.preservation_sigma_rad, cfg_.preservation_weight},
            HeightChangeTerm{o.dup_m, hs, cfg_.height_weight}};
}

double WindowProblem::StepCost(std::size_t i, const StepVector& v, StepVector* g,
                               StepMatrix* h) const {
    const StepTerms t = TermsOfStep(i);
    StepVector gt;
    StepMatrix ht;
    StepVector* gp = g ? &gt : nullptr;
    StepMatrix* hp = h ? &ht : nullptr;
    if (g) g->setZero();
    if (h) h->setZero();
    double cost = 0.0;
    auto add = [&](double c) {
        cost += c;
        if (g) *g += gt;
        if (h) *h += ht;
    };
    add(t.length.Evaluate(v, gp, hp));
    add(t.direction.Evaluate(v, gp, hp));
    add(t.heading.Evaluate(v, gp, hp));
    add(t.preservation.Evaluate(v, gp, hp));
    if (!state_.fix_height) add(t.height.Evaluate(v, gp, hp));
    return cost;
}

// Segment 0 carries the prior around 1 (Gaussian); later segments the (robust) random walk.
ScaleRandomWalkTerm WindowProblem::ScaleTerm(int segment) const {
    if (segment == 0) return ScaleRandomWalkTerm{cfg_.scale_prior_sigma, 1.0, 0.0};
    return ScaleRandomWalkTerm{cfg_.scale_rw_sigma, 1.0, cfg_.scale_rw_robust_k};
}

const std::vector<std::optional<TraversableSample>>& WindowProblem::Samples(const double* x) const {
    const std::size_t n = static_cast<std::size_t>(n_vars_);
    if (cache_x_.size() == n && std::equal(cache_x_.begin(), cache_x_.end(), x)) return cache_samples_;
    cache_x_.assign(x, x + n);
    cache_samples_.resize(last_ - first_ + 1);
    for (std::size_t i = first_; i <= last_; ++i) {
        cache_samples_[i - first_] = field_ ? field_->Query(PosePosition(x, i)) : std::nullopt;
    }
    return cache_samples_;
}

PoseVector WindowProblem::BoundaryPose(const double* x) const {
    const double* v = x + PoseVar(first_ - 1, 0);
    return PoseVector(v[0], v[1], v[2], v[3]);
}

Eigen::Vector3d WindowProblem::PosePosition(const double* x, std::size_t pose) const {
    const double* v = x + PoseVar(pose, 0);
    return {v[0], v[1], v[2]};
}

double WindowProblem::Objective(const double* x) const {
    double f = 0.0;
    const MapDistanceTerm map{cfg_.map_sigma_m, cfg_.map_giveup_m, cfg_.map_weight};
    const auto& samples = Samples(x);
    for (std::size_t i = first_; i <= last_; ++i) {
        f += StepCost(i, GatherStep(x, i), nullptr, nullptr);
        if (HasSpeedTerm(i)) f += SpeedTerm(i).Evaluate(GatherSpeed(x, i), nullptr, nullptr);
        if (const auto& s = samples[i - first_]) {
            f += map.Evaluate(s->centre.value, s->centre.gradient, s->centre.hessian, nullptr, nullptr);
        }
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) {
        const int a = ScaleVar(sgm - 1);
        const double sa = a >= 0 ? x[a] : (sgm > 0 ? state_.scales[sgm - 1] : 1.0);
        f += ScaleTerm(sgm).Evaluate({sa, x[ScaleVar(sgm)]}, nullptr, nullptr);
    }
    if (prior_) f += prior_->Evaluate(BoundaryPose(x), nullptr, nullptr);
    return f;
}

void WindowProblem::Gradient(const double* x, double* grad) const {
    for (int k = 0; k < n_vars_; ++k) grad[k] = 0.0;
    const MapDistanceTerm map{cfg_.map_sigma_m, cfg_.map_giveup_m, cfg_.map_weight};
    StepVector g;
    const auto& samples = Samples(x);
    for (std::size_t i = first_; i <= last_; ++i) {
        StepCost(i, GatherStep(x, i), &g, nullptr);
        const StepSlots& s = steps_[i - first_];
        for (int r = 0; r < kStepVars; ++r) if (s.var[r] >= 0) grad[s.var[r]] += g[r];
        if (HasSpeedTerm(i)) {
            SpeedVector gs;
            SpeedTerm(i).Evaluate(GatherSpeed(x, i), &gs, nullptr);
            const SpeedSlots& sp = speeds_[i - first_];
            for (int r = 0; r < 12; ++r) if (sp.var[r] >= 0) grad[sp.var[r]] += gs[r];
        }
        if (const auto& fs = samples[i - first_]) {
            Eigen::Vector3d gm;
            map.Evaluate(fs->centre.value, fs->centre.gradient, fs->centre.hessian, &gm, nullptr);
            for (int c = 0; c < 3; ++c) grad[PoseVar(i, c)] += gm[c];
        }
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) {
        const int a = ScaleVar(sgm - 1), b = ScaleVar(sgm);
        const double sa = a >= 0 ? x[a] : (sgm > 0 ? state_.scales[sgm - 1] : 1.0);
        Eigen::Vector2d gs;
        ScaleTerm(sgm).Evaluate({sa, x[b]}, &gs, nullptr);
        if (a >= 0) grad[a] += gs[0];
        grad[b] += gs[1];
    }
    if (prior_) {
        PoseVector gp;
        prior_->Evaluate(BoundaryPose(x), &gp, nullptr);
        for (int c = 0; c < 4; ++c) grad[PoseVar(first_ - 1, c)] += gp[c];
    }
}

void WindowProblem::Constraints(const double* x, double* g) const {
    const auto& samples = Samples(x);
    for (std::size_t k = 0; k < constraint_pose_.size(); ++k) {
        const auto& s = samples[constraint_pose_[k] - first_];
        g[k] = s ? s->corridor.value : field_->truncation_m();
    }
}

void WindowProblem::JacobianValues(const double* x, double* values) const {
    const auto& samples = Samples(x);
    for (std::size_t k = 0; k < constraint_pose_.size(); ++k) {
        const auto& s = samples[constraint_pose_[k] - first_];
        for (int c = 0; c < 3; ++c) values[3 * k + c] = s ? s->corridor.gradient[c] : 0.0;
    }
}

void WindowProblem::HessianValues(const double* x, double obj_factor, const double* lambda,
                                  double* values) const {
    assert(!pose_hess_slot_.empty() && pose_hess_slot_[0][0] >= 0 && "built with kLinearise");
    for (std::size_t k = 0; k < hess_.size(); ++k) values[k] = 0.0;
    StepMatrix h;
    for (std::size_t i = first_; i <= last_; ++i) {
        StepCost(i, GatherStep(x, i), nullptr, &h);
        const StepSlots& s = steps_[i - first_];
        for (int r = 0; r < kStepVars; ++r) {
            for (int c = 0; c <= r; ++c) {
                if (s.hess_slot[r][c] >= 0) values[s.hess_slot[r][c]] += obj_factor * h(r, c);
            }
        }
        if (!HasSpeedTerm(i)) continue;
        SpeedMatrix hs;
        SpeedTerm(i).Evaluate(GatherSpeed(x, i), nullptr, &hs);
        const SpeedSlots& sp = speeds_[i - first_];
        for (int r = 0; r < 12; ++r) {
            for (int c = 0; c <= r; ++c) {
                if (sp.hess_slot[r][c] >= 0) values[sp.hess_slot[r][c]] += obj_factor * hs(r, c);
            }
        }
    }
    const MapDistanceTerm map{cfg_.map_sigma_m, cfg_.map_giveup_m, cfg_.map_weight};
    auto add_pose = [&](std::size_t pose, const Eigen::Matrix3d& m, double factor) {
        const auto& sl = pose_hess_slot_[pose - first_];
        values[sl[0]] += factor * m(0, 0), values[sl[1]] += factor * m(1, 0);
        values[sl[2]] += factor * m(1, 1), values[sl[3]] += factor * m(2, 0);
        values[sl[4]] += factor * m(2, 1), values[sl[5]] += factor * m(2, 2);
    };
    if (field_) {
        const auto& samples = Samples(x);
        for (std::size_t i = first_; i <= last_; ++i) {
            const auto& fs = samples[i - first_];
            if (!fs) continue;
            Eigen::Matrix3d hm;
            map.Evaluate(fs->centre.value, fs->centre.gradient, fs->centre.hessian, nullptr, &hm);
            add_pose(i, hm, obj_factor);
        }
        for (std::size_t k = 0; k < constraint_pose_.size(); ++k) {
            const auto& fs = samples[constraint_pose_[k] - first_];
            if (fs) add_pose(constraint_pose_[k], fs->corridor.hessian, lambda[k]);
        }
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) {
        const auto& sl = scale_hess_slot_[sgm - seg_first_];
        const int a = ScaleVar(sgm - 1);
        const double sa = a >= 0 ? x[a] : (sgm > 0 ? state_.scales[sgm - 1] : 1.0);
        Eigen::Matrix2d hs;
        ScaleTerm(sgm).Evaluate({sa, x[ScaleVar(sgm)]}, nullptr, &hs);
        if (sl[0] >= 0) values[sl[0]] += obj_factor * hs(0, 0), values[sl[1]] += obj_factor * hs(1, 0);
        values[sl[2]] += obj_factor * hs(1, 1);
    }
    if (prior_) {
        for (int r = 0, k = 0; r < 4; ++r) {
            for (int c = 0; c <= r; ++c) {
                values[prior_hess_slot_[k++]] += obj_factor * prior_->information(r, c);
            }
        }
    }
}

void WindowProblem::LineariseStep(std::size_t i, const StepVector& v,
                                  std::vector<LinearisedTerm>& terms) const {
    const StepTerms t = TermsOfStep(i);
    const int* var = steps_[i - first_].var;
    Append(TermFamily::kStepLength, t.length.Linearise(v), var, terms);
    Append(TermFamily::kStepDirection, t.direction.Linearise(v), var, terms);
    Append(TermFamily::kHeadingChange, t.heading.Linearise(v), var, terms);
    Append(TermFamily::kHeadingPreservation, t.preservation.Linearise(v), var, terms);
    if (!state_.fix_height) Append(TermFamily::kHeightChange, t.height.Linearise(v), var, terms);
}

Eigen::Vector3d WindowProblem::MapJacobian(const Eigen::Vector3d& p, const FieldSample& s) const {
    if (s.gradient.norm() >= kExactGradient) return s.gradient;
    // The crease runs across the direction of the field's largest curvature; probes 4 cells to
    // either side of p (at least 2.5 cells from the line) read the exact distance, whose
    // gradients point away from the line.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(s.hessian);
    const Eigen::Vector3d u = eigen.eigenvectors().col(2);
    const double delta_m = 4.0 * field_->spec().resolution_m;
    const auto a = field_->Query(p + delta_m * u), b = field_->Query(p - delta_m * u);
    if (!a || !b) return s.gradient;
    const Eigen::Vector3d& ga = a->centre.gradient;
    const Eigen::Vector3d& gb = b->centre.gradient;
    const bool across_one_line = ga.norm() >= kProbeGradient && gb.norm() >= kProbeGradient &&
                                 ga.dot(gb) < -0.5 * ga.norm() * gb.norm();
    return across_one_line ? Eigen::Vector3d((ga - gb).normalized()) : s.gradient;
}

void WindowProblem::LineariseTerms(const double* x, std::vector<LinearisedTerm>& terms) const {
    const MapDistanceTerm map{cfg_.map_sigma_m, cfg_.map_giveup_m, cfg_.map_weight};
    const auto& samples = Samples(x);
    for (std::size_t i = first_; i <= last_; ++i) {
        LineariseStep(i, GatherStep(x, i), terms);
        if (HasSpeedTerm(i)) {
            Append(TermFamily::kSpeedChange, SpeedTerm(i).Linearise(GatherSpeed(x, i)),
                   speeds_[i - first_].var, terms);
        }
        if (const auto& fs = samples[i - first_]) {
            const int var[3] = {PoseVar(i, 0), PoseVar(i, 1), PoseVar(i, 2)};
            const Eigen::Vector3d j = MapJacobian(PosePosition(x, i), fs->centre);
            Append(TermFamily::kMapDistance, map.Linearise(fs->centre.value, j), var, terms);
            terms.back().pose = static_cast<int>(i);
        }
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) {
        const int var[2] = {ScaleVar(sgm - 1), ScaleVar(sgm)};
        const double sa = var[0] >= 0 ? x[var[0]] : (sgm > 0 ? state_.scales[sgm - 1] : 1.0);
        Append(TermFamily::kScaleWalk, ScaleTerm(sgm).Linearise({sa, x[var[1]]}), var, terms);
    }
    if (prior_) {
        const int var[4] = {PoseVar(first_ - 1, 0), PoseVar(first_ - 1, 1), PoseVar(first_ - 1, 2),
                            PoseVar(first_ - 1, 3)};
        for (const Linearisation<4>& l : prior_->Linearise(BoundaryPose(x))) {
            Append(TermFamily::kBoundaryPrior, l, var, terms);
            terms.back().pose = static_cast<int>(first_ - 1);
        }
    }
}

void WindowProblem::Store(const double* x) const {
    for (std::size_t i = var_first_; i <= last_; ++i) {
        PoseState& p = state_.poses[i];
        const double* v = x + PoseVar(i, 0);
        p.p = Eigen::Vector3d(v[0], v[1], v[2]);
        p.yaw_rad = v[3];
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) state_.scales[sgm] = x[ScaleVar(sgm)];
}

}  // namespace driftcorr
