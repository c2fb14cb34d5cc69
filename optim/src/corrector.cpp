// The definitions of what driftcorr/optim/corrector.h declares.
#include "driftcorr/optim/corrector.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"
#include "driftcorr/core/format.h"
#include "driftcorr/core/metrics.h"
#include "driftcorr/core/observables.h"
#include "driftcorr/optim/incremental_corrector.h"
#include "driftcorr/optim/window_problem.h"
#include "floor_hypotheses.h"
#include "whole_corrections.h"

namespace driftcorr {

std::optional<ParamProblem> CorrectorConfig::FindProblem() const {
    if (auto problem = CheckRows(kCorrectorParams, *this)) return problem;
    if (!(window_m >= chunk_m)) {
        return RelationProblem("window_m", window_m, ">=", "chunk_m", chunk_m);
    }
    if (max_window_poses < max_chunk_poses) {
        return RelationProblem("max_window_poses", double(max_window_poses),
                               ">=", "max_chunk_poses", double(max_chunk_poses));
    }
    if (start_scales.empty())
        return ParamProblem{"start_scales", "must list a scale (got none)", ""};
    for (double v : start_scales) {
        if (!(v >= kScaleMin && v <= kScaleMax)) {
            return ParamProblem{"start_scales",
                                "must lie in [" + FormatParamNumber(kScaleMin) + ", " +
                                    FormatParamNumber(kScaleMax) + "] (got " +
                                    FormatParamNumber(v) + ")",
                                ""};
        }
    }
    return std::nullopt;
}

std::string CorrectorConfig::Validate() const {
    if (std::string m = model.Validate(); !m.empty()) return m;
    if (std::string m = ToMessage(kCorrectorParams.section, FindProblem()); !m.empty()) return m;
    return covariance.Validate();
}

CorrectorConfig CorrectorConfig::Pedestrian() {
    CorrectorConfig c;
    c.model = ModelConfig::Pedestrian();
    c.chunk_m = 15.0;
    c.window_m = 60.0;
    c.restart_offroad_m = 2.0;
    c.covariance.step_error_sd = 0.10;
    c.covariance.step_error_correlation_m = 10.0;
    c.start_scales = {1.0, 1.25, 1.5};
    c.floor_gain_sigma = 0.03;
    return c;
}

namespace {

// Share of poses within reach of the map: inside the field and closer than 3 giveup distances to
// a traversable place (where the map term still pulls).
double MapCoverage(const PlanarTrajectory& t, const TraversableField& field, double reach_m) {
    std::size_t covered = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        const auto q = field.Query(Eigen::Vector3d(t.p_en[i].x(), t.p_en[i].y(), t.up_m[i]));
        if (q && q->centre.value <= reach_m) ++covered;
    }
    return t.size() ? double(covered) / double(t.size()) : 0.0;
}

// RMS of |a[i] - b[i]|; precondition: same size, not empty.
double RmsDistance(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]).squaredNorm();
    return std::sqrt(sum / double(a.size()));
}

}  // namespace

