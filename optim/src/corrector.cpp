#include "driftcorr/optim/corrector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "driftcorr/core/check.h"
#include "driftcorr/core/format.h"
#include "driftcorr/optim/incremental_corrector.h"
#include "driftcorr/optim/window_problem.h"

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

IncrementalCorrector CorrectFromStarts(TrajectoryState initial, const std::vector<double>& t_s,
                                       const TraversableField* field, const CorrectorConfig& cfg,
                                       CorrectionResult& result, const ProgressCallback& progress) {
    DRIFTCORR_CHECK(initial.poses.size() >= 3 && t_s.size() == initial.poses.size(),
                    "CorrectFromStarts needs at least 3 poses and a time stamp for each");
    DRIFTCORR_CHECK(!cfg.start_scales.empty(), "CorrectFromStarts needs a start scale");
    CorrectorConfig each = cfg;
    each.compute_covariance = false;
    std::optional<IncrementalCorrector> best;
    std::vector<double> nll;
    std::vector<std::vector<Eigen::Vector2d>> paths;  // each start's corrected positions
    CorrectionResult work;  // the counters and times over every start
    for (std::size_t k = 0; k < cfg.start_scales.size(); ++k) {
        // The last start takes the initial state itself, not a copy.
        TrajectoryState state = k + 1 < cfg.start_scales.size() ? initial : std::move(initial);
        std::fill(state.scales.begin(), state.scales.end(), cfg.start_scales[k]);
        IncrementalCorrector inc(std::move(state), field, each);
        inc.SolveRemaining(progress);
        CorrectionResult r = inc.Finish(t_s, progress);
        work.windows += r.windows, work.window_retries += r.window_retries;
        work.window_restarts += r.window_restarts, work.iterations += r.iterations;
        work.incremental_s += r.incremental_s, work.refine_s += r.refine_s;
        nll.push_back(Usable(r.status) ? r.nll : std::numeric_limits<double>::quiet_NaN());
        paths.push_back(Usable(r.status) ? r.corrected.p_en : std::vector<Eigen::Vector2d>{});
        const bool better =
            !best || (Usable(r.status) && (!Usable(result.status) || r.nll < result.nll));
        if (!better) continue;
        best.emplace(std::move(inc));
        result = std::move(r);
        result.start_chosen = k;
    }
    result.start_scales = cfg.start_scales;
    result.start_nll = std::move(nll);
    const std::vector<Eigen::Vector2d>& kept = paths[result.start_chosen];
    for (const std::vector<Eigen::Vector2d>& path : paths) {
        result.start_rms_m.push_back(path.empty() || kept.empty()
                                         ? std::numeric_limits<double>::quiet_NaN()
                                         : RmsDistance(path, kept));
    }
    result.windows = work.windows, result.window_retries = work.window_retries;
    result.window_restarts = work.window_restarts, result.iterations = work.iterations;
    result.incremental_s = work.incremental_s, result.refine_s = work.refine_s;
    if (Usable(result.status) && cfg.compute_covariance) best->AddCovariance(result);
    return std::move(*best);
}

CorrectionResult CorrectTrajectory(const PlanarTrajectory& estimate, const TraversableField* field,
                                   const CorrectorConfig& cfg, const ProgressCallback& progress) {
    CorrectionResult result;
    CorrectFromStarts(estimate, field, cfg, result, progress);
    DiagnoseCorrection(estimate, field, cfg, result);
    return result;
}

}  // namespace driftcorr
