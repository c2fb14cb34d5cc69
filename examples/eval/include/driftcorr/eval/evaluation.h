#pragma once
// `driftcorr eval`: runs several correction methods on each scenario and measures them against
// the ground truth (docs/FORMAT.md "Judging": horizontal, no re-alignment). The methods share one
// loaded scenario and one map field per scenario. No printing: progress goes through a callback,
// every outcome (including a scenario that could not be loaded) into the result structs.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/metrics.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::eval {

/// The compared methods, in table column order. A new method is an enumerator here, its name in
/// ToString, a case in RunMethod (evaluation.cpp) and an entry in DefaultMethods(); the report
/// writer iterates over whatever methods a ScenarioEvaluation holds, so the table, JSON and plots
/// follow. kOnline is the causal (per-epoch) output of the online corrector
/// (optim/online_corrector.h), run synchronously: each pose's estimate is what Push returned for
/// it, every window solved before the next pose arrives (what the threaded mode gives when solves
/// keep up with the input).
enum class Method { kEstimate, kPaper, kDriftcorr, kOnline };
std::string ToString(Method method);
/// The method named `name` (ToString's names); nullopt for any other name.
std::optional<Method> MethodFromString(const std::string& name);
/// estimate, paper, driftcorr (batch), online.
std::vector<Method> DefaultMethods();

/// One method's outcome on one scenario.
struct MethodResult {
    Method method = Method::kEstimate;
    bool ok = false;                      ///< produced a usable trajectory
    std::string message;                  ///< solver outcome, or why it failed
    PlanarTrajectory trajectory;          ///< world plane; valid when ok
    std::optional<ErrorMetrics> metrics;  ///< when ok and the scenario has ground truth
    std::vector<double> errors_m;         ///< per-pose horizontal error [m] (with ground truth)
    /// Mean distance [m] of the poses to the nearest road centre line (from the map field,
    /// truncated at its truncation distance; poses outside the field are left out).
    std::optional<double> mean_map_distance_m;
    double wall_s = 0.0;       ///< solver wall time [s] (0 for the estimate)
    double poses_per_s = 0.0;  ///< poses / wall_s (0 for the estimate)
    /// Degenerate input or outcome reported by the corrector (CorrectionResult::warnings).
    std::vector<std::string> warnings;
    /// The verdict judged without ground truth (paper and driftcorr; optim/verdict.h).
    std::optional<Verdict> verdict;
    /// Per-pose covariance of the correction (driftcorr), and with ground truth the share of
    /// poses whose true horizontal error lies inside their 95 % region.
    std::vector<PoseCovariance> covariance;
    std::optional<double> covariance_in_95;
};

/// One scenario: either it failed as a whole (`error`, bad input), or it holds one MethodResult
/// per method.
struct ScenarioEvaluation {
    std::string path;   ///< as given on the command line
    std::string label;  ///< the folder name, used for file names and table rows
    std::string name;   ///< scenario.yaml `name` (empty if it could not be read)
    std::string mode;   ///< road2d | indoor3d (empty if unknown)
    std::string error;  ///< non-empty: the scenario could not be evaluated
    std::size_t poses = 0;
    bool has_ground_truth = false;
    double load_s = 0.0, map_s = 0.0;  ///< shared by all methods [s]
    std::optional<PlanarTrajectory> ground_truth;
    /// Horizontal distance travelled [m] per pose, along the ground truth (or along the estimate
    /// when there is none).
    std::vector<double> distance_m;
    RoadNetwork network;  ///< for the plots
    std::vector<MethodResult> methods;

    bool ok() const { return error.empty(); }
    /// The scenario failed or one of its methods did.
    bool AnyFailed() const;
    const MethodResult* Find(Method m) const;
};

struct EvalConfig {
    pipeline::PipelineConfig pipeline;  ///< `solver` is ignored: each method sets its own
    std::vector<Method> methods = DefaultMethods();
};

struct EvalProgress {
    std::size_t scenario_index = 0;  ///< 0-based
    std::size_t scenario_count = 0;
    std::string label;
    std::string stage;      ///< "load", a method name, or "done"
    double fraction = 0.0;  ///< of the current stage, [0, 1]
};
using EvalProgressCallback = std::function<void(const EvalProgress&)>;

/// Evaluates one scenario. Never throws for bad input or solver failures: a scenario that cannot
/// be loaded (or whose mode is not supported) comes back with `error` set (the InputError's
/// message, naming file and key), a failed method with ok = false and its message.
ScenarioEvaluation EvaluateScenario(
    const std::string& path, const EvalConfig& config,
    const std::function<void(const std::string& stage, double fraction)>& progress = {});

/// Evaluates every path in order; one failing scenario does not stop the others. Labels are made
/// unique (a suffix _2, _3, ... for repeated folder names).
std::vector<ScenarioEvaluation> EvaluateScenarios(const std::vector<std::string>& paths,
                                                  const EvalConfig& config,
                                                  const EvalProgressCallback& progress = {});

}  // namespace driftcorr::eval