void DiagnoseCorrection(const PlanarTrajectory& estimate, const TraversableField* field,
                        const CorrectorConfig& cfg, CorrectionResult& r) {
    double path_m = 0.0;
    std::size_t jumps = 0;
    for (std::size_t i = 1; i < estimate.size(); ++i) {
        const double step = (estimate.p_en[i] - estimate.p_en[i - 1]).norm();
        path_m += step;
        if (step > cfg.model.max_speed_mps * (estimate.t_s[i] - estimate.t_s[i - 1])) ++jumps;
    }
    if (path_m <= cfg.stationary_m * estimate.size()) {
        r.warnings.push_back("the estimate does not move (" + FormatFixed(path_m, 2) +
                             " m in all): nothing to correct");
    }
    if (jumps > 0) {
        r.warnings.push_back(std::to_string(jumps) + " step(s) faster than model.max_speed_mps (" +
                             FormatFixed(cfg.model.max_speed_mps, 1) +
                             " m/s) treated as discontinuities of the estimate (not scaled)");
    }
    if (field) {
        const PlanarTrajectory& t = Usable(r.status) ? r.corrected : estimate;
        const double coverage = MapCoverage(t, *field, 3.0 * cfg.model.map_giveup_m);
        if (coverage == 0.0) {
            r.warnings.push_back(
                "the map covers none of the drive (no pose within reach of a "
                "traversable place): the output is the odometry alone");
        } else if (coverage < 0.5) {
            r.warnings.push_back("the map covers only " + FormatPercent(coverage) +
                                 " of the drive: the rest is the odometry alone");
        }
    }
    if (r.repaired_steps > 0) {
        r.warnings.push_back(std::to_string(r.repaired_steps) +
                             " odometry step(s) inside dropped-step episodes (speed falling and "
                             "recovering faster than model.outlier_accel_mps2) observed at the "
                             "speed around them");
    }
    if (r.scale_min <= kScaleMin * 1.01 || r.scale_max >= kScaleMax * 0.99) {
        r.warnings.push_back("the step-length scale reached its bound (" +
                             FormatFixed(r.scale_min, 2) + ".." + FormatFixed(r.scale_max, 2) +
                             "): map and odometry disagree; check the anchor and the map");
    }
}

namespace {

// The heading-rate bias is a freedom of the model, kept only where the data support it: the
// final solve of `kept` (a correction without the bias, `result` its outcome) is repeated with
// the bias's unknowns added (ModelConfig::heading_bias_segment_s, all 0 to start), and the bias
// stays when the NLL falls by more than the Bayesian information criterion's price of those
// unknowns, k / 2 ln n (k bias segments, n poses). Replaces `kept` and `result` when it stays;
// returns the repeated solve's outcome (its counters).
CorrectionResult DecideHeadingBias(const std::vector<double>& t_s, const TraversableField* field,
                                   const CorrectorConfig& cfg,
                                   std::optional<IncrementalCorrector>& kept,
                                   CorrectionResult& result) {
    TrajectoryState state = kept->state();
    state.bias_segment = BiasSegments(state.obs, cfg.model.heading_bias_segment_s);
    state.biases.assign(state.bias_segment.back() + 1, 0.0);
    const double k = double(state.biases.size());
    CorrectorConfig biased = cfg;
    biased.compute_covariance = false;
    IncrementalCorrector inc(std::move(state), field, biased, IncrementalCorrector::Corrected{});
    CorrectionResult with = inc.Finish(t_s);
    HeadingBiasDecision d;
    d.nll_with = Usable(with.status) ? with.nll : std::numeric_limits<double>::quiet_NaN();
    d.nll_without = result.nll;
    d.price = 0.5 * k * std::log(double(t_s.size()));
    d.kept = Usable(with.status) && d.nll_with + d.price < d.nll_without;
    if (d.kept) {
        CorrectionResult stats = with;
        kept.emplace(std::move(inc));
        result = std::move(stats);
    }
    result.heading_bias = d;
    return with;
}

}  // namespace

// The incremental pass and the refinement live in IncrementalCorrector (shared with the online
// corrector); the batch case hands it the whole estimate at once, once per start scale.
IncrementalCorrector CorrectFromStarts(const PlanarTrajectory& estimate,
                                       const TraversableField* field, const CorrectorConfig& cfg,
                                       CorrectionResult& result, const ProgressCallback& progress) {
    DRIFTCORR_CHECK(estimate.size() >= 3, "CorrectFromStarts needs at least 3 poses");
    const bool planar = !field || field->planar();
    return CorrectFromStarts(InitialState(estimate, cfg, planar), estimate.t_s, field, cfg, result,
                             progress);
}

