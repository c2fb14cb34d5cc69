// The definitions of what driftcorr/eval/evaluation.h declares.
#include "driftcorr/eval/evaluation.h"

#include <chrono>
#include <exception>
#include <filesystem>
#include <map>

#include "driftcorr/core/errors.h"
#include "driftcorr/optim/online_corrector.h"

namespace driftcorr::eval {
namespace {

double Since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The folder name of a scenario path ("a/b/kitti00/" -> "kitti00"; "x/scenario.yaml" -> "x").
std::string LabelOf(const std::string& path) {
    std::filesystem::path p(path);
    while (!p.empty() && p.filename().empty()) p = p.parent_path();
    if (p.extension() == ".yaml" || p.extension() == ".yml") {
        const std::string parent = p.parent_path().filename().string();
        return parent.empty() ? p.stem().string() : parent;
    }
    const std::string name = p.filename().string();
    return name.empty() || name == "." || name == ".." ? std::string("scenario") : name;
}

std::optional<double> MeanMapDistance(const PlanarTrajectory& t, const TraversableField& field) {
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        const auto s = field.QueryCentre(Eigen::Vector3d(t.p_en[i].x(), t.p_en[i].y(), t.up_m[i]));
        if (!s) continue;
        sum += std::max(0.0, s->value);
        ++count;
    }
    if (count == 0) return std::nullopt;
    return sum / static_cast<double>(count);
}

// The causal outputs of the online corrector, fed the estimate pose by pose.
MethodResult RunOnline(const pipeline::PreparedScenario& ps, const pipeline::PipelineConfig& base) {
    MethodResult r;
    r.method = Method::kOnline;
    OnlineConfig oc = base.online;
    oc.corrector = pipeline::CorrectorFor(ps.scenario, base);
    oc.synchronous = true;
    const auto t0 = std::chrono::steady_clock::now();
    OnlineCorrector online(&ps.field, oc);
    const PlanarTrajectory& est = ps.estimate;
    PlanarTrajectory causal;
    for (std::size_t i = 0; i < est.size(); ++i) {
        PlanarPose pose{est.t_s[i], est.p_en[i], est.up_m[i], std::nullopt};
        if (est.HasYaw()) pose.yaw_rad = est.yaw_rad[i];
        const PushResult pushed = online.Push(pose);
        if (pushed.status != PushStatus::kAccepted) {
            r.message = "pose " + std::to_string(i) + " rejected: " + pushed.message;
            return r;
        }
        causal.t_s.push_back(pushed.corrected.t_s);
        causal.p_en.push_back(pushed.corrected.p_en);
        causal.up_m.push_back(pushed.corrected.up_m);
        causal.yaw_rad.push_back(*pushed.corrected.yaw_rad);
    }
    const CorrectionResult smoothed = online.Finish();
    if (Usable(smoothed.status)) {
        r.verdict =
            JudgeOnline(est, causal, &ps.field, oc.corrector.model, smoothed, base.verdict).verdict;
    }
    r.wall_s = Since(t0);
    r.poses_per_s = est.size() / std::max(1e-9, r.wall_s);
    r.ok = true;
    r.message = "causal per-epoch output; Finish(): " + ToString(smoothed.status);
    r.trajectory = std::move(causal);
    return r;
}

// Runs one method on the prepared scenario and fills timing and the trajectory.
MethodResult RunMethod(Method method, const pipeline::PreparedScenario& ps,
                       const pipeline::PipelineConfig& base, const ProgressCallback& progress) {
    MethodResult r;
    r.method = method;
    if (method == Method::kEstimate) {
        r.ok = true;
        r.message = "uncorrected";
        r.trajectory = ps.estimate;
        return r;
    }
    if (method == Method::kOnline) return RunOnline(ps, base);
    pipeline::PipelineConfig cfg = base;
    cfg.solver = method == Method::kPaper ? pipeline::Solver::kPaper : pipeline::Solver::kDriftcorr;
    const auto t0 = std::chrono::steady_clock::now();
    CorrectionResult cr = pipeline::Correct(ps, cfg, progress);
    r.wall_s = Since(t0);
    r.poses_per_s = ps.estimate.size() / std::max(1e-9, r.wall_s);
    r.ok = Usable(cr.status);
    r.message = ToString(cr.status) + ": " + cr.message;
    for (const std::string& warning : cr.warnings) r.message += "; warning: " + warning;
    r.warnings = cr.warnings;
    r.verdict = pipeline::JudgeResult(ps, cfg, cr);
    if (cr.covariance.status == CovarianceStatus::kOk) r.covariance = cr.covariance.poses;
    if (r.ok) r.trajectory = std::move(cr.corrected);
    return r;
}

// Share of poses whose horizontal error e satisfies e^T Sigma^-1 e <= 5.991 (chi-square, 2 degrees
// of freedom, 95 %); pose 0, the known start, is left out.
double ShareInside95(const PlanarTrajectory& t, const PlanarTrajectory& gt,
                     const std::vector<PoseCovariance>& cov) {
    std::size_t inside = 0, n = 0;
    for (std::size_t i = 1; i < t.size(); ++i) {
        const Eigen::Vector2d e = t.p_en[i] - gt.p_en[i];
        const Eigen::Matrix2d& c = cov[i].xy_m2;
        if (!(c.determinant() > 0.0)) continue;
        ++n;
        if (e.dot(c.inverse() * e) <= 5.991) ++inside;
    }
    return n ? double(inside) / double(n) : 0.0;
}

void Measure(MethodResult& r, const pipeline::PreparedScenario& ps) {
    if (!r.ok) return;
    r.mean_map_distance_m = MeanMapDistance(r.trajectory, ps.field);
    if (ps.ground_truth) {
        r.metrics = ComputeMetrics(r.trajectory, *ps.ground_truth);
        r.errors_m = HorizontalErrors(r.trajectory, *ps.ground_truth);
        if (r.covariance.size() == r.trajectory.size()) {
            r.covariance_in_95 = ShareInside95(r.trajectory, *ps.ground_truth, r.covariance);
        }
    }
}

}  // namespace

