// The definitions of what driftcorr/optim/window_problem.h declares.
#include "driftcorr/optim/window_problem.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <unordered_map>

#include "driftcorr/core/check.h"

namespace driftcorr {
namespace {

constexpr double kInfBound = 1e19;

// The Hessian's slots by (row, column), row >= column. Below `split` (the pose variables) a row
// couples with a short span of columns [lo, hi] (a pose with the two before it; a scale or bias
// segment with its poses), held as one entry per column of the span (-1: no slot yet). Pairs of
// two variables at or above `split` (segment with segment: the random walks, a handful per
// segment) are kept by key. Two passes: Note every pair, Allocate, then Slot them.
class SlotTable {
public:
    SlotTable(int n, int split) : split_(split), lo_(n, INT_MAX), hi_(n, -1) {}
    void Note(int r, int c) {
        if (r < c) std::swap(r, c);
        if (c >= split_) return;
        lo_[r] = std::min(lo_[r], c);
        hi_[r] = std::max(hi_[r], c);
    }
    /// Note(r, c) for every pair of the block's variables (held ones left out), in a pass over
    /// them: the pairs with row r reach down to the block's least variable and up to r itself
    /// (a row at or above split: up to the block's last variable below split).
    void NoteBlock(const TermBlock& block) {
        int least = INT_MAX, below_split = -1;
        for (int k = 0; k < block.size(); ++k) {
            const int v = block.var(k);
            if (v < 0) continue;
            least = std::min(least, v);
            if (v < split_) below_split = std::max(below_split, v);
        }
        if (least >= split_) return;
        for (int k = 0; k < block.size(); ++k) {
            const int v = block.var(k);
            if (v < 0) continue;
            lo_[v] = std::min(lo_[v], least);
            hi_[v] = std::max(hi_[v], v < split_ ? v : below_split);
        }
    }
    void Allocate() {
        offset_.assign(lo_.size() + 1, 0);
        for (std::size_t r = 0; r < lo_.size(); ++r) {
            const std::size_t span = hi_[r] >= lo_[r] ? std::size_t(hi_[r] - lo_[r] + 1) : 0;
            offset_[r + 1] = offset_[r] + span;
        }
        entries_.assign(offset_.back(), -1);
    }
    /// At least the number of pairs below split (each row's span holds its pairs).
    std::size_t Capacity() const { return entries_.size(); }
    /// The slot of (r, c) in `hess` (appended on first use). Precondition: (r, c) was noted.
    int Slot(int r, int c, std::vector<std::pair<int, int>>& hess) {
        if (r < c) std::swap(r, c);
        int& e = c >= split_ ? segments_.try_emplace((std::int64_t(r) << 32) | c, -1).first->second
                             : entries_[offset_[r] + std::size_t(c - lo_[r])];
        if (e < 0) {
            e = static_cast<int>(hess.size());
            hess.emplace_back(r, c);
        }
        return e;
    }

private:
    int split_;
    std::vector<int> lo_, hi_;
    std::vector<std::size_t> offset_;
    std::vector<int> entries_;
    std::unordered_map<std::int64_t, int> segments_;
};

// Whether two blocks read the same window variables in the same order (fixed values aside).
bool SameVariables(const TermBlock& a, const TermBlock& b) {
    if (a.size() != b.size()) return false;
    for (int k = 0; k < a.size(); ++k) {
        if (a.var(k) != b.var(k)) return false;
    }
    return true;
}

}  // namespace

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

std::vector<double> PathPositions(const std::vector<StepObservation>& obs) {
    std::vector<double> path_m(obs.size(), 0.0);
    for (std::size_t i = 1; i < obs.size(); ++i) path_m[i] = path_m[i - 1] + obs[i].length_m;
    return path_m;
}

std::vector<int> BiasSegments(const std::vector<StepObservation>& obs, double segment_s) {
    if (!(segment_s > 0.0)) return {};
    std::vector<int> seg(obs.size(), 0);
    double t = 0.0;
    for (std::size_t i = 1; i < obs.size(); ++i) {
        seg[i] = static_cast<int>(t / segment_s);
        t += std::max(obs[i].dt_s, 0.0);
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
      var_first_(prior_ ? first - 1 : first),
      arena_((last - first + 2) * kArenaBytesPerPose) {
    DRIFTCORR_CHECK(first >= 1 && first <= last && last < state.poses.size(), "bad window");
    DRIFTCORR_CHECK(constrained.size() == last - first + 1, "one constraint flag per window pose");
    seg_first_ = state.scale_segment[first];
    // A prior joint with its segment's scale makes that scale a variable (it summarises the walk
    // and range terms of that segment and before).
    if (prior_ && prior_->HasScale()) seg_first_ = std::min(seg_first_, prior_->scale_segment);
    seg_last_ = state.scale_segment[last];
    n_vars_ = 4 * static_cast<int>(last - var_first_ + 1) + (seg_last_ - seg_first_ + 1);
    if (HasBias()) {
        DRIFTCORR_CHECK(state.bias_segment.size() == state.poses.size(),
                        "one bias segment per step");
        bias_first_ = state.bias_segment[first];
        bias_last_ = state.bias_segment[last];
        bias_var0_ = n_vars_;
        n_vars_ += bias_last_ - bias_first_ + 1;
    }
    for (std::size_t k = 0; k < constrained.size(); ++k) {
        if (constrained[k] && field_) constraint_pose_.push_back(first + k);
    }
    BuildStructure(use);
}

WindowProblem::~WindowProblem() {
    for (TermBlock* block : blocks_) block->~TermBlock();
}

int WindowProblem::PoseVar(std::size_t pose, int component) const {
    if (pose < var_first_) return -1;
    return 4 * static_cast<int>(pose - var_first_) + component;
}

int WindowProblem::ScaleVar(int segment) const {
    if (segment < seg_first_) return -1;
    return 4 * static_cast<int>(last_ - var_first_ + 1) + (segment - seg_first_);
}

int WindowProblem::BiasVar(int segment) const {
    if (!HasBias() || segment < bias_first_) return -1;
    return bias_var0_ + (segment - bias_first_);
}

bool WindowProblem::IsJump(std::size_t i) const {
    return driftcorr::IsJump(state_.obs[i], cfg_.max_speed_mps);
}

bool WindowProblem::HasSpeedTerm(std::size_t i) const {
    return cfg_.accel_sigma_mps2 > 0.0 && i >= 2 && !IsJump(i) && !IsJump(i - 1);
}

void WindowProblem::BindPose(TermBlock& block, int k0, std::size_t pose) const {
    const PoseState& p = state_.poses[pose];
    const double fixed[4] = {p.p.x(), p.p.y(), p.p.z(), p.yaw_rad};
    for (int c = 0; c < 4; ++c) block.Bind(k0 + c, PoseVar(pose, c), fixed[c]);
}

StepNoise StepNoiseOf(const ModelConfig& m, const StepObservation& o) {
    StepNoise n;
    const double len_rel =
        o.repaired ? std::max(m.step_sigma_rel, m.outlier_sigma_rel) : m.step_sigma_rel;
    n.length_m = o.tread ? m.tread_sigma_m : m.step_sigma_m + len_rel * o.length_m;
    n.lateral_m = m.lateral_sigma_m + m.lateral_sigma_rel * o.length_m;
    const double rw = m.heading_rw_rad_per_sqrt_s, rel = m.heading_sigma_rel * o.dheading_rad;
    n.heading_rad =
        std::max(m.heading_sigma_min_rad, std::sqrt(rw * rw * std::max(o.dt_s, 0.0) + rel * rel));
    n.height_m = m.height_sigma_m + m.height_sigma_rel * std::abs(o.dup_m);
    return n;
}

// Step i's terms over [pose i-1, pose i, scale] (core StepVar layout): length, direction, heading
// change, heading preservation, height change (heights free); then speed continuity over poses
// i-2..i.
void WindowProblem::AddStepBlocks(std::size_t i) {
    const StepObservation& o = state_.obs[i];
    const StepNoise noise = StepNoiseOf(cfg_, o);
    const double len_sigma = noise.length_m, lat_sigma = noise.lateral_m;
    const double head_sigma = noise.heading_rad, hs = noise.height_m;
    const double robust_k = IsJump(i) ? 0.0 : cfg_.step_robust_k;
    const std::size_t begin = blocks_.size();
    blocks_.push_back(Core<StepLengthTerm, 9>(
        TermFamily::kStepLength,
        StepLengthTerm{o.length_m, o.direction_rad, len_sigma, cfg_.step_weight, robust_k}));
    blocks_.back()->set_pose(static_cast<int>(i));  // the covariance's step error (covariance.h)
    blocks_.push_back(Core<StepDirectionTerm, 9>(
        TermFamily::kStepDirection,
        StepDirectionTerm{o.direction_rad, lat_sigma, cfg_.step_weight}));
    if (!HasBias()) {
        blocks_.push_back(Core<HeadingChangeTerm, 9>(
            TermFamily::kHeadingChange,
            HeadingChangeTerm{o.dheading_rad, head_sigma, cfg_.heading_weight}));
    }
    blocks_.push_back(Core<HeadingPreservationTerm, 9>(
        TermFamily::kHeadingPreservation,
        HeadingPreservationTerm{cfg_.preservation_sigma_rad, cfg_.preservation_weight}));
    if (!state_.fix_height) {
        blocks_.push_back(Core<HeightChangeTerm, 9>(
            TermFamily::kHeightChange, HeightChangeTerm{o.dup_m, hs, cfg_.height_weight}));
    }
    const bool unscaled = IsJump(i) || o.tread;  // a tread's run is its own
    const int scale_var = unscaled ? -1 : ScaleVar(state_.scale_segment[i]);
    const double scale_fixed = unscaled ? 1.0 : state_.scales[state_.scale_segment[i]];
    for (std::size_t b = begin; b < blocks_.size(); ++b) {
        BindPose(*blocks_[b], kXa, i - 1);
        BindPose(*blocks_[b], kXb, i);
        blocks_[b]->Bind(kScale, scale_var, scale_fixed);
    }
    if (HasBias()) {  // heading change with the bias: [yaw_a, yaw_b, bias]
        const int segment = state_.bias_segment[i];
        blocks_.push_back(Core<HeadingChangeBiasTerm, 3>(
            TermFamily::kHeadingChange, HeadingChangeBiasTerm{o.dheading_rad, std::max(o.dt_s, 0.0),
                                                              head_sigma, cfg_.heading_weight}));
        blocks_.back()->Bind(0, PoseVar(i - 1, 3), state_.poses[i - 1].yaw_rad);
        blocks_.back()->Bind(1, PoseVar(i, 3), 0.0);
        blocks_.back()->Bind(2, BiasVar(segment), state_.biases[segment]);
    }
    if (HasSpeedTerm(i)) {
        const StepObservation& a = state_.obs[i - 1];
        const double sigma = cfg_.accel_sigma_mps2 * 0.5 * (a.dt_s + o.dt_s);
        blocks_.push_back(Core<SpeedChangeTerm, 12>(
            TermFamily::kSpeedChange, SpeedChangeTerm{a.direction_rad, a.dt_s, o.direction_rad,
                                                      o.dt_s, sigma, cfg_.speed_weight}));
        for (int k = 0; k < 3; ++k) BindPose(*blocks_.back(), 4 * k, i - 2 + k);
    }
}

// Segment 0 carries the prior around scale_prior_mean (Gaussian: the walk from a fixed value);
// later segments the (robust) random walk from the one before; each the plausible range
// (ModelConfig).
void WindowProblem::AddScaleBlocks() {
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) {
        if (prior_ && prior_->scale_segment == sgm) continue;  // in the boundary prior
        const RandomWalkTerm walk =
            sgm == 0 ? RandomWalkTerm{cfg_.scale_prior_sigma, 1.0, 0.0}
                     : RandomWalkTerm{cfg_.scale_rw_sigma, 1.0, cfg_.scale_rw_robust_k};
        blocks_.push_back(Core<RandomWalkTerm, 2>(TermFamily::kScaleWalk, walk));
        const int a = ScaleVar(sgm - 1);
        blocks_.back()->Bind(
            0, a, a >= 0 ? 0.0 : (sgm > 0 ? state_.scales[sgm - 1] : cfg_.scale_prior_mean));
        blocks_.back()->Bind(1, ScaleVar(sgm), 0.0);
        if (cfg_.scale_range_sigma > 0.0) {
            blocks_.push_back(Core<ScaleRangeTerm, 1>(
                TermFamily::kScaleRange, ScaleRangeTerm{cfg_.scale_range_min, cfg_.scale_range_max,
                                                        cfg_.scale_range_sigma, 1.0}));
            blocks_.back()->Bind(0, ScaleVar(sgm), 0.0);
        }
    }
}

// Bias segment 0 carries the prior around 0 (the walk from a fixed 0); later segments the walk.
void WindowProblem::AddBiasBlocks() {
    for (int sgm = bias_first_; sgm <= bias_last_; ++sgm) {
        const double sigma = sgm == 0 ? cfg_.heading_bias_prior_rad_s : cfg_.heading_bias_rw_rad_s;
        blocks_.push_back(
            Core<RandomWalkTerm, 2>(TermFamily::kHeadingBiasWalk, RandomWalkTerm{sigma, 1.0, 0.0}));
        const int a = BiasVar(sgm - 1);
        blocks_.back()->Bind(0, a, a >= 0 || sgm == 0 ? 0.0 : state_.biases[sgm - 1]);
        blocks_.back()->Bind(1, BiasVar(sgm), 0.0);
    }
}

// ModelConfig::floor_sigma_m: a pose where the estimate is level is drawn to the floor nearest to
// its height when the window is built (the scale prior's form: a walk from a fixed floor). The
// estimate's heights and times come from the steps (their sums), over the window and the half
// level window on each side that the state holds: online, a pose near the newest one is judged
// on what came so far.
void WindowProblem::AddFloorBlocks() {
    const double half_s = 0.5 * cfg_.floor_level_window_s;
    std::size_t lo = first_, hi = last_;
    for (double span_s = 0.0; lo > 0 && span_s <= half_s; --lo) {
        span_s += std::max(state_.obs[lo].dt_s, 0.0);
    }
    for (double span_s = 0.0; hi + 1 < state_.obs.size() && span_s <= half_s;) {
        span_s += std::max(state_.obs[++hi].dt_s, 0.0);
    }
    std::vector<double> t_s(hi - lo + 1, 0.0), up_m(hi - lo + 1, 0.0);
    for (std::size_t i = lo + 1; i <= hi; ++i) {
        t_s[i - lo] = t_s[i - lo - 1] + std::max(state_.obs[i].dt_s, 0.0);
        up_m[i - lo] = up_m[i - lo - 1] + state_.obs[i].dup_m;
    }
    const std::vector<std::uint8_t> level =
        LevelSpans(t_s, up_m, cfg_.floor_level_window_s, cfg_.floor_level_height_m);
    for (std::size_t i = first_; i <= last_; ++i) {
        if (!level[i - lo]) continue;
        const double floor = NearestFloor(field_->floor_heights_m(), state_.poses[i].p.z());
        blocks_.push_back(
            Core<RandomWalkTerm, 2>(TermFamily::kFloorHeight,
                                    RandomWalkTerm{cfg_.floor_sigma_m, 1.0, cfg_.floor_robust_k}));
        blocks_.back()->Bind(0, -1, floor);
        blocks_.back()->Bind(1, PoseVar(i, 2), 0.0);
    }
}

// ModelConfig::lift_sigma_m: a pose in a lift ride (RideSpans over the steps the state holds
// within a minute of the window: online, a ride is found once its height change has come) is
// drawn to the nearest lift shaft.
void WindowProblem::AddLiftBlocks() {
    constexpr double kAround_s = 60.0;
    std::size_t lo = first_, hi = last_;
    for (double span_s = 0.0; lo > 0 && span_s <= kAround_s; --lo) {
        span_s += std::max(state_.obs[lo].dt_s, 0.0);
    }
    for (double span_s = 0.0; hi + 1 < state_.obs.size() && span_s <= kAround_s;) {
        span_s += std::max(state_.obs[++hi].dt_s, 0.0);
    }
    // obs[lo] is the slice's unused step 0: pose lo starts it.
    const std::vector<StepObservation> slice(state_.obs.begin() + lo, state_.obs.begin() + hi + 1);
    const std::vector<std::uint8_t> ride =
        RideSpans(slice, cfg_.ride_min_s, cfg_.ride_min_height_m, cfg_.ride_gap_s, cfg_.ride_lag_s);
    for (std::size_t i = first_; i <= last_; ++i) {
        if (!ride[i - lo]) continue;
        blocks_.push_back(Make<LiftDistanceBlock>(
            MapDistanceTerm{cfg_.lift_sigma_m, cfg_.lift_giveup_m, 1.0}, static_cast<int>(i)));
        for (int c = 0; c < 3; ++c) blocks_.back()->Bind(c, PoseVar(i, c), 0.0);
    }
}

void WindowProblem::BuildStructure(WindowUse use) {
    for (std::size_t i = first_; i <= last_; ++i) {
        AddStepBlocks(i);
        if (field_) {
            blocks_.push_back(Make<MapDistanceBlock>(
                MapDistanceTerm{cfg_.map_sigma_m, cfg_.map_giveup_m, cfg_.map_weight},
                static_cast<int>(i)));
            for (int c = 0; c < 3; ++c) blocks_.back()->Bind(c, PoseVar(i, c), 0.0);
        }
    }
    AddScaleBlocks();
    if (HasBias()) AddBiasBlocks();
    if (field_ && !state_.fix_height && cfg_.floor_sigma_m > 0.0 &&
        !field_->floor_heights_m().empty()) {
        AddFloorBlocks();
    }
    if (field_ && !state_.fix_height && cfg_.lift_sigma_m > 0.0 && !field_->lift_shafts().empty()) {
        AddLiftBlocks();
    }
    if (prior_) {
        blocks_.push_back(Make<BoundaryPriorBlock>(*prior_, static_cast<int>(first_ - 1)));
        for (int c = 0; c < 4; ++c) blocks_.back()->Bind(c, PoseVar(first_ - 1, c), 0.0);
        if (prior_->HasScale()) blocks_.back()->Bind(4, ScaleVar(prior_->scale_segment), 0.0);
    }
    for (std::size_t k = 0; k < constraint_pose_.size(); ++k) {
        for (int c = 0; c < 3; ++c)
            jac_.emplace_back(static_cast<int>(k), PoseVar(constraint_pose_[k], c));
    }
    if (use != WindowUse::kSolve) return;
    // Pass 1 notes every pair the blocks and the constraints' Hessians touch, pass 2 numbers
    // them in the order they are met. A step's blocks read the same variables one after the
    // other: such a block takes the pairs of the block before, already noted and numbered.
    SlotTable slots(n_vars_, PoseVar(last_, 3) + 1);
    auto same_as_previous = [&](std::size_t b) {
        return b > 0 && SameVariables(*blocks_[b - 1], *blocks_[b]);
    };
    auto pose_pairs = [&](std::size_t i, auto&& slot) {
        const int x = PoseVar(i, 0), y = PoseVar(i, 1), z = PoseVar(i, 2);
        return std::array<int, 6>{slot(x, x), slot(y, x), slot(y, y),
                                  slot(z, x), slot(z, y), slot(z, z)};
    };
    std::size_t pairs = 0;
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
        pairs += std::size_t(blocks_[b]->size() * (blocks_[b]->size() + 1) / 2);
        if (!same_as_previous(b)) slots.NoteBlock(*blocks_[b]);
    }
    for (std::size_t i = first_; i <= last_; ++i) {
        pose_pairs(i, [&](int r, int c) {
            slots.Note(r, c);
            return -1;
        });
    }
    slots.Allocate();
    hess_.reserve(slots.Capacity() + 16);
    // Every pair of a block's variables is numbered (the Hessian's structure), but the block's
    // entries list only the pairs of variables it reads: the others are exact zeros.
    block_entry_begin_.reserve(blocks_.size() + 1);
    block_entries_.reserve(pairs);
    // The current block's slots, (r, c <= r) at r (r + 1) / 2 + c.
    std::array<int, kMaxBlockVars*(kMaxBlockVars + 1) / 2> triangle{};
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
        const TermBlock& block = *blocks_[b];
        block_entry_begin_.push_back(static_cast<int>(block_entries_.size()));
        if (!same_as_previous(b)) {
            int* t = triangle.data();
            for (int r = 0; r < block.size(); ++r) {
                for (int c = 0; c <= r; ++c) {
                    const int vr = block.var(r), vc = block.var(c);
                    *t++ = vr >= 0 && vc >= 0 ? slots.Slot(vr, vc, hess_) : -1;
                }
            }
        }
        // The pairs of read variables, in the triangle's order.
        const unsigned reads = block.reads();
        for (unsigned rows = reads; rows != 0; rows &= rows - 1) {
            const int r = __builtin_ctz(rows);
            for (unsigned columns = reads & ((2u << r) - 1); columns != 0; columns &= columns - 1) {
                const int c = __builtin_ctz(columns);
                const int slot = triangle[std::size_t(r * (r + 1) / 2 + c)];
                if (slot >= 0) block_entries_.push_back({c * block.size() + r, slot});
            }
        }
    }
    block_entry_begin_.push_back(static_cast<int>(block_entries_.size()));
    pose_hess_slot_.resize(last_ - first_ + 1);
    for (std::size_t i = first_; i <= last_; ++i) {
        pose_hess_slot_[i - first_] =
            pose_pairs(i, [&](int r, int c) { return slots.Slot(r, c, hess_); });
    }
}