namespace {

// The covariance of the mixture of the starts' corrections about the kept one: each start weighs
// exp(-(its NLL - the kept one's)) and adds its offset from the kept path (squared) to the kept
// one's covariance, which stands in for its own, so that where two starts' corrections of close
// NLL part the covariance says so. Starts that met the kept one's basin add nothing.
// `kept_start`: the start whose correction is the result (paths.size() when a floor hypothesis
// replaced it).
void AddStartsToCovariance(const std::vector<std::vector<Eigen::Vector2d>>& paths,
                           const std::vector<double>& nll, std::size_t kept_start,
                           CorrectionResult& result) {
    if (result.covariance.status != CovarianceStatus::kOk) return;
    std::vector<PoseCovariance>& poses = result.covariance.poses;
    const std::vector<Eigen::Vector2d>& kept = result.corrected.p_en;
    double total = 1.0;  // the kept correction's weight
    std::vector<Eigen::Matrix2d> spread(poses.size(), Eigen::Matrix2d::Zero());
    for (std::size_t k = 0; k < paths.size(); ++k) {
        if (k == kept_start || paths[k].size() != kept.size() || !std::isfinite(nll[k])) continue;
        const double w = std::exp(-std::max(nll[k] - result.nll, 0.0));
        total += w;
        for (std::size_t i = 0; i < poses.size(); ++i) {
            const Eigen::Vector2d d = paths[k][i] - kept[i];
            spread[i] += w * d * d.transpose();
        }
    }
    for (std::size_t i = 0; i < poses.size(); ++i) poses[i].xy_m2 += spread[i] / total;
}

// Each start scale runs the whole correction (incremental pass and refinement) from `initial`;
// the lowest NLL is kept. Returns each start's NLL (NaN where unusable) and corrected positions.
std::pair<std::vector<double>, std::vector<std::vector<Eigen::Vector2d>>> SearchStartScales(
    TrajectoryState initial, const CorrectorConfig& cfg, WholeCorrections& run,
    KeptCorrection& kept) {
    std::vector<double> nll;
    std::vector<std::vector<Eigen::Vector2d>> paths;
    for (std::size_t k = 0; k < cfg.start_scales.size(); ++k) {
        // The last start takes the initial state itself, not a copy.
        TrajectoryState state = k + 1 < cfg.start_scales.size() ? initial : std::move(initial);
        std::fill(state.scales.begin(), state.scales.end(), cfg.start_scales[k]);
        auto [inc, r] = run.Run(std::move(state), cfg.start_scales[k], nullptr);
        nll.push_back(Usable(r.status) ? r.nll : std::numeric_limits<double>::quiet_NaN());
        paths.push_back(Usable(r.status) ? r.corrected.p_en : std::vector<Eigen::Vector2d>{});
        if (!kept.Better(r)) continue;
        kept.Keep(std::move(inc), std::move(r));
        kept.result.start_chosen = k;
    }
    return {std::move(nll), std::move(paths)};
}

}  // namespace

