// The definitions of what driftcorr/optim/incremental_corrector.h declares.
#include "driftcorr/optim/incremental_corrector.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "driftcorr/core/check.h"
#include "driftcorr/core/observables.h"
#include "driftcorr/optim/newton_solver.h"

namespace driftcorr {
namespace {

// RepairSpeedEpisodes: speeds compared over 0.3 s (three KITTI frames, the verdict's window),
// episodes up to 10 s, steps more than 25 % off the speed around them.
constexpr double kOutlierWindowS = 0.3, kOutlierEpisodeS = 10.0, kOutlierDeviation = 0.25;

double SecondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Share of poses [first, last] farther than limit_m from every traversable centre.
double OffRoadShare(const TrajectoryState& s, const TraversableField& field, std::size_t first,
                    std::size_t last, double limit_m) {
    std::size_t off = 0;
    for (std::size_t i = first; i <= last; ++i) {
        const auto d = field.CentreValue(s.poses[i].p);
        if (!d || *d > limit_m) ++off;
    }
    return double(off) / double(last - first + 1);
}

std::vector<std::uint8_t> GateConstraints(const TrajectoryState& s, const TraversableField* field,
                                          const ModelConfig& m, std::size_t first,
                                          std::size_t last) {
    std::vector<std::uint8_t> flags(last - first + 1, 0);
    if (!field || !m.hard_corridor) return flags;
    for (std::size_t i = first; i <= last; ++i) {
        const auto d = field->CorridorValue(s.poses[i].p);
        flags[i - first] = d && *d <= m.corridor_gate_m;
    }
    return flags;
}

// Poses [from, to] of a state, saved to be restored (a window's, not the whole trajectory's).
struct SavedPoses {
    std::size_t from;
    std::vector<PoseState> poses;
    SavedPoses(const TrajectoryState& s, std::size_t from_, std::size_t to)
        : from(from_), poses(s.poses.begin() + from_, s.poses.begin() + to + 1) {}
    void RestoreInto(TrajectoryState& s) const {
        std::copy(poses.begin(), poses.end(), s.poses.begin() + from);
    }
};

// The Newton solver's limits: the Ipopt options' (a window's), or with the final solve's own
// tolerance (refine_newton_tolerance).
NewtonOptions NewtonFrom(const IpoptOptions& opt, const CorrectorConfig& cfg, bool refine) {
    const double tolerance = refine ? cfg.refine_newton_tolerance : opt.tolerance;
    return {opt.max_iterations, tolerance, std::max(opt.acceptable_tolerance, tolerance),
            opt.on_iteration};
}

// The largest excess of a flagged pose's corridor distance over corridor_slack_m (0 if none).
double CorridorExcess(const TrajectoryState& s, const TraversableField& field, const ModelConfig& m,
                      std::size_t first, const std::vector<std::uint8_t>& flags) {
    double excess = 0.0;
    for (std::size_t k = 0; k < flags.size(); ++k) {
        if (!flags[k]) continue;
        const auto d = field.CorridorValue(s.poses[first + k].p);
        excess = std::max(excess, d.value_or(field.truncation_m()) - m.corridor_slack_m);
    }
    return excess;
}

// Solves one window; on failure re-solves it with the soft terms only.
// Incremental windows carry the soft terms only: a hard corridor on poses whose road is not yet
// settled pins them to whichever corridor they first touch (at junctions, the crossing road), and
// the chain then cannot recover (measured: kitti00 gicp ATE 213 m with, 7 m without). The hard
// constraint is imposed in the refinement, once the soft solution sits on its roads.
// With refine_newton the hard solve starts with the soft terms' minimum (Newton): where every
// constrained pose lies inside its corridor there, no constraint is active and that minimum is
// the constrained program's solution (its KKT point with zero multipliers); otherwise Ipopt solves
// the constrained program from it.
SolveReport SolveWindow(TrajectoryState& s, const TraversableField* field,
                        const CorrectorConfig& cfg, const IpoptOptions& opt, std::size_t first,
                        std::size_t last, CorrectionResult& result, bool hard,
                        const std::optional<PosePriorTerm>& prior = std::nullopt) {
    const std::vector<std::uint8_t> none(last - first + 1, 0);
    std::vector<std::uint8_t> flags =
        hard ? GateConstraints(s, field, cfg.model, first, last) : none;
    const std::size_t constrained = std::count(flags.begin(), flags.end(), std::uint8_t(1));
    if (hard) result.constrained_poses = constrained;
    if (!hard || constrained == 0) {
        WindowProblem problem(s, field, cfg.model, first, last, none, WindowUse::kSolve, prior);
        SolveReport rep = cfg.window_newton ? SolveWithNewton(problem, NewtonFrom(opt, cfg, hard))
                                            : SolveWithIpopt(problem, opt);
        result.iterations += rep.iterations;
        return rep;
    }
    if (cfg.refine_newton) {
        const SavedPoses saved(s, first - 1, last);
        const std::vector<double> saved_scales = s.scales, saved_biases = s.biases;
        WindowProblem soft(s, field, cfg.model, first, last, none, WindowUse::kSolve, prior);
        SolveReport rep = SolveWithNewton(soft, NewtonFrom(opt, cfg, hard));
        result.iterations += rep.iterations;
        if (Usable(rep.status)) {
            const double excess = CorridorExcess(s, *field, cfg.model, first, flags);
            if (excess <= opt.constraint_tolerance) {
                rep.max_violation_m = std::max(excess, 0.0);
                rep.message += " (no corridor constraint active)";
                return rep;
            }
        }
        // Ipopt from the same start as without this step (from the soft minimum it measurably
        // converged elsewhere: kitti05 cvo 7.65 against 7.45 m).
        saved.RestoreInto(s);
        s.scales = saved_scales;
        s.biases = saved_biases;
    }
    WindowProblem problem(s, field, cfg.model, first, last, flags, WindowUse::kSolve, prior);
    SolveReport rep = SolveWithIpopt(problem, opt);
    result.iterations += rep.iterations;
    if (Usable(rep.status)) return rep;
    ++result.window_retries;
    WindowProblem soft(s, field, cfg.model, first, last, none, WindowUse::kSolve, prior);
    SolveReport rep2 = SolveWithIpopt(soft, opt);
    result.iterations += rep2.iterations;
    rep2.message = rep.message + ", re-solved without hard constraints: " + rep2.message;
    return rep2;
}

bool HeightSettled(const TrajectoryState& s, std::size_t i) {
    return !s.height_settled.empty() && s.height_settled[i];
}

// Sum of |height change| over the steps into poses [first, last] whose reading is not settled [m].
double HeightTravel(const TrajectoryState& s, std::size_t first, std::size_t last) {
    double sum = 0.0;
    for (std::size_t i = first; i <= last; ++i) {
        if (!HeightSettled(s, i)) sum += std::abs(s.obs[i].dup_m);
    }
    return sum;
}

// The final solve of poses [1, n-1]: one window, or for a drive of more than
// cfg.refine_block_poses poses, consecutive windows of that many poses, each starting a tenth of a
// block before the end of the one before (its poses re-solved with the next block's terms), the
// poses before each held at their solved values. A block's memory is the whole drive's bound.
// Reports the first unusable block's outcome, else the last block's, and the first block that was
// re-solved without its corridor constraints (the verdict's signal); the iterations of all, the
// largest violation, the constrained poses of the poses each block settles.
SolveReport RefineInBlocks(TrajectoryState& s, const TraversableField* field,
                           const CorrectorConfig& cfg, const IpoptOptions& opt,
                           CorrectionResult& result) {
    const std::size_t n = s.poses.size(), block = std::max<std::size_t>(cfg.refine_block_poses, 2);
    if (n - 1 <= block) return SolveWindow(s, field, cfg, opt, 1, n - 1, result, true);
    const std::size_t step = block - block / 10;
    SolveReport report;
    std::string soft;  // the first block re-solved without its corridor constraints
    std::size_t blocks = 0, constrained = 0;
    int iterations = 0;
    double violation = 0.0;
    for (std::size_t first = 1;; first += step) {
        const std::size_t last = std::min(n - 1, first + block - 1);
        SolveReport rep = SolveWindow(s, field, cfg, opt, first, last, result, true);
        ++blocks;
        iterations += rep.iterations;
        violation = std::max(violation, rep.max_violation_m);
        if (soft.empty() && rep.message.find("without hard constraints") != std::string::npos) {
            soft =
                "poses " + std::to_string(first) + "-" + std::to_string(last) + ": " + rep.message;
        }
        const std::size_t settled_last = last == n - 1 ? last : first + step - 1;
        const std::vector<std::uint8_t> flags =
            GateConstraints(s, field, cfg.model, first, settled_last);
        constrained += std::count(flags.begin(), flags.end(), std::uint8_t(1));
        report = std::move(rep);
        if (!Usable(report.status) || last == n - 1) break;
    }
    result.constrained_poses = constrained;
    report.iterations = iterations;
    report.max_violation_m = violation;
    report.message = std::to_string(blocks) + " blocks of at most " + std::to_string(block) +
                     " poses, " + (Usable(report.status) ? "the last: " : "stopped at: ") +
                     report.message + (soft.empty() ? "" : "; " + soft);
    return report;
}

}  // namespace

bool PoorWindow(const TrajectoryState& s, const TraversableField& field, const CorrectorConfig& cfg,
                std::size_t first, std::size_t last, const SolveReport& report) {
    const double nll_per_pose = report.objective / double(last - first + 1);
    return !Usable(report.status) || nll_per_pose > cfg.restart_nll_per_pose ||
           OffRoadShare(s, field, first, last, cfg.restart_offroad_m) > cfg.restart_offroad_share;
}

// One incremental window (soft terms). When its solution leaves many poses off the roads, or
// explains the window poorly (a high NLL per pose), the window fell into a wrong basin (typically:
// a turn before the junction is reached, with the scale collapsing to keep the poses on the road
// they left), so it is re-solved from other step-length scale hypotheses, re-composed from the
// window's start, and the lowest NLL wins. A window that changes floor is also re-solved from
// other readings of its height changes (restart_height_gains): another floor's basin. Saves and
// restores the window's poses only (pose first-1 included: with a boundary prior it is a
// variable), so its cost does not grow with the trajectory.
SolveReport SolveSoftWindow(TrajectoryState& s, const TraversableField* field,
                            const CorrectorConfig& cfg, std::size_t first, std::size_t last,
                            const std::optional<PosePriorTerm>& prior, bool restarts,
                            CorrectionResult& result) {
    const SavedPoses saved(s, first - 1, last);
    const std::vector<double> saved_scales = s.scales, saved_biases = s.biases;  // few
    SolveReport best =
        SolveWindow(s, field, cfg, cfg.window_ipopt, first, last, result, false, prior);
    if (!restarts || !field) return best;
    // The hypotheses (scale factor, height-change gain) to start from as well.
    std::vector<std::pair<double, double>> starts;
    if (PoorWindow(s, *field, cfg, first, last, best)) {
        for (double factor : cfg.restart_scale_factors) starts.emplace_back(factor, 1.0);
    }
    if (!s.fix_height && HeightTravel(s, first, last) >= cfg.restart_height_change_m) {
        for (double gain : cfg.restart_height_gains) starts.emplace_back(1.0, gain);
    }
    if (starts.empty()) return best;
    SavedPoses best_poses(s, first - 1, last);
    std::vector<double> best_scales = s.scales, best_biases = s.biases;
    for (const auto& [factor, gain] : starts) {
        saved.RestoreInto(s);
        s.scales = saved_scales;
        s.biases = saved_biases;
        for (int g = s.scale_segment[first]; g <= s.scale_segment[last]; ++g) s.scales[g] *= factor;
        ComposeOdometry(s, first, last, gain);
        SolveReport rep =
            SolveWindow(s, field, cfg, cfg.window_ipopt, first, last, result, false, prior);
        ++result.window_restarts;
        if (Usable(rep.status) && (!Usable(best.status) || rep.objective < best.objective)) {
            best = rep;
            best_poses = SavedPoses(s, first - 1, last);
            best_scales = s.scales;
            best_biases = s.biases;
        }
    }
    best_poses.RestoreInto(s);
    s.scales = std::move(best_scales);
    s.biases = std::move(best_biases);
    return best;
}

namespace {

PlanarTrajectory ToTrajectory(const std::vector<double>& t_s, const TrajectoryState& s) {
    PlanarTrajectory out;
    out.t_s = t_s;
    for (const PoseState& p : s.poses) {
        out.p_en.emplace_back(p.p.x(), p.p.y());
        out.up_m.push_back(p.p.z());
        out.yaw_rad.push_back(p.yaw_rad);
    }
    return out;
}

}  // namespace

void ComposeOdometry(TrajectoryState& s, std::size_t from, std::size_t to, double height_gain) {
    for (std::size_t i = from; i <= to; ++i) {
        const double bias = s.bias_segment.empty() ? 0.0 : s.biases[s.bias_segment[i]];
        StepObservation o = s.obs[i];
        if (!HeightSettled(s, i)) o.dup_m *= height_gain;
        s.poses[i] = ComposeStep(s.poses[i - 1], o, s.scales[s.scale_segment[i]], s.fix_height,
                                 s.poses[i].p.z(), bias);
    }
}

void SeedNewScales(TrajectoryState& s, std::size_t from, std::size_t to) {
    for (int g = s.scale_segment[from - 1] + 1; g <= s.scale_segment[to]; ++g) {
        s.scales[g] = s.scales[g - 1];
    }
    if (s.bias_segment.empty()) return;  // likewise the heading-rate biases
    for (int g = s.bias_segment[from - 1] + 1; g <= s.bias_segment[to]; ++g) {
        s.biases[g] = s.biases[g - 1];
    }
}

PoseState ComposeStep(const PoseState& a, const StepObservation& o, double scale, bool fix_height,
                      double up_fixed_m, double bias_rad_s) {
    const double phi = a.yaw_rad + o.direction_rad;
    const double len = ScaledLength(o, scale);
    PoseState b;
    const double up = fix_height ? up_fixed_m : a.p.z() + o.dup_m;
    b.p = Eigen::Vector3d(a.p.x() + len * std::cos(phi), a.p.y() + len * std::sin(phi), up);
    b.yaw_rad = a.yaw_rad + o.dheading_rad + bias_rad_s * std::max(o.dt_s, 0.0);
    return b;
}

TrajectoryState BatchState(std::vector<StepObservation> obs, std::vector<PoseState> poses,
                           const CorrectorConfig& cfg, bool fix_height) {
    DRIFTCORR_CHECK(obs.size() == poses.size() && !obs.empty(), "one observation per pose");
    TrajectoryState s;
    s.obs = std::move(obs);
    RepairSpeedEpisodes(s.obs, cfg.model.outlier_accel_mps2, kOutlierWindowS, kOutlierEpisodeS,
                        kOutlierDeviation);
    if (!fix_height) {
        const ModelConfig& m = cfg.model;
        MoveRideLag(s.obs, m.ride_min_s, m.ride_min_height_m, m.ride_gap_s, m.ride_lag_s);
        if (m.tread_m > 0.0) {
            MarkStairTreads(s.obs, m.tread_m, m.tread_window_s, m.tread_rate_mps, m.ride_gap_s);
        }
    }
    const ModelConfig& m = cfg.model;
    if (m.step_length_exponent != 1.0) {
        const double median_m = MedianGaitStep(s.obs, m.max_speed_mps);
        for (StepObservation& o : s.obs) {
            ReadAtGait(o, median_m, m.step_length_exponent, m.max_speed_mps);
        }
    }
    s.scale_segment = ScaleSegments(s.obs, cfg.model.scale_segment_m);
    s.scales.assign(s.scale_segment.back() + 1, 1.0);
    s.bias_segment = BiasSegments(s.obs, cfg.model.heading_bias_segment_s);
    if (!s.bias_segment.empty()) s.biases.assign(s.bias_segment.back() + 1, 0.0);
    s.poses = std::move(poses);
    s.fix_height = fix_height;
    return s;
}

std::size_t RepairRecentEpisodes(TrajectoryState& s, std::size_t end, const ModelConfig& model) {
    std::size_t from = end;  // the span's first step
    for (double span_s = 0.0; from > 1 && span_s < 2.0 * kOutlierEpisodeS; --from) {
        span_s += std::max(s.obs[from].dt_s, 0.0);
    }
    // slice[0] stands for the step before the span (RepairSpeedEpisodes leaves index 0 alone).
    std::vector<StepObservation> slice(s.obs.begin() + (from - 1), s.obs.begin() + end + 1);
    const std::size_t episodes = RepairSpeedEpisodes(
        slice, model.outlier_accel_mps2, kOutlierWindowS, kOutlierEpisodeS, kOutlierDeviation);
    if (episodes > 0) std::copy(slice.begin() + 1, slice.end(), s.obs.begin() + from);
    return episodes;
}

TrajectoryState InitialState(const PlanarTrajectory& est, const CorrectorConfig& cfg,
                             bool fix_height) {
    std::vector<PoseState> poses(est.size());
    const std::vector<double> yaw = UnwrappedHeadings(est, cfg.stationary_m);
    for (std::size_t i = 0; i < est.size(); ++i) {
        poses[i].p = Eigen::Vector3d(est.p_en[i].x(), est.p_en[i].y(), est.up_m[i]);
        poses[i].yaw_rad = yaw[i];
    }
    return BatchState(ComputeObservations(est, cfg.stationary_m), std::move(poses), cfg,
                      fix_height);
}

IncrementalCorrector::IncrementalCorrector(TrajectoryState state, const TraversableField* field,
                                           const CorrectorConfig& config)
    : state_(std::move(state)), field_(field), cfg_(config) {
    DRIFTCORR_CHECK(!state_.poses.empty() && state_.obs.size() == state_.poses.size() &&
                        state_.scale_segment.size() == state_.poses.size(),
                    "inconsistent state");
    dist_ = PathPositions(state_.obs);
}

IncrementalCorrector::IncrementalCorrector(TrajectoryState state, const TraversableField* field,
                                           const CorrectorConfig& config, Corrected)
    : IncrementalCorrector(std::move(state), field, config) {
    done_ = size() - 1;
}

TrajectoryState StartState(const PoseState& pose0, bool fix_height, const ModelConfig& model) {
    TrajectoryState s;
    s.obs.assign(1, StepObservation{});
    s.scale_segment.assign(1, 0);
    s.poses.assign(1, pose0);
    s.scales.assign(1, 1.0);
    if (model.heading_bias_segment_s > 0.0) {
        s.bias_segment.assign(1, 0);
        s.biases.assign(1, 0.0);
    }
    s.fix_height = fix_height;
    return s;
}

// Step i belongs to scale segment floor(path before it / scale_segment_m) (ScaleSegments) and to
// bias segment floor(time before it / heading_bias_segment_s) (BiasSegments).
void AppendStep(TrajectoryState& s, const PoseState& initial, const StepObservation& step,
                double path_before_m, double elapsed_before_s, const ModelConfig& model) {
    const int segment = static_cast<int>(path_before_m / model.scale_segment_m);
    s.obs.push_back(step);
    s.scale_segment.push_back(segment);
    s.poses.push_back(initial);
    if (segment + 1 > static_cast<int>(s.scales.size())) s.scales.resize(segment + 1, 1.0);
    if (s.bias_segment.empty()) return;
    const int bias_segment = static_cast<int>(elapsed_before_s / model.heading_bias_segment_s);
    s.bias_segment.push_back(bias_segment);
    if (bias_segment + 1 > static_cast<int>(s.biases.size()))
        s.biases.resize(bias_segment + 1, 0.0);
}

IncrementalCorrector::IncrementalCorrector(const PoseState& pose0, bool fix_height,
                                           const TraversableField* field,
                                           const CorrectorConfig& config)
    : state_(StartState(pose0, fix_height, config.model)), field_(field), cfg_(config) {
    dist_.assign(1, 0.0);
}

void IncrementalCorrector::Append(const PoseState& initial, const StepObservation& step) {
    AppendStep(state_, initial, step, dist_.back(), elapsed_s_, cfg_.model);
    elapsed_s_ += std::max(step.dt_s, 0.0);
    dist_.push_back(dist_.back() + step.length_m);
}

bool IncrementalCorrector::ChunkCompleteAt(std::size_t end) const {
    return dist_[end] - dist_[done_] >= cfg_.chunk_m || end - done_ >= cfg_.max_chunk_poses;
}

std::size_t IncrementalCorrector::NextChunkEnd() const {
    std::size_t i = done_ + 1;
    while (i + 1 < size() && !ChunkCompleteAt(i)) ++i;
    return i;
}

void IncrementalCorrector::SolveChunk(std::size_t end) {
    DRIFTCORR_CHECK(done_ < end && end < size(), "chunk must add poses");
    const auto t0 = std::chrono::steady_clock::now();
    SeedNewScales(state_, done_ + 1, end);
    ComposeOdometry(state_, done_ + 1, end);
    const std::size_t first = WindowFirst(end);
    SolveReport rep = SolveSoftWindow(state_, field_, cfg_, first, end, std::nullopt, true, stats_);
    ++stats_.windows;
    if (!Usable(rep.status)) ++stats_.window_failures;
    done_ = end;
    stats_.incremental_s += SecondsSince(t0);
}

std::size_t IncrementalCorrector::WindowFirst(std::size_t end) const {
    std::size_t first = end;
    while (first > 1 && dist_[end] - dist_[first - 1] <= cfg_.window_m &&
           end - first + 1 < cfg_.max_window_poses) {
        --first;
    }
    return first;
}

void IncrementalCorrector::SolveRemaining(const ProgressCallback& progress) {
    while (done_ + 1 < size()) {
        SolveChunk(NextChunkEnd());
        if (progress) progress({"incremental", done_ + 1, size()});
    }
}

void IncrementalCorrector::ReplaceObservations(std::vector<StepObservation> obs) {
    DRIFTCORR_CHECK(obs.size() == size(), "ReplaceObservations needs one observation a pose");
    state_.obs = std::move(obs);
}

double IncrementalCorrector::Nll() {
    DRIFTCORR_CHECK(size() >= 2, "Nll needs a step");
    return SoftNll(state_, field_, cfg_.model, size() - 1);
}

CorrectionResult IncrementalCorrector::Finish(const std::vector<double>& t_s,
                                              const ProgressCallback& progress) {
    DRIFTCORR_CHECK(size() >= 3 && done_ + 1 == size() && t_s.size() == size(),
                    "Finish preconditions");
    CorrectionResult result = stats_;
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t n = size();
    if (cfg_.refine) {
        IpoptOptions opt = cfg_.refine_ipopt;
        int iterations = 0;  // over the Newton and Ipopt solves of the final solve
        if (progress) {
            opt.on_iteration = [&](int) { progress({"refining", n, n, ++iterations}); };
        }
        result.refine_report = RefineInBlocks(state_, field_, cfg_, opt, result);
        if (progress) progress({"refine", n, n});
        result.status = result.refine_report.status;
        result.message = "refine: " + result.refine_report.message;
    } else {
        result.status = result.window_failures == 0 ? SolveStatus::kSuccess : SolveStatus::kFailed;
        result.message = std::to_string(result.window_failures) + " window(s) failed";
    }
    result.refine_s = SecondsSince(t0);
    result.scale_min = *std::min_element(state_.scales.begin(), state_.scales.end());
    result.scale_max = *std::max_element(state_.scales.begin(), state_.scales.end());
    result.step_length_m.resize(n);
    result.height_change_m.resize(n);
    result.tread_steps.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        result.tread_steps[i] = state_.obs[i].tread ? 1 : 0;
        result.step_length_m[i] = i > 0 ? state_.obs[i].length_m : 0.0;
        result.height_change_m[i] = i > 0 ? state_.obs[i].dup_m : 0.0;
        result.repaired_steps += state_.obs[i].repaired ? 1 : 0;
    }
    result.nll = Nll();
    if (Usable(result.status)) {
        result.corrected = ToTrajectory(t_s, state_);
        if (state_.fix_height) {  // the heights as estimated, at bounded grades
            result.grades = BoundGrades(result.corrected.p_en, cfg_.model.grade_stretch_m,
                                        cfg_.model.max_grade, result.corrected.up_m);
        }
    }
    if (Usable(result.status) && cfg_.compute_covariance) AddCovariance(result);
    return result;
}

void IncrementalCorrector::AddCovariance(CorrectionResult& result) const {
    const auto t0 = std::chrono::steady_clock::now();
    result.covariance = ComputeCovariance(state_, field_, cfg_.model, cfg_.covariance);
    result.covariance_s = SecondsSince(t0);
}

}  // namespace driftcorr
