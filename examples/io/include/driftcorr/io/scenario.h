#pragma once
// The scenario format of docs/FORMAT.md (scenario.yaml and the files it names).
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/frames.h"
#include "driftcorr/core/types.h"
#include "driftcorr/mapping/walkable_surface.h"

namespace driftcorr::io {

enum class ScenarioMode { kRoad2d, kIndoor3d };
/// kTum: "t x y z qx qy qz qw" or positions only "t x y z"; kCsv: comma-separated with a header
/// naming the columns (trajectory_io.h), which also reads EuRoC / ASL files; kEuroc: the same
/// reader, requiring the EuRoC / ASL header.
enum class TrajectoryFormat { kKitti, kTum, kCsv, kEuroc };
enum class MapFormat { kOsm, kGeoJson, kPcd, kPly, kOctomap };
enum class LayerRole { kNone, kWalkways, kFloorplan };

/// Where a trajectory comes from (the `estimate:` / `ground_truth:` blocks).
struct TrajectorySource {
    std::string path;  ///< absolute or relative to the working dir (resolved)
    TrajectoryFormat format = TrajectoryFormat::kTum;
    std::optional<double> rate_hz;          ///< kitti only
    std::optional<std::string> times_path;  ///< kitti only, resolved
    /// `heading: motion`: the heading is taken from the direction of motion even when the file
    /// has orientations (e.g. a body frame whose forward axis is not the frame's, such as the
    /// EuRoC IMU frame with x up); `heading: orientation` (the default) uses them when present.
    /// A file without orientations always gives the heading from the motion.
    bool heading_from_motion = false;
};

/// `anchor:`. Exactly one of (lat_deg, lon_deg[, alt_m]) or (crs, easting_m, northing_m).
struct AnchorSpec {
    std::optional<double> lat_deg, lon_deg, alt_m;
    std::optional<std::string> crs;  ///< e.g. "EPSG:32632", as written
    std::optional<double> easting_m, northing_m;
    /// Heading of the trajectory frame in East-North (docs/FORMAT.md); std::nullopt when the file
    /// says `yaw_deg: auto`: the start is then estimated from the map (the key itself is required).
    std::optional<double> yaw_deg;
    /// `position_search_m` (optional): radius around the given position within which the start
    /// is estimated from the map together with the yaw [m]; 0: the position is taken as given.
    double position_search_m = 0.0;
    /// `scale` (optional): the estimate's positions times this are metres (1: a metric estimate,
    /// as when the key is absent). `scale: auto` sets scale_auto: the global scale of a
    /// monocular estimate is then found from the map.
    double scale = 1.0;
    bool scale_given = false;  ///< the key is present (a number or auto)
    bool scale_auto = false;
    /// Height of the frame's origin in the map's height datum; required in indoor3d, where it
    /// picks the floor (road2d ignores heights: 0 when absent).
    double z_m = 0.0;
    bool IsGeographic() const { return lat_deg.has_value(); }
};

/// Why `text` cannot be an anchor's `scale` (empty if it can): `auto` or a number in (0, 1e6).
/// Sets `anchor`'s scale fields when it can.
std::string ParseAnchorScale(const std::string& text, AnchorSpec& anchor);

/// An anchor value outside its range: its key (as in scenario.yaml) and the rule it breaks.
struct AnchorProblem {
    std::string key, rule;
};
/// The first of `anchor`'s values that is given and outside its range (lat_deg within [-90, 90],
/// lon_deg within [-180, 180], crs a known spelling, position_search_m within [0, 1000] m);
/// nothing when every one is within. The readers of scenario.yaml, the CLI's --anchor and the
/// Python anchor dict all check with it and name the key in their own terms.
std::optional<AnchorProblem> FindAnchorProblem(const AnchorSpec& anchor);

struct MapLayerSpec {
    std::string path;  ///< resolved
    MapFormat format = MapFormat::kOsm;
    LayerRole role = LayerRole::kNone;
    std::optional<double> floor_z_m;
    /// `lifts:` (point-cloud / OctoMap layers only): the footprints of the building's lift shafts
    /// in the layer's frame; a shaft joins every floor. A scan does not show where a lift is.
    std::vector<LiftShaft> lifts;
};

struct Scenario {
    std::string yaml_path;  ///< the scenario.yaml that was read
    std::string dir;        ///< its folder; relative paths are resolved against it
    std::string name;
    ScenarioMode mode = ScenarioMode::kRoad2d;
    TrajectorySource estimate;
    std::optional<TrajectorySource> ground_truth;
    FrameAxes frame = FrameAxes::kEnu;
    AnchorSpec anchor;
    std::vector<MapLayerSpec> map;
    /// Non-fatal findings, one line each ("file:line: key: unknown key, ignored").
    std::vector<std::string> warnings;
};

/// Loads `path` (a scenario folder containing scenario.yaml, or a .yaml file). Throws
/// InputError naming the yaml file, the line and the key for: unreadable file, YAML syntax error,
/// missing required key, unknown mode/format/frame/role, anchor without coordinates (or with both
/// kinds), kitti estimate without rate_hz and times, non-finite numbers, an empty map list, and
/// `lifts` that CheckLayerLifts refuses. Does not open the files named inside (LoadTrajectory and
/// the map readers do).
Scenario LoadScenario(const std::string& path);

/// A file a run reads, with what it is for messages ("the estimate", "map layer 2").
struct InputFile {
    std::string what;
    std::string path;
};

/// Every file a correction of `scenario` reads: scenario.yaml (unless built in memory), the
/// estimate and the ground truth with their times files, and each map layer.
std::vector<InputFile> InputFiles(const Scenario& scenario);

std::string ToString(ScenarioMode mode);
std::string ToString(MapFormat format);
std::string ToString(TrajectoryFormat format);
/// "kitti", "tum", "csv", "euroc"; std::nullopt for anything else.
std::optional<TrajectoryFormat> ParseTrajectoryFormat(const std::string& name);

/// Empty when `lifts` may sit on a layer of `format` (point clouds and OctoMaps: a floor plan marks
/// its lifts itself) and every footprint is finite with x1 > x0 and y1 > y0; else what is wrong.
std::string CheckLayerLifts(MapFormat format, const std::vector<LiftShaft>& lifts);

/// The names scenario.yaml accepts, for scenarios built in memory (the Python bindings):
/// "road2d" | "indoor3d"; "osm" | "geojson" | "pcd" | "ply" | "bt" | "ot" | "octomap";
/// "walkways" | "floorplan". std::nullopt for anything else (the caller names its argument).
std::optional<ScenarioMode> ParseScenarioMode(const std::string& name);
std::optional<MapFormat> ParseMapFormat(const std::string& name);
std::optional<LayerRole> ParseLayerRole(const std::string& name);
/// The map format a layer file's extension names (.json counts as GeoJSON), as scenario.yaml
/// does when a layer has no `format:`; std::nullopt when it names none.
std::optional<MapFormat> MapFormatFromExtension(const std::string& path);

}  // namespace driftcorr::io