// The start scales (SearchStartScales), then the floor hypotheses (TryOtherFloors, 3D with the
// floors known), then the heading-rate bias's decision (DecideHeadingBias); the counters add up
// over every correction. The windows' own floor restarts see a window of path: a stay that fits
// the wrong floor's walkways for its first tens of metres (the floors of a building are alike near
// their lifts) keeps that floor, and what denies it (walkways that floor does not have, a stair
// climb from it to no floor) comes later, hence the whole corrections on other floors. Time: one
// correction per start and per floor tried.
IncrementalCorrector CorrectFromStarts(TrajectoryState initial, const std::vector<double>& t_s,
                                       const TraversableField* field, const CorrectorConfig& cfg,
                                       CorrectionResult& result, const ProgressCallback& progress) {
    DRIFTCORR_CHECK(initial.poses.size() >= 3 && t_s.size() == initial.poses.size(),
                    "CorrectFromStarts needs at least 3 poses and a time stamp for each");
    DRIFTCORR_CHECK(!cfg.start_scales.empty(), "CorrectFromStarts needs a start scale");
    CorrectorConfig each = cfg;
    each.compute_covariance = false;
    // The heading-rate bias as a freedom: every correction below runs without it, and the final
    // solve of the kept one is then repeated with it (DecideHeadingBias).
    const bool decide_bias = cfg.decide_heading_bias && cfg.model.heading_bias_segment_s > 0.0;
    if (decide_bias) {
        each.model.heading_bias_segment_s = 0.0;
        initial.bias_segment.clear();
        initial.biases.clear();
    }
    const bool floor_hypotheses = FloorHypotheses(field, initial.fix_height, cfg);
    WholeCorrections run(t_s, field, each, cfg.model.scale_prior_mean, progress);
    KeptCorrection kept{std::nullopt, result};
    std::optional<TrajectoryState> observed;  // the observations as they are, for the floors
    if (floor_hypotheses) observed = initial;
    auto [nll, paths] = SearchStartScales(std::move(initial), cfg, run, kept);
    const std::size_t start_chosen = result.start_chosen;
    std::vector<CorrectionResult::FloorHypothesis> tried;
    if (floor_hypotheses && Usable(result.status)) {
        tried =
            TryOtherFloors(*observed, cfg.start_scales[start_chosen], t_s, *field, cfg, run, kept);
    }
    CorrectionResult& work = run.work();
    if (decide_bias && Usable(result.status)) {
        CorrectionResult with = DecideHeadingBias(t_s, field, cfg, kept.corrector, result);
        work.iterations += with.iterations, work.refine_s += with.refine_s;
    }
    result.floor_hypotheses = std::move(tried);
    result.start_chosen = start_chosen;
    result.start_scales = cfg.start_scales;
    result.start_nll = std::move(nll);
    const std::vector<Eigen::Vector2d>& kept_path = paths[start_chosen];
    for (const std::vector<Eigen::Vector2d>& path : paths) {
        result.start_rms_m.push_back(path.empty() || kept_path.empty()
                                         ? std::numeric_limits<double>::quiet_NaN()
                                         : RmsDistance(path, kept_path));
    }
    result.windows = work.windows, result.window_retries = work.window_retries;
    result.window_restarts = work.window_restarts, result.iterations = work.iterations;
    result.incremental_s = work.incremental_s, result.refine_s = work.refine_s;
    if (Usable(result.status) && cfg.compute_covariance) {
        kept.corrector->AddCovariance(result);
        const bool floor_kept =
            std::any_of(result.floor_hypotheses.begin(), result.floor_hypotheses.end(),
                        [](const auto& h) { return h.kept; });
        AddStartsToCovariance(paths, result.start_nll, floor_kept ? paths.size() : start_chosen,
                              result);
    }
    return std::move(*kept.corrector);
}