void WindowProblem::InitialPoint(double* x) const {
    for (std::size_t i = var_first_; i <= last_; ++i) {
        const PoseState& p = state_.poses[i];
        double* v = x + PoseVar(i, 0);
        v[0] = p.p.x(), v[1] = p.p.y(), v[2] = p.p.z(), v[3] = p.yaw_rad;
    }
    for (int sgm = seg_first_; sgm <= seg_last_; ++sgm) x[ScaleVar(sgm)] = state_.scales[sgm];
    for (int sgm = bias_first_; sgm <= bias_last_; ++sgm) x[BiasVar(sgm)] = state_.biases[sgm];
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

const std::vector<std::optional<TraversableSample>>& WindowProblem::Samples(const double* x) const {
    const std::size_t n = static_cast<std::size_t>(n_vars_);
    if (cache_x_.size() == n && std::equal(cache_x_.begin(), cache_x_.end(), x))
        return cache_samples_;
    cache_x_.assign(x, x + n);
    cache_samples_.resize(last_ - first_ + 1);
    // The terms read the centre distance; the corridor distance only the constraints do.
    const bool corridor = !constraint_pose_.empty();
    for (std::size_t i = first_; i <= last_; ++i) {
        auto& sample = cache_samples_[i - first_];
        if (!field_) {
            sample.reset();
        } else if (corridor) {
            sample = field_->Query(PosePosition(x, i));
        } else if (const auto centre = field_->QueryCentre(PosePosition(x, i))) {
            sample = TraversableSample{*centre, FieldSample{}};
        } else {
            sample.reset();
        }
    }
    return cache_samples_;
}

BlockContext WindowProblem::Context(const double* x) const {
    return BlockContext{field_, &Samples(x), first_};
}

Eigen::Vector3d WindowProblem::PosePosition(const double* x, std::size_t pose) const {
    const double* v = x + PoseVar(pose, 0);
    return {v[0], v[1], v[2]};
}

double WindowProblem::Objective(const double* x) const {
    return AccumulateBlocks(Context(x), x, 1.0, nullptr, nullptr);
}

void WindowProblem::Gradient(const double* x, double* grad) const {
    AccumulateBlocks(Context(x), x, 1.0, grad, nullptr);
}

double WindowProblem::ObjectiveGradientHessian(const double* x, double* grad,
                                               double* values) const {
    DRIFTCORR_CHECK(block_entry_begin_.size() == blocks_.size() + 1, "built with kLinearise");
    return AccumulateBlocks(Context(x), x, 1.0, grad, values);
}

// One pass over the blocks, each evaluated once for what is asked: their costs summed (the
// objective, returned), the gradient summed into `grad`, obj_factor times the Hessian into the
// slots of `values` (both zeroed first).
double WindowProblem::AccumulateBlocks(const BlockContext& ctx, const double* x, double obj_factor,
                                       double* grad, double* values) const {
    if (grad) std::fill(grad, grad + n_vars_, 0.0);
    if (values) std::fill(values, values + hess_.size(), 0.0);
    double f = 0.0;
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
        // The entries exist only in a problem built with kSolve, and only `values` needs them.
        const BlockEntry* begin = values ? block_entries_.data() + block_entry_begin_[b] : nullptr;
        const BlockEntry* end =
            values ? block_entries_.data() + block_entry_begin_[b + 1] : nullptr;
        f += blocks_[b]->Accumulate(ctx, x, obj_factor, grad, values, begin, end);
    }
    return f;
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
    DRIFTCORR_CHECK(block_entry_begin_.size() == blocks_.size() + 1, "built with kLinearise");
    const BlockContext ctx = Context(x);
    AccumulateBlocks(ctx, x, obj_factor, nullptr, values);
    for (std::size_t k = 0; k < constraint_pose_.size(); ++k) {
        const auto& fs = (*ctx.samples)[constraint_pose_[k] - first_];
        if (!fs) continue;
        const Eigen::Matrix3d& m = fs->corridor.hessian;
        const auto& sl = pose_hess_slot_[constraint_pose_[k] - first_];
        values[sl[0]] += lambda[k] * m(0, 0), values[sl[1]] += lambda[k] * m(1, 0);
        values[sl[2]] += lambda[k] * m(1, 1), values[sl[3]] += lambda[k] * m(2, 0);
        values[sl[4]] += lambda[k] * m(2, 1), values[sl[5]] += lambda[k] * m(2, 2);
    }
}

