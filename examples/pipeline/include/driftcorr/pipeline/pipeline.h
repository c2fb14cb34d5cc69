#pragma once
// The example pipeline behind `driftcorr correct`: scenario -> world plane -> map field ->
// correction -> corrected trajectory in the trajectory's own frame, with metrics when the
// scenario has ground truth. It wires the library together; the CLI only parses and prints.
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "driftcorr/core/metrics.h"
#include "driftcorr/io/scenario.h"
#include "driftcorr/mapping/indoor_field.h"
#include "driftcorr/mapping/road_network.h"
#include "driftcorr/mapping/surface_field.h"
#include "driftcorr/optim/anchor_fit.h"
#include "driftcorr/optim/corrector.h"
#include "driftcorr/optim/online_corrector.h"
#include "driftcorr/optim/paper_solver.h"
#include "driftcorr/optim/verdict.h"

namespace driftcorr::pipeline {

/// Which solver corrects the estimate: driftcorr's batch corrector (optim/corrector.h) or the
/// paper's epoch-wise gradient descent, kept as a reference (optim/paper_solver.h).
enum class Solver { kDriftcorr, kPaper };
std::string ToString(Solver solver);

/// Every parameter of a run; defaults written once, in the member structs.
struct PipelineConfig {
    Solver solver = Solver::kDriftcorr;
    CorrectorConfig corrector;  ///< road2d, Solver::kDriftcorr (sections `model`, `corrector`)
    /// indoor3d, Solver::kDriftcorr (sections `indoor_model`, `indoor_corrector`)
    CorrectorConfig indoor_corrector = CorrectorConfig::Pedestrian();
    IndoorFieldConfig indoor_field;  ///< indoor3d GeoJSON map field (section `indoor_field`)
    /// indoor3d point-cloud / OctoMap map field (section `surface_field`)
    SurfaceFieldConfig surface_field;
    PaperSolverConfig paper;  ///< used by Solver::kPaper (params.yaml section `paper`)
    RoadClassConfig roads;
    RoadFieldConfig field;
    /// driftcorr stream and the online method of eval (section `online`); its `corrector` is
    /// not read from the file: the mode's corrector above is used.
    OnlineConfig online;
    /// The anchor check and `yaw_deg: auto` (not read from the file; reach_m is the mode's
    /// map_giveup_m).
    AnchorFitConfig anchor_fit;
    /// The verdict's thresholds (optim/verdict.h; params.yaml section `verdict`).
    VerdictConfig verdict;