namespace {

// The two-sided 95 % quantile of the standard normal.
constexpr double kNormal95 = 1.959963984540054;

// The least share of poses inside the 95 % region that does not reject "the input is as likely
// as the truth" (AgreementShareThreshold): the poses are not independent, the map's error holding
// along a street, so the sample is the path's number of map-offset correlation lengths
// (CovarianceConfig::map_offset_correlation_m).
double AgreementThreshold(const PlanarTrajectory& estimate, const CorrectorConfig& cfg) {
    return AgreementShareThreshold(PathLength(estimate) / cfg.covariance.map_offset_correlation_m);
}

// Keeps the input as the result (CorrectionResult::input_kept).
void KeepInput(const PlanarTrajectory& estimate, CorrectionResult& result) {
    result.input_kept = true;
    result.corrected = estimate;
    result.scale_min = result.scale_max = 1.0;
    result.grades = GradeBound{};  // the input's heights, unchanged
}

// The second moment about `kept` of the error of a kept trajectory whose offset from the
// correction is kept - correction: each pose's covariance (the correction's) plus the outer product
// of its offset (East, North, the height where the covariance has one, the heading where both
// trajectories have one).
void AddOffsets(const PlanarTrajectory& correction, const PlanarTrajectory& kept,
                std::vector<PoseCovariance>& poses) {
    const bool yaw = correction.HasYaw() && kept.HasYaw();
    for (std::size_t i = 1; i < poses.size() && i < kept.size() && i < correction.size(); ++i) {
        const Eigen::Vector4d d(kept.p_en[i].x() - correction.p_en[i].x(),
                                kept.p_en[i].y() - correction.p_en[i].y(),
                                poses[i].z_m2 > 0.0 ? kept.up_m[i] - correction.up_m[i] : 0.0,
                                yaw ? AngleDiff(kept.yaw_rad[i], correction.yaw_rad[i]) : 0.0);
        poses[i] = ToPoseCovariance(ToPoseMatrix(poses[i]) + d * d.transpose());
    }
}

// The BIC price of a correction's unknowns beyond one scale: (scales - 1 + heading-rate biases
// kept) / 2 ln n.
double FreedomPrice(const TrajectoryState& s) {
    const double k = double(s.scales.size() - 1 + s.biases.size());
    return 0.5 * k * std::log(double(s.poses.size()));
}

// Adds `from`'s work counters (windows, restarts, iterations, times) to `to`'s.
void AddWork(const CorrectionResult& from, CorrectionResult& to) {
    to.windows += from.windows, to.window_retries += from.window_retries;
    to.window_restarts += from.window_restarts, to.iterations += from.iterations;
    to.incremental_s += from.incremental_s, to.refine_s += from.refine_s;
}

// Sets `to`'s work counters to `work`'s (every solve's, added up).
void SetWork(const CorrectionResult& work, CorrectionResult& to) {
    to.windows = 0, to.window_retries = 0, to.window_restarts = 0;
    to.iterations = 0, to.incremental_s = 0.0, to.refine_s = 0.0;
    AddWork(work, to);
}

// A final solve repeated from `correction`'s solution (`refined`) stands for that correction:
// it takes the correction's heading-bias decision and start scales.
void TakeStartsOf(const CorrectionResult& correction, CorrectionResult& refined) {
    refined.heading_bias = correction.heading_bias;
    refined.start_scales = correction.start_scales, refined.start_nll = correction.start_nll;
    refined.start_rms_m = correction.start_rms_m, refined.start_chosen = correction.start_chosen;
}

// A state of one scale for the whole drive with the walk's segments instead (one per
// model.scale_segment_m), each at that scale: its final solve repeated with the walk
// (CorrectorConfig::decide_scale_walk, one_scale_start).
TrajectoryState WithWalkSegments(TrajectoryState state, const ModelConfig& model) {
    state.scale_segment = ScaleSegments(state.obs, model.scale_segment_m);
    state.scales.assign(state.scale_segment.back() + 1, state.scales.front());
    return state;
}

// The scale walk as a freedom (CorrectorConfig::decide_scale_walk): one scale for the whole drive
// first; its final solve repeated with the walk's segments; when that lowers the NLL by more than
// the walk's price, the whole correction with the walk. Keeps the lowest NLL plus price, with its
// covariance; the work counters add up over every solve.
void CorrectWithDecidedScaleWalk(const PlanarTrajectory& estimate, const TraversableField* field,
                                 const CorrectorConfig& cfg, CorrectionResult& result,
                                 const ProgressCallback& progress) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CorrectorConfig one = cfg, walk = cfg;
    one.compute_covariance = walk.compute_covariance = false;
    const double path_m = PathLength(estimate);
    one.model.scale_segment_m = 2.0 * path_m + 1.0;  // one segment (repaired steps are longer)
    std::optional<IncrementalCorrector> kept;
    kept.emplace(CorrectFromStarts(estimate, field, one, result, progress));
    ScaleWalkDecision d;
    d.nll_refined = d.nll_walk = d.price_refined = d.price_walk = nan;
    d.nll_one_scale = Usable(result.status) ? result.nll : nan;
    d.price_one_scale = FreedomPrice(kept->state());
    TrajectoryState state = WithWalkSegments(kept->state(), cfg.model);
    if (Usable(result.status) && state.scales.size() > 1) {
        const double price = FreedomPrice(state);
        IncrementalCorrector inc(std::move(state), field, walk, IncrementalCorrector::Corrected{});
        CorrectionResult refined = inc.Finish(estimate.t_s);
        CorrectionResult whole;
        std::optional<IncrementalCorrector> winc;
        if (Usable(refined.status)) {
            d.nll_refined = refined.nll, d.price_refined = price;
            if (refined.nll + price < result.nll + d.price_one_scale) {
                winc.emplace(CorrectFromStarts(estimate, field, walk, whole, progress));
                if (Usable(whole.status)) {
                    d.nll_walk = whole.nll, d.price_walk = FreedomPrice(winc->state());
                }
            }
        }
        CorrectionResult work;  // every solve's counters
        AddWork(result, work), AddWork(refined, work), AddWork(whole, work);
        const double best = result.nll + d.price_one_scale;
        const double refined_score = Usable(refined.status) ? d.nll_refined + price : best;
        if (Usable(whole.status) && d.nll_walk + d.price_walk < std::min(best, refined_score)) {
            d.kept = ScaleWalkDecision::Kept::kWalk;
            kept = std::move(winc);
            result = std::move(whole);
        } else if (refined_score < best) {
            d.kept = ScaleWalkDecision::Kept::kRefined;
            kept.emplace(std::move(inc));
            TakeStartsOf(result, refined);
            result = std::move(refined);
        }
        SetWork(work, result);
    }
    result.scale_walk = d;
    if (Usable(result.status) && cfg.compute_covariance) kept->AddCovariance(result);
}