void WindowProblem::LineariseTerms(const double* x, std::vector<LinearisedTerm>& terms) const {
    const BlockContext ctx = Context(x);
    std::vector<LinearisedTerm> local;
    for (const auto& block : blocks_) {
        local.clear();
        block->Linearise(ctx, block->Gather(x), local);
        for (const LinearisedTerm& l : local) {
            LinearisedTerm t;
            t.family = block->family();
            t.pose = block->pose();
            for (int k = 0; k < l.size; ++k) {
                const int var = block->var(l.var[k]);
                if (var < 0 || l.jacobian[k] == 0.0) continue;
                t.var[t.size] = var;
                t.jacobian[t.size++] = l.jacobian[k];
            }
            t.residual = l.residual, t.information = l.information, t.chi2 = l.chi2;
            terms.push_back(t);
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
    for (int sgm = bias_first_; sgm <= bias_last_; ++sgm) state_.biases[sgm] = x[BiasVar(sgm)];
}

// Each step's and pose's terms belong to one window; a scale or bias segment that a window shares
// with the one before has its walk and range terms counted there, so they are left out of the
// later window's sum.
double SoftNll(TrajectoryState& s, const TraversableField* field, const ModelConfig& model,
               std::size_t last, std::size_t block_poses) {
    const std::size_t block = std::max<std::size_t>(block_poses, 1);
    if (last <= block) {
        WindowProblem problem(s, field, model, 1, last, std::vector<std::uint8_t>(last, 0),
                              WindowUse::kLinearise);
        std::vector<double> x(problem.NumVariables());
        problem.InitialPoint(x.data());
        return problem.Objective(x.data());
    }
    double nll = 0.0;
    for (std::size_t first = 1; first <= last; first += block) {
        const std::size_t end = std::min(last, first + block - 1);
        const WindowProblem problem(s, field, model, first, end,
                                    std::vector<std::uint8_t>(end - first + 1, 0),
                                    WindowUse::kLinearise);
        std::vector<double> x(problem.NumVariables());
        problem.InitialPoint(x.data());
        const bool shared_scale = s.scale_segment[first] == s.scale_segment[first - 1];
        const bool shared_bias =
            !s.bias_segment.empty() && s.bias_segment[first] == s.bias_segment[first - 1];
        const int scale_var = problem.ScaleVar(s.scale_segment[first]);
        const int bias_var = s.bias_segment.empty() ? -1 : problem.BiasVar(s.bias_segment[first]);
        const BlockContext ctx = problem.Context(x.data());
        for (const TermBlock* term : problem.Blocks()) {
            const TermFamily f = term->family();
            const int segment_var = term->var(term->size() - 1);
            if (first > 1 && shared_scale && segment_var == scale_var &&
                (f == TermFamily::kScaleWalk || f == TermFamily::kScaleRange)) {
                continue;
            }
            if (first > 1 && shared_bias && segment_var == bias_var &&
                f == TermFamily::kHeadingBiasWalk) {
                continue;
            }
            nll += term->Accumulate(ctx, x.data(), 1.0, nullptr, nullptr, nullptr, nullptr);
        }
    }
    return nll;
}

}  // namespace driftcorr