std::string ToString(Method method) {
    switch (method) {
        case Method::kEstimate:
            return "estimate";
        case Method::kPaper:
            return "paper";
        case Method::kDriftcorr:
            return "driftcorr";
        case Method::kOnline:
            return "online";
    }
    return "unknown";
}

std::optional<Method> MethodFromString(const std::string& name) {
    for (const Method m : DefaultMethods()) {
        if (ToString(m) == name) return m;
    }
    return std::nullopt;
}

std::vector<Method> DefaultMethods() {
    return {Method::kEstimate, Method::kPaper, Method::kDriftcorr, Method::kOnline};
}

bool ScenarioEvaluation::AnyFailed() const {
    if (!ok()) return true;
    for (const MethodResult& m : methods) {
        if (!m.ok) return true;
    }
    return false;
}

const MethodResult* ScenarioEvaluation::Find(Method m) const {
    for (const MethodResult& r : methods) {
        if (r.method == m) return &r;
    }
    return nullptr;
}

ScenarioEvaluation EvaluateScenario(
    const std::string& path, const EvalConfig& config,
    const std::function<void(const std::string& stage, double fraction)>& progress) {
    ScenarioEvaluation ev;
    ev.path = path;
    ev.label = LabelOf(path);
    auto report = [&](const std::string& stage, double f) {
        if (progress) progress(stage, f);
    };
    try {
        report("load", 0.0);
        pipeline::PreparedScenario ps = pipeline::PrepareScenario(path, config.pipeline);
        ev.name = ps.scenario.name;
        ev.mode = io::ToString(ps.scenario.mode);
        ev.poses = ps.estimate.size();
        ev.has_ground_truth = ps.ground_truth.has_value();
        ev.load_s = ps.timings.load_s;
        ev.map_s = ps.timings.map_s;
        ev.ground_truth = ps.ground_truth;
        ev.distance_m = DistanceTravelled(ps.ground_truth ? *ps.ground_truth : ps.estimate);
        report("load", 1.0);
        for (Method m : config.methods) {
            const std::string stage = ToString(m);
            report(stage, 0.0);
            MethodResult r = RunMethod(m, ps, config.pipeline, [&](const CorrectionProgress& p) {
                if (p.stage == "refining") return;  // iterations of the final solve
                report(stage, p.poses_done / std::max(1.0, double(p.poses_total)));
            });
            Measure(r, ps);
            ev.methods.push_back(std::move(r));
            report(stage, 1.0);
        }
        ev.network = std::move(ps.network);
    } catch (const InputError& e) {
        ev.error = e.what();
        if (ev.mode.empty()) {
            // The scenario.yaml may still be readable (e.g. an unsupported mode): keep its name.
            try {
                const io::Scenario sc = io::LoadScenario(path);
                ev.name = sc.name;
                ev.mode = io::ToString(sc.mode);
            } catch (const std::exception&) {
            }
        }
    } catch (const std::exception& e) {
        ev.error = std::string("internal error: ") + e.what();
    }
    ev.methods.shrink_to_fit();
    return ev;
}

std::vector<ScenarioEvaluation> EvaluateScenarios(const std::vector<std::string>& paths,
                                                  const EvalConfig& config,
                                                  const EvalProgressCallback& progress) {
    std::vector<ScenarioEvaluation> out;
    std::map<std::string, int> seen;
    for (std::size_t k = 0; k < paths.size(); ++k) {
        std::string label = LabelOf(paths[k]);
        const int n = ++seen[label];
        if (n > 1) label += "_" + std::to_string(n);
        auto cb = [&](const std::string& stage, double f) {
            if (progress) progress({k, paths.size(), label, stage, f});
        };
        out.push_back(EvaluateScenario(paths[k], config, cb));
        out.back().label = label;
        if (progress) progress({k, paths.size(), label, "done", 1.0});
    }
    return out;
}

}  // namespace driftcorr::eval