// The state `s` with one scale for the whole drive: the median of its segments' scales, each
// weighted by its steps (CorrectorConfig::one_scale_start).
TrajectoryState WithOneScale(TrajectoryState s) {
    std::vector<std::pair<double, std::size_t>> by_scale;  // (scale, steps)
    for (std::size_t k = 0; k < s.scales.size(); ++k) by_scale.emplace_back(s.scales[k], 0);
    for (std::size_t i = 1; i < s.scale_segment.size(); ++i) ++by_scale[s.scale_segment[i]].second;
    std::sort(by_scale.begin(), by_scale.end());
    std::size_t total = 0, below = 0;
    for (const auto& [scale, steps] : by_scale) total += steps;
    double median = by_scale.front().first;
    for (const auto& [scale, steps] : by_scale) {
        median = scale;
        below += steps;
        if (2 * below >= total) break;
    }
    std::fill(s.scale_segment.begin(), s.scale_segment.end(), 0);
    s.scales.assign(1, median);
    return s;
}

// How far one scale's NLL must lie below the walk's to be another basin, not the solvers'
// tolerance.
constexpr double kLowerNll = 1e-3;
// The most iterations of the one-scale solve (CorrectFromOneScaleToo).
constexpr int kProbeIterations = 10;

// CorrectorConfig::one_scale_start: the correction with the walk; its solution with one scale
// (the median) solved again with one scale, a solution of the same model (every step of the walk
// zero). Where that NLL is lower, the walk's solution is a poorer basin: the one-scale solution,
// refined with the walk's segments, is kept, with its covariance, and its corrector returned.
// The work counters add up.
IncrementalCorrector CorrectFromOneScaleToo(TrajectoryState initial, const std::vector<double>& t_s,
                                            const TraversableField* field,
                                            const CorrectorConfig& cfg, CorrectionResult& result,
                                            const ProgressCallback& progress) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CorrectorConfig one = cfg, walk = cfg;
    one.compute_covariance = walk.compute_covariance = false;
    // One segment, as decide_scale_walk's (repaired steps are longer than estimated).
    one.model.scale_segment_m = 2.0 * PathPositions(initial.obs).back() + 1.0;
    // A probe (at most kProbeIterations of Newton, then of Ipopt): a one-scale basin lies a few
    // Newton steps away, and a drive that one scale does not describe (dropped odometry steps)
    // would take a hundred; a probe stopped short is not usable, and the walk's solution stays.
    one.refine_ipopt.max_iterations = std::min(one.refine_ipopt.max_iterations, kProbeIterations);
    std::optional<IncrementalCorrector> kept;
    kept.emplace(CorrectFromStarts(std::move(initial), t_s, field, walk, result, progress));
    OneScaleStart d;
    d.nll_walk = Usable(result.status) ? result.nll : nan;
    d.nll_one_scale = d.nll_refined = nan;
    CorrectionResult from_one, refined;
    if (Usable(result.status) && kept->state().scales.size() > 1) {
        IncrementalCorrector one_inc(WithOneScale(kept->state()), field, one,
                                     IncrementalCorrector::Corrected{});
        from_one = one_inc.Finish(t_s);
        if (Usable(from_one.status)) d.nll_one_scale = from_one.nll;
        if (Usable(from_one.status) && from_one.nll < result.nll - kLowerNll) {
            IncrementalCorrector inc(WithWalkSegments(one_inc.state(), cfg.model), field, walk,
                                     IncrementalCorrector::Corrected{});
            refined = inc.Finish(t_s);
            if (Usable(refined.status)) d.nll_refined = refined.nll;
            if (Usable(refined.status) && refined.nll < result.nll - kLowerNll) {
                d.from_one_scale = true;
                kept.emplace(std::move(inc));
                TakeStartsOf(result, refined);
            }
        }
    }
    CorrectionResult work;  // every solve's counters
    AddWork(result, work), AddWork(from_one, work), AddWork(refined, work);
    if (d.from_one_scale) result = std::move(refined);
    SetWork(work, result);
    result.one_scale_start = d;
    if (Usable(result.status) && cfg.compute_covariance) kept->AddCovariance(result);
    return std::move(*kept);
}