    /// Empty if valid, else "<section>.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// Calls f(section, table, part, about) for every params.yaml section, in the order
/// ParameterReference lists them: `table` is the ParamTable of the section's keys, `part` the
/// member of `config` (a PipelineConfig, const or not) the section sets, `about` one line on it.
template <class Pipeline, class F>
void ForEachParamSection(Pipeline&& config, F&& f) {
    f("model", kModelParams, config.corrector.model,
      "road2d: sigmas and weights of the NLL (optim/include/driftcorr/optim/model_config.h)");
    f("corrector", kCorrectorParams, config.corrector,
      "road2d: chunks, windows, restarts (optim/include/driftcorr/optim/corrector_config.h)");
    f("paper", kPaperSolverParams, config.paper,
      "--solver paper: the published method (optim/include/driftcorr/optim/paper_solver.h)");
    f("roads", kRoadClassParams, config.roads,
      "road2d: traversable OSM classes (mapping/include/driftcorr/mapping/road_network.h)");
    f("field", kRoadFieldParams, config.field,
      "road2d: the road distance field (mapping/include/driftcorr/mapping/road_network.h)");
    f("indoor_model", kModelParams, config.indoor_corrector.model,
      "indoor3d: the keys of model at ModelConfig::Pedestrian() (model_config.h)");
    f("indoor_corrector", kCorrectorParams, config.indoor_corrector,
      "indoor3d: the keys of corrector at CorrectorConfig::Pedestrian() (corrector_config.h)");
    f("indoor_field", kIndoorFieldParams, config.indoor_field,
      "indoor3d GeoJSON floor plans (mapping/include/driftcorr/mapping/indoor_field.h)");
    f("surface_field", kSurfaceFieldParams, config.surface_field,
      "indoor3d point-cloud / OctoMap maps (mapping/include/driftcorr/mapping/surface_field.h)");
    f("online", kOnlineParams, config.online,
      "driftcorr stream, eval's online method (optim/include/driftcorr/optim/online_corrector.h)");
    f("verdict", kVerdictParams, config.verdict,
      "the verdict's thresholds, every mode (optim/include/driftcorr/optim/verdict.h)");
}

/// Reads a params.yaml (sections `model`, `corrector`, `paper`, `roads`, `field`, `indoor_model`,
/// `indoor_corrector`, `indoor_field`, `surface_field`, `online`, `verdict`; their keys are the
/// rows of the parameter tables, e.g. kModelParams). Unknown keys are errors (a misspelt parameter
/// must not be ignored). Throws InputError naming the file, the line and the key as written
/// ("params.yaml:3: indoor_field.resolution_m: must be > 0 (got -1)"), one bad key at a time.
PipelineConfig LoadPipelineConfig(const std::string& path);

/// Every section and key of params.yaml with its value in `config`, and a comment with what it
/// may be and what it does: a complete params.yaml (LoadPipelineConfig reads it back to `config`).
/// `driftcorr params` prints it for the defaults; it is the parameter list of docs/parameters.md.
std::string ParameterReference(const PipelineConfig& config = PipelineConfig{});

/// The sections `model` and `corrector` of ParameterReference (road2d's) with the values of
/// `corrector`, e.g. CorrectorConfig::Pedestrian(): a preset as params.yaml writes it. Members
/// that are no params.yaml key (start_scales, restart_*_factors/gains, covariance) are not listed.
std::string CorrectorReference(const CorrectorConfig& corrector);

/// Converts between the world plane (ENU at the anchor) and WGS84, for maps and GeoJSON output.
class WorldFrame {
public:
    explicit WorldFrame(const io::AnchorSpec& anchor);  ///< throws InputError for a bad CRS
    ~WorldFrame();
    Eigen::Vector2d ToEn(const GeoPoint& geo) const;
    GeoPoint ToGeo(const Eigen::Vector2d& en) const;
    PlanarAnchor planar_anchor() const { return anchor_; }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    PlanarAnchor anchor_;
};

struct Timings {
    double load_s = 0.0;   ///< scenario and trajectories
    double map_s = 0.0;    ///< map parsing and field
    double solve_s = 0.0;  ///< correction
};

struct CorrectionRun {
    io::Scenario scenario;
    Trajectory estimate_frame;  ///< as read
    PlanarTrajectory estimate;  ///< in the world plane
    std::optional<PlanarTrajectory> ground_truth;
    RoadNetwork network;
    PlanarAnchor anchor;                        ///< as given, or as estimated from the map
    std::optional<AnchorFitResult> anchor_fit;  ///< see PreparedScenario
    std::size_t map_grid_cells = 0;
    /// See PreparedScenario.
    double global_scale = 1.0;
    std::optional<ScaleFitResult> scale_fit;
    CorrectionResult result;
    /// Can the result be vouched for (no ground truth used): ok, degraded or failed, reasons and
    /// per-pose flags.
    Verdict verdict;
    Trajectory corrected_frame;  ///< valid only when Usable(result.status)
    std::optional<ErrorMetrics> before, after;
    Timings timings;
    /// The heading came from the direction of motion: the estimate has no orientation, or the
    /// scenario asked for it (`heading: motion`).
    bool heading_from_motion = false;
};

/// A scenario read and placed in the world, with its map field: everything a solver needs.
/// Lets several solvers run on one loaded scenario (driftcorr eval).
struct PreparedScenario {
    io::Scenario scenario;
    Trajectory estimate_frame;  ///< as read
    PlanarTrajectory estimate;  ///< in the world plane
    std::optional<PlanarTrajectory> ground_truth;
    PlanarAnchor anchor;  ///< as given, or as estimated from the map
    /// How the start fits the map: the estimated start (`yaw_deg: auto`, `position_search_m`), or
    /// the given anchor scored against every other heading (the anchor check).
    std::optional<AnchorFitResult> anchor_fit;
    /// The estimate's global scale: the anchor's `scale`, or with `scale: auto` the one found
    /// from the map; `estimate` is scaled by it (1: a metric estimate).
    double global_scale = 1.0;
    /// `scale: auto`: how the leading path fits the map at each scale (FitScale).
    std::optional<ScaleFitResult> scale_fit;
    RoadNetwork network;
    TraversableField field;
    Timings timings;                   ///< load_s and map_s
    bool heading_from_motion = false;  ///< see CorrectionRun
};

/// Loads the scenario, its trajectories and its map field. Throws InputError for bad input
/// (files, anchor, an unsupported mode, map with no usable roads, field too large).
PreparedScenario PrepareScenario(const std::string& scenario_path, const PipelineConfig& config);
/// The same for a scenario built in memory (e.g. from command-line options); its paths are used
/// as they are (absolute, or relative to the working directory).
PreparedScenario PrepareScenario(io::Scenario scenario, const PipelineConfig& config);

/// The same from a scenario whose trajectories are already in memory (the Python bindings):
/// `scenario` supplies mode, frame, anchor and map layers (its `estimate` and `ground_truth`
/// sources are not read), `estimate_frame` and `ground_truth_frame` the poses in the
/// trajectory's own frame (ground truth: same size as the estimate). Throws InputError as above.
/// timings.load_s is left 0 (nothing is loaded).
PreparedScenario PrepareScenario(io::Scenario scenario, Trajectory estimate_frame,
                                 std::optional<Trajectory> ground_truth_frame,
                                 const PipelineConfig& config);

/// The scenario's map as a field: OSM roads rasterised over `region_en` (road2d; with a
/// `corridor` and field.tile_m > 0, only the tiles within its discs, see RasteriseRoadCorridor),
/// or the indoor GeoJSON / point-cloud / OctoMap layers (indoor3d; `up_m` picks the floor whose
/// walkways go into `network` for pictures; with `heights`, GeoJSON floors only at the layers
/// that serve them, see BuildIndoorField; the field holds the scenario's FloorHeights). Throws
/// InputError naming the file or setting.
TraversableField LoadMapField(const io::Scenario& sc, const WorldFrame& world,
                              const PipelineConfig& config, const Eigen::AlignedBox2d& region_en,
                              double up_m, RoadNetwork& network,
                              const std::vector<FieldDisc>* corridor = nullptr,
                              const std::optional<HeightRange>& heights = std::nullopt);

/// The floors' pose heights of an indoor3d scenario whose map is GeoJSON floors: each layer's
/// floor_z_m + indoor_field.device_height_m, once each; empty otherwise.
std::vector<double> FloorHeights(const io::Scenario& sc, const PipelineConfig& config);
/// The corrector settings for the scenario's mode (config.corrector or config.indoor_corrector).
CorrectorConfig CorrectorFor(const io::Scenario& sc, const PipelineConfig& config);

/// Runs config.solver on a prepared scenario. Solver outcomes are in the result, never thrown.
CorrectionResult Correct(const PreparedScenario& prepared, const PipelineConfig& config,
                         const ProgressCallback& progress = {});

/// The verdict on `result`, a correction of `prepared` by config.solver (optim/verdict.h).
Verdict JudgeResult(const PreparedScenario& prepared, const PipelineConfig& config,
                    const CorrectionResult& result);

/// `scale: auto`: the field a trial correction of a candidate scale runs on, for `trial` (its
/// estimate at that scale, placed): a reference to a field that outlives the call, or one made
/// into `storage`.
using TrialField = std::function<const TraversableField&(const PlanarTrajectory& trial,
                                                         std::optional<TraversableField>& storage)>;
/// The global scale of an estimate whose size is unknown, found from the map.
struct GlobalScale {
    double scale = 1.0;  ///< the estimate's positions times it are metres
    ScaleFitResult fit;  ///< the search and its candidates (fit.kept: the one kept)
};
/// The search of FindGlobalScale without its trial corrections: the scales that fit the leading
/// path of `estimate` best (fit.candidates, best first). Throws as FindGlobalScale.
ScaleFitResult FitGlobalScale(const io::Scenario& sc, const PipelineConfig& config,
                              const PlanarTrajectory& estimate, const PlanarAnchor& anchor,
                              const TraversableField& lead_field);
/// `scale: auto` on `estimate` (world plane, at scale 1, placed by `anchor`): the scales that give
/// it a plausible median speed for the mode (a vehicle 2-40 m/s, a walker 0.3-2.5 m/s) are searched
/// on a log grid (2 % apart) by how the first ScaleLeadPathM() of the scaled path fit `lead_field`
/// (every heading too when the anchor's yaw is auto); the best six minima are each corrected
/// whole on field_for(trial) (no window restarts, final solve or covariance) and the one of lowest
/// NLL is kept, its scale times the ratio of its correction's path to the scaled estimate's.
/// Throws InputError naming anchor.scale when the estimate never moves or no scale fits.
GlobalScale FindGlobalScale(const io::Scenario& sc, const PipelineConfig& config,
                            const PlanarTrajectory& estimate, const PlanarAnchor& anchor,
                            const TraversableField& lead_field, const TrialField& field_for);
/// The second half of FindGlobalScale, on a search already made (FitGlobalScale's `fit`, at least
/// one candidate): each candidate corrected whole, the one of lowest NLL kept.
GlobalScale ChooseGlobalScale(const io::Scenario& sc, const PipelineConfig& config,
                              const PlanarTrajectory& estimate, const PlanarAnchor& anchor,
                              ScaleFitResult fit, const TrialField& field_for);
/// The leading path FindGlobalScale matches against the map [m].
double ScaleLeadPathM();

/// The drive's scale as corrected: the global scale times the corrected path over the scaled
/// estimate's, and its standard deviation (the correction's covariance of its mean step-length
/// scale, CovarianceResult::mean_scale_sd, times the global scale). Both NaN when the run wrote
/// no correction of its own (unusable, or the input kept); the deviation alone when the
/// covariance was not computed whole.
struct DriveScale {
    double value = std::numeric_limits<double>::quiet_NaN();
    double sd = std::numeric_limits<double>::quiet_NaN();
};
DriveScale DriveScaleOf(const CorrectionRun& run);

/// Runs the whole correction (PrepareScenario, then Correct, then metrics). Throws InputError for
/// bad input. Solver outcomes are reported in run.result, never thrown.
CorrectionRun RunCorrection(const std::string& scenario_path, const PipelineConfig& config,
                            const ProgressCallback& progress = {});
CorrectionRun RunCorrection(io::Scenario scenario, const PipelineConfig& config,
                            const ProgressCallback& progress = {});
/// Correct, verdict and metrics on a prepared scenario (RunCorrection(path) is PrepareScenario,
/// then this).
///
/// Thread safety: independent runs may go on concurrently in several threads (one config each or
/// a shared const one, no shared progress callback state); the solver serialises its calls into
/// Ipopt's linear solver MUMPS, which is not thread-safe (optim/ipopt_solver.h).
CorrectionRun RunCorrection(PreparedScenario prepared, const PipelineConfig& config,
                            const ProgressCallback& progress = {});

}  // namespace driftcorr::pipeline