// One correction of `initial` (CorrectFromStarts), from one scale too where
// CorrectorConfig::one_scale_start applies: a scale walk, one start scale, no floor hypotheses.
IncrementalCorrector CorrectOnce(TrajectoryState initial, const std::vector<double>& t_s,
                                 const TraversableField* field, const CorrectorConfig& cfg,
                                 CorrectionResult& result, const ProgressCallback& progress) {
    if (cfg.one_scale_start && cfg.start_scales.size() == 1 &&
        !FloorHypotheses(field, initial.fix_height, cfg) && t_s.size() >= 3) {
        return CorrectFromOneScaleToo(std::move(initial), t_s, field, cfg, result, progress);
    }
    return CorrectFromStarts(std::move(initial), t_s, field, cfg, result, progress);
}

// The normalisation of a state's step-length terms, sum of ln sigma over its steps: what the NLL
// leaves out as a constant of the model, which differs between readings of the step lengths.
double StepLengthNormalisation(const TrajectoryState& s, const ModelConfig& model) {
    double sum = 0.0;
    for (std::size_t i = 1; i < s.obs.size(); ++i) {
        const double sigma = StepNoiseOf(model, s.obs[i]).length_m;
        if (sigma > 0.0) sum += std::log(sigma);
    }
    return sum;
}

}  // namespace

IncrementalCorrector CorrectWithStepReading(
    const std::function<TrajectoryState(const CorrectorConfig&)>& initial,
    const std::vector<double>& t_s, const TraversableField* field, const CorrectorConfig& cfg,
    CorrectionResult& result, const ProgressCallback& progress) {
    if (!cfg.decide_step_reading || cfg.model.step_length_exponent == 1.0) {
        return CorrectOnce(initial(cfg), t_s, field, cfg, result, progress);
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CorrectorConfig read = cfg;
    read.model.step_length_exponent = 1.0;
    StepReadingDecision d;
    d.exponent = cfg.model.step_length_exponent;
    IncrementalCorrector about = CorrectOnce(initial(cfg), t_s, field, cfg, result, progress);
    if (Usable(result.status)) {
        d.nll_about_median = result.nll + StepLengthNormalisation(about.state(), cfg.model);
    } else {
        d.nll_about_median = nan;
    }
    CorrectionResult as_read;
    IncrementalCorrector inc = CorrectOnce(initial(read), t_s, field, read, as_read, progress);
    d.nll_as_read = Usable(as_read.status)
                        ? as_read.nll + StepLengthNormalisation(inc.state(), read.model)
                        : nan;
    d.price = 0.5 * std::log(double(t_s.size()));
    d.as_read = !std::isnan(d.nll_as_read) &&
                (std::isnan(d.nll_about_median) || d.nll_as_read + d.price < d.nll_about_median);
    CorrectionResult work;
    AddWork(result, work), AddWork(as_read, work);
    if (d.as_read) result = std::move(as_read);
    SetWork(work, result);
    result.step_reading = d;
    return d.as_read ? std::move(inc) : std::move(about);
}

// Do no harm: scores the input by the correction's objective and keeps it when it scores better;
// counts the poses whose input lies inside the correction's 95 % region and keeps the input
// unless they are significantly fewer than the region's own share. Pose 0 (the known start) and
// poses without a positive-definite covariance are not counted.
void KeepAgreeingInput(const PlanarTrajectory& estimate, const TraversableField* field,
                       const CorrectorConfig& cfg, CorrectionResult& result) {
    if (!Usable(result.status)) return;
    // The input scored as a correction would be: scale 1 and no heading-rate bias, so that its
    // scale walk, bias and scale prior terms cost nothing whichever segments the model has.
    TrajectoryState input = InitialState(estimate, cfg, !field || field->planar());
    result.input_nll = SoftNll(input, field, cfg.model, input.poses.size() - 1);
    result.input_nll_lower = result.input_nll < result.nll;
    if (result.covariance.status == CovarianceStatus::kOk) {
        const std::vector<PoseCovariance>& cov = result.covariance.poses;
        const PlanarTrajectory& c = result.corrected;
        for (std::size_t i = 1; i < cov.size() && i < estimate.size() && i < c.size(); ++i) {
            const Eigen::Matrix2d& s = cov[i].xy_m2;
            if (!(s(0, 0) > 0.0 && s.determinant() > 0.0)) continue;
            bool inside = InsideRegion95(estimate.p_en[i] - c.p_en[i], s);
            if (cov[i].z_m2 > 0.0 && i < estimate.up_m.size() && i < c.up_m.size()) {
                inside = inside && std::abs(estimate.up_m[i] - c.up_m[i]) <=
                                       kNormal95 * std::sqrt(cov[i].z_m2);
            }
            ++result.agreement_poses;
            result.agreement_inside += inside ? 1 : 0;
        }
        result.agreement_threshold = AgreementThreshold(estimate, cfg);
    }
    if (!cfg.keep_agreeing_input) return;
    const bool agrees = result.agreement_poses > 0 &&
                        double(result.agreement_inside) / double(result.agreement_poses) >=
                            result.agreement_threshold;
    if (!result.input_nll_lower && !agrees) return;
    const PlanarTrajectory correction = std::move(result.corrected);
    KeepInput(estimate, result);
    // An input kept for its lower NLL lies in another basin than the correction: its covariance
    // is the model's curvature at the input, not the correction's. An input kept for lying
    // inside the correction's 95 % region errs by its offset from the correction plus the
    // correction's own error: its covariance is that second moment.
    if (result.input_nll_lower && cfg.compute_covariance) {
        result.covariance = ComputeCovariance(input, field, cfg.model, cfg.covariance);
    } else if (result.covariance.status == CovarianceStatus::kOk) {
        AddOffsets(correction, estimate, result.covariance.poses);
    }
}

CorrectionResult CorrectTrajectory(const PlanarTrajectory& estimate, const TraversableField* field,
                                   const CorrectorConfig& cfg, const ProgressCallback& progress) {
    CorrectionResult result;
    const bool floor_hypotheses = FloorHypotheses(field, !field || field->planar(), cfg);
    if (cfg.decide_scale_walk && cfg.start_scales.size() == 1 && !floor_hypotheses &&
        estimate.size() >= 3) {
        CorrectWithDecidedScaleWalk(estimate, field, cfg, result, progress);
    } else if (estimate.size() >= 3) {  // (fewer: CorrectFromStarts's check names them)
        const bool planar = !field || field->planar();
        CorrectWithStepReading(
            [&](const CorrectorConfig& c) { return InitialState(estimate, c, planar); },
            estimate.t_s, field, cfg, result, progress);
    } else {
        CorrectFromStarts(estimate, field, cfg, result, progress);
    }
    KeepAgreeingInput(estimate, field, cfg, result);
    DiagnoseCorrection(estimate, field, cfg, result);
    return result;
}

}  // namespace driftcorr
