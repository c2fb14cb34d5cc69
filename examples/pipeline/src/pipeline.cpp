// The definitions of what driftcorr/pipeline/pipeline.h declares.
#include "driftcorr/pipeline/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>
#include <stdexcept>
#include <utility>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/core/format.h"
#include "driftcorr/core/metrics.h"
#include "driftcorr/core/observables.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/mapping/floor_plan.h"
#include "driftcorr/mapping/geodesy.h"
#include "driftcorr/mapping/grid.h"
#include "driftcorr/mapping/osm_reader.h"
#include "driftcorr/optim/anchor_fit.h"
#include "driftcorr/pipeline/surface_io_loader.h"

namespace driftcorr::pipeline {
namespace {

double Since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Eigen::AlignedBox2d BoundsOf(const PlanarTrajectory& t) {
    Eigen::AlignedBox2d box;
    for (const auto& p : t.p_en) box.extend(p);
    return box;
}

// Road map of all osm layers. Throws InputError when no layer yields a usable road.
RoadNetwork LoadRoads(const io::Scenario& sc, const WorldFrame& world,
                      const RoadClassConfig& roads) {
    RoadNetwork net;
    std::string last_layer;
    for (const io::MapLayerSpec& layer : sc.map) {
        if (layer.format != io::MapFormat::kOsm) {
            throw InputError(sc.yaml_path, 0, "map",
                             "road2d mode reads OpenStreetMap layers only; '" + layer.path +
                                 "' is " + io::ToString(layer.format));
        }
        const OsmRoads osm = ReadOsmRoads(layer.path);
        RoadNetwork part = BuildRoadNetwork(
            osm, [&](const GeoPoint& g) { return world.ToEn(g); }, roads);
        if (part.roads.empty()) {
            throw InputError(layer.path, 0, "",
                             "no usable roads: " + std::to_string(osm.ways.size()) +
                                 " highway way(s), none of a class in the '" + roads.profile +
                                 "' profile");
        }
        net.ways_excluded_by_class += part.ways_excluded_by_class;
        net.ways_area += part.ways_area;
        net.missing_node_refs += part.missing_node_refs;
        net.lon_lat_deg.extend(part.lon_lat_deg);
        for (auto& r : part.roads) net.roads.push_back(std::move(r));
    }
    return net;
}

// The walkways of the floor nearest to `up_m`, as a network for pictures and summaries.
RoadNetwork WalkwaysNear(const IndoorMap& map, double up_m, double half_width_m) {
    RoadNetwork net;
    const IndoorFloor* best = nullptr;
    for (const IndoorFloor& f : map.floors) {
        if (!best || std::abs(f.floor_z_m - up_m) < std::abs(best->floor_z_m - up_m)) best = &f;
    }
    if (!best) return net;
    for (const auto& line : best->walkways_en)
        net.roads.push_back({0, "walkway", half_width_m, line});
    return net;
}

bool IsSurfaceLayer(const io::MapLayerSpec& layer) {
    return layer.format == io::MapFormat::kPcd || layer.format == io::MapFormat::kPly ||
           layer.format == io::MapFormat::kOctomap;
}

// The walkable surfaces of the scenario's point-cloud / OctoMap layers as a 3D field, with the
// lift shafts the layers declare. The files hold points in the anchor's local East-North frame
// (metres from the anchor origin) and heights in the map's datum (the one z_m refers to).
TraversableField LoadSurfaceField(const io::Scenario& sc, const SurfaceFieldConfig& config) {
    std::vector<Eigen::Vector3d> points;
    std::vector<ShaftOutline> shafts;
    for (std::size_t i = 0; i < sc.map.size(); ++i) {
        if (!IsSurfaceLayer(sc.map[i])) {
            throw InputError(sc.yaml_path, 0, "map[" + std::to_string(i) + "].format",
                             "indoor3d maps are either point-cloud/OctoMap layers or GeoJSON "
                             "layers, not both");
        }
        const std::vector<Eigen::Vector3d> layer = SurfaceIo().read_surface_points(sc.map[i].path);
        points.insert(points.end(), layer.begin(), layer.end());
        for (const LiftShaft& l : sc.map[i].lifts) {
            shafts.push_back({{l.x0, l.y0}, {l.x1, l.y0}, {l.x1, l.y1}, {l.x0, l.y1}});
        }
    }
    try {
        TraversableField field = BuildSurfaceField(points, config);
        field.set_lift_shafts(std::move(shafts));
        return field;
    } catch (const std::invalid_argument& e) {
        throw InputError(sc.yaml_path, 0, "map",
                         std::string(e.what()) + " (surface_field settings)");
    }
}

// The indoor map of the scenario's GeoJSON layers as a 3D field (and, in `walkways`, the walkway
// lines of the floor nearest to `up_m`). Layer files are named in the loader's errors; a field
// too large for the memory cap names the scenario and the setting.
TraversableField LoadIndoorField(const io::Scenario& sc, const IndoorFieldConfig& config,
                                 double up_m, RoadNetwork& walkways,
                                 const std::optional<HeightRange>& heights) {
    std::vector<IndoorLayerSpec> specs;
    for (std::size_t i = 0; i < sc.map.size(); ++i) {
        const io::MapLayerSpec& layer = sc.map[i];
        const std::string key = "map[" + std::to_string(i) + "]";
        if (layer.format != io::MapFormat::kGeoJson) {
            throw InputError(sc.yaml_path, 0, key + ".format",
                             io::ToString(layer.format) +
                                 " layers are not supported in indoor3d "
                                 "mode yet (GeoJSON walkways and floor plans are)");
        }
        if (layer.role == io::LayerRole::kNone || !layer.floor_z_m) {
            throw InputError(
                sc.yaml_path, 0, key,
                "an indoor GeoJSON layer needs role (walkways | floorplan) and floor_z_m");
        }
        specs.push_back({layer.path,
                         layer.role == io::LayerRole::kWalkways ? IndoorLayerRole::kWalkways
                                                                : IndoorLayerRole::kFloorplan,
                         *layer.floor_z_m});
    }
    IndoorFrame frame;
    if (sc.anchor.IsGeographic()) {
        auto world = std::make_shared<WorldFrame>(sc.anchor);
        frame.geo_to_en = [world](const GeoPoint& g) { return world->ToEn(g); };
    } else {
        frame.anchor_crs = NormaliseCrsName(*sc.anchor.crs);
        const Eigen::Vector2d origin(*sc.anchor.easting_m, *sc.anchor.northing_m);
        frame.anchor_crs_to_en = [origin](const Eigen::Vector2d& en) {
            return Eigen::Vector2d(en - origin);
        };
    }
    const IndoorMap map = LoadIndoorMap(specs, frame);
    walkways = WalkwaysNear(map, up_m, config.walkway_half_width_m);
    try {
        return BuildIndoorField(map.floors, config, nullptr, heights);
    } catch (const std::invalid_argument& e) {
        throw InputError(sc.yaml_path, 0, "map",
                         std::string(e.what()) + " (indoor_field settings)");
    }
}

// The anchor check matches the leading path against the map with the mode's reach of the map
// term (a pose farther than that from every traversable place is off the map).
AnchorFitConfig AnchorFitFor(const io::Scenario& sc, const PipelineConfig& config) {
    AnchorFitConfig c = config.anchor_fit;
    c.reach_m = CorrectorFor(sc, config).model.map_giveup_m;
    return c;
}

// Where the corrected track can be: within field.margin_m (the drift the field allows for) of
// every pose of the anchored estimate, and within reach of every start the anchor check scores
// (the leading path turned about the start over the whole circle, moved by up to the check's
// radius).
std::vector<FieldDisc> FieldCorridor(const PlanarTrajectory& estimate,
                                     const Eigen::Vector2d& origin_en, const AnchorFitConfig& fit,
                                     const RoadFieldConfig& field) {
    std::vector<FieldDisc> discs;
    discs.reserve(estimate.size() + 1);
    double lead_reach_m = 0.0, path_m = 0.0;
    for (std::size_t i = 0; i < estimate.size(); ++i) {
        discs.push_back({estimate.p_en[i], field.margin_m});
        if (i > 0) path_m += (estimate.p_en[i] - estimate.p_en[i - 1]).norm();
        if (path_m <= fit.lead_path_m) {
            lead_reach_m = std::max(lead_reach_m, (estimate.p_en[i] - origin_en).norm());
        }
    }
    discs.push_back({origin_en, lead_reach_m + fit.check_position_radius_m + fit.reach_m});
    return discs;
}

// The heights where the corrected walk can be: the estimate's, grown by half their range (a
// height change read up to 1.4x) and by indoor_field.height_margin_m.
std::optional<HeightRange> WalkHeights(const PlanarTrajectory& estimate,
                                       const IndoorFieldConfig& config) {
    if (estimate.up_m.empty()) return std::nullopt;
    const auto [lo, hi] = std::minmax_element(estimate.up_m.begin(), estimate.up_m.end());
    const double grow = 0.5 * (*hi - *lo) + config.height_margin_m;
    return HeightRange{*lo - grow, *hi + grow};
}

// `scale: auto`: the leading path whose fit to the map picks the global scale [m], and the
// ratio between neighbouring scales of the search.
constexpr double kScaleLeadPathM = 1000.0;
constexpr double kScaleStepRatio = 1.02;
// The leading path's best fits that are corrected whole: on a regular grid of streets several
// wrong scales fit the leading path better than the right one.
constexpr std::size_t kScaleCandidates = 6;

// The road field of `network` over `region_en`: along `corridor` when given and tiled, else the
// whole region. A field the settings cannot make is bad input naming the map.
TraversableField RoadField(const io::Scenario& sc, const RoadNetwork& network,
                           const PipelineConfig& config, const Eigen::AlignedBox2d& region_en,
                           const std::vector<FieldDisc>* corridor) {
    try {
        if (corridor != nullptr && config.field.tile_m > 0.0) {
            return RasteriseRoadCorridor(network, region_en, *corridor, config.field);
        }
        return RasteriseRoads(network, region_en, config.field);
    } catch (const std::invalid_argument& e) {
        throw InputError(sc.yaml_path, 0, "map", e.what());
    }
}

// The map field over the square of half-width `half_m` about the anchor, for matching the
// estimate's leading path.
TraversableField LeadField(const WorldFrame& world, const PipelineConfig& config,
                           const PreparedScenario& ps, double half_m) {
    const Eigen::Vector2d c = ps.anchor.origin_en, h(half_m, half_m);
    RoadNetwork unused;
    return LoadMapField(ps.scenario, world, config, Eigen::AlignedBox2d(c - h, c + h),
                        ps.anchor.origin_up_m, unused, nullptr,
                        WalkHeights(ps.estimate, config.indoor_field));
}

// `yaw_deg: auto` / `position_search_m`: the leading path is matched against a field that covers
// every heading and position searched, then the estimate is placed where it fits best and the
// anchor takes that heading and position.
void PlaceStart(const WorldFrame& world, const PipelineConfig& config, PreparedScenario& ps) {
    const io::Scenario& sc = ps.scenario;
    const AnchorFitConfig fit_cfg = AnchorFitFor(sc, config);
    double reach_m = 0.0, path_m = 0.0;
    for (std::size_t i = 0; i < ps.estimate.size() && path_m <= fit_cfg.lead_path_m; ++i) {
        if (i > 0) path_m += (ps.estimate.p_en[i] - ps.estimate.p_en[i - 1]).norm();
        reach_m = std::max(reach_m, (ps.estimate.p_en[i] - ps.anchor.origin_en).norm());
    }
    const TraversableField lead_field =
        LeadField(world, config, ps, reach_m + sc.anchor.position_search_m + fit_cfg.reach_m);
    ps.anchor_fit = FitAnchor(ps.estimate, ps.anchor.origin_en, lead_field, !sc.anchor.yaw_deg,
                              sc.anchor.position_search_m, fit_cfg);
    const AnchorPlacement& best = ps.anchor_fit->best;
    ps.estimate = ApplyPlacement(ps.estimate, ps.anchor.origin_en, best);
    ps.anchor.yaw_rad += best.dyaw_rad;
    ps.anchor.origin_en += best.offset_en;
}

// The poses of `traj` at the times `t_s` (both increasing), each within 1 ms of its time;
// nullopt if one has none.
std::optional<Trajectory> PosesAtTimes(const Trajectory& traj, const std::vector<double>& t_s) {
    Trajectory out;
    std::size_t j = 0;
    for (double t : t_s) {
        while (j < traj.size() && traj.t_s[j] < t - 1e-3) ++j;
        if (j == traj.size() || std::abs(traj.t_s[j] - t) > 1e-3) return std::nullopt;
        out.t_s.push_back(traj.t_s[j]);
        out.p_frame.push_back(traj.p_frame[j]);
        if (traj.HasOrientation()) out.q_frame_body.push_back(traj.q_frame_body[j]);
    }
    return out;
}

// The plausible median speed of a drive or a walk while it moves [m/s]: a vehicle's median
// below walking pace or above 40 m/s (144 km/h), a walker's outside 0.3-2.5 m/s, is not
// plausible. Outside a band twice as wide, an estimate with no `scale` is not taken as metric.
struct SpeedBand {
    double lo_mps, hi_mps;
};
SpeedBand PlausibleSpeeds(const io::Scenario& sc) {
    return sc.mode == io::ScenarioMode::kIndoor3d ? SpeedBand{0.3, 2.5} : SpeedBand{2.0, 40.0};
}

// The median speed of the steps that move (longer than stationary_m, dt > 0) [m/s]; 0 if none.
double MedianMovingSpeed(const PlanarTrajectory& t, double stationary_m) {
    std::vector<double> v;
    for (std::size_t i = 1; i < t.size(); ++i) {
        const double d = (t.p_en[i] - t.p_en[i - 1]).norm(), dt = t.t_s[i] - t.t_s[i - 1];
        if (d > stationary_m && dt > 0.0) v.push_back(d / dt);
    }
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
}

// An estimate without `scale` is taken as metric: one whose median speed is far outside the
// mode's plausible band (a monocular tracker's, whose size is arbitrary) is bad input.
void CheckMetricSpeeds(const PreparedScenario& ps, const PipelineConfig& config) {
    const io::Scenario& sc = ps.scenario;
    const double v = MedianMovingSpeed(ps.estimate, CorrectorFor(sc, config).stationary_m);
    const SpeedBand band = PlausibleSpeeds(sc);
    if (v <= 0.0 || (v >= 0.5 * band.lo_mps && v <= 2.0 * band.hi_mps)) return;
    const bool walk = sc.mode == io::ScenarioMode::kIndoor3d;
    throw InputError(
        sc.yaml_path, 0, "anchor.scale",
        "the estimate's median speed is " + FormatFixed(v, v < 1.0 ? 2 : 1) + " m/s, where " +
            (walk ? "a walker's" : "a vehicle's") + " is " + FormatFixed(band.lo_mps, 1) + "-" +
            FormatFixed(band.hi_mps, 0) + " m/s: it looks " +
            (v < band.lo_mps ? "monocular (its size unknown)" : "not in metres") +
            ". Give `scale: auto` in the anchor (--scale auto) to find its scale from the map, "
            "`scale: S` if its positions times S are metres, or `scale: 1` if it is metric");
}

// `scale: auto`: the estimate's global scale (FindGlobalScale), the leading path matched against
// a field about the anchor and each trial corrected on a field along its own corridor.
void PlaceScale(const WorldFrame& world, const PipelineConfig& config, PreparedScenario& ps) {
    const io::Scenario& sc = ps.scenario;
    const AnchorFitConfig fit_cfg = AnchorFitFor(sc, config);
    const TraversableField lead_field = LeadField(
        world, config, ps, kScaleLeadPathM + sc.anchor.position_search_m + fit_cfg.reach_m);
    // Roads are read once; each trial rasterises its own corridor.
    const bool road = sc.mode == io::ScenarioMode::kRoad2d;
    const RoadNetwork roads = road ? LoadRoads(sc, world, config.roads) : RoadNetwork{};
    const Eigen::Vector2d c = ps.anchor.origin_en;
    const TrialField field_for =
        [&](const PlanarTrajectory& trial,
            std::optional<TraversableField>& storage) -> const TraversableField& {
        const std::vector<FieldDisc> corridor = FieldCorridor(trial, c, fit_cfg, config.field);
        RoadNetwork unused;
        storage = road ? RoadField(sc, roads, config, BoundsOf(trial), &corridor)
                       : LoadMapField(sc, world, config, BoundsOf(trial), ps.anchor.origin_up_m,
                                      unused, &corridor, WalkHeights(trial, config.indoor_field));
        return *storage;
    };
    const GlobalScale found =
        FindGlobalScale(sc, config, ps.estimate, ps.anchor, lead_field, field_for);
    ps.scale_fit = found.fit;
    ps.global_scale = found.scale;
    ps.estimate = ScaleAbout(ps.estimate, c, ps.anchor.origin_up_m, ps.global_scale);
}

// The anchor check: the given start, scored against every other heading and against nearby
// positions at the given heading; the better of the two searches is kept.
// With `scale: auto` the leading path is checked at the scale it fits best within the model's
// plausible scale range about the global one: a monocular estimate's scale drifts, and over its
// first few hundred metres it may differ from the drive's by more than a start a few metres
// off the roads shows.
AnchorFitResult CheckAnchor(const PreparedScenario& ps, const PipelineConfig& config) {
    const AnchorFitConfig fit_cfg = AnchorFitFor(ps.scenario, config);
    PlanarTrajectory leading = ps.estimate;
    if (ps.scenario.anchor.scale_auto) {
        const ModelConfig& model = CorrectorFor(ps.scenario, config).model;
        const ScaleFitResult local =
            FitScale(ps.estimate, ps.anchor.origin_en, ps.anchor.origin_up_m, ps.field, false,
                     model.scale_range_min, model.scale_range_max, kScaleStepRatio, 1, fit_cfg);
        if (!local.candidates.empty()) {
            leading = ScaleAbout(ps.estimate, ps.anchor.origin_en, ps.anchor.origin_up_m,
                                 local.candidates.front().scale);
        }
    }
    AnchorFitResult fit = FitAnchor(leading, ps.anchor.origin_en, ps.field, true, 0.0, fit_cfg);
    if (fit_cfg.check_position_radius_m > 0.0) {
        const AnchorFitResult moved = FitAnchor(leading, ps.anchor.origin_en, ps.field, false,
                                                fit_cfg.check_position_radius_m, fit_cfg);
        if (moved.best.rms_m < fit.best.rms_m) fit.best = moved.best;
    }
    return fit;
}

// When the anchor check runs: at the end of the map stage, or (RunCorrection, when the map stage
// may use a second thread) beside the correction, which does not read it.
enum class AnchorCheck { kInMapStage, kBesideCorrectionIfAllowed };

// The `threads` setting of the scenario's map stage: that of its field's section.
int MapThreads(const io::Scenario& sc, const PipelineConfig& config) {
    if (sc.mode != io::ScenarioMode::kIndoor3d) return config.field.threads;
    const bool surface = !sc.map.empty() && IsSurfaceLayer(sc.map.front());
    return surface ? config.surface_field.threads : config.indoor_field.threads;
}

}  // namespace

struct WorldFrame::Impl {
    std::optional<LocalTangentPlane> ltp;
    std::optional<CrsProjection> crs;
    Eigen::Vector2d crs_origin = Eigen::Vector2d::Zero();
};

WorldFrame::WorldFrame(const io::AnchorSpec& a) : impl_(std::make_unique<Impl>()) {
    // `yaw_deg: auto`: the heading is estimated from the map (PrepareScenario), starting from 0.
    anchor_.yaw_rad = DegToRad(a.yaw_deg.value_or(0.0));
    anchor_.origin_up_m = a.z_m;
    if (a.IsGeographic()) {
        impl_->ltp.emplace(GeoPoint{*a.lat_deg, *a.lon_deg, a.alt_m.value_or(0.0)});
    } else {
        try {
            impl_->crs.emplace(*a.crs);
        } catch (const std::invalid_argument& e) {
            throw InputError("", 0, "anchor.crs", e.what());
        }
        impl_->crs_origin = Eigen::Vector2d(*a.easting_m, *a.northing_m);
    }
}
WorldFrame::~WorldFrame() = default;

Eigen::Vector2d WorldFrame::ToEn(const GeoPoint& geo) const {
    if (impl_->ltp) return impl_->ltp->ToEnu(geo).head<2>();
    return impl_->crs->FromGeo(geo) - impl_->crs_origin;
}

GeoPoint WorldFrame::ToGeo(const Eigen::Vector2d& en) const {
    if (impl_->ltp) return impl_->ltp->ToGeo(Eigen::Vector3d(en.x(), en.y(), 0.0));
    return impl_->crs->ToGeo(en + impl_->crs_origin);
}

std::string ToString(Solver solver) { return solver == Solver::kPaper ? "paper" : "driftcorr"; }

namespace {

// An indoor walk starts on the walkable surface: a start farther than kStartOffSurfaceM from it
// (in 3D) means that map and walk are not in one frame (another origin or floor height, a map
// whose z points down), which no correction can repair: reported, not snapped onto the map.
void CheckWalkStart(const PreparedScenario& ps) {
    constexpr double kStartOffSurfaceM = 1.0;
    const Eigen::Vector3d start(ps.estimate.p_en[0].x(), ps.estimate.p_en[0].y(),
                                ps.estimate.up_m[0]);
    const auto q = ps.field.Query(start);
    if (q && q->corridor.value <= kStartOffSurfaceM) return;
    const std::string where = "(" + FormatFixed(start.x(), 2) + ", " + FormatFixed(start.y(), 2) +
                              ", " + FormatFixed(start.z(), 2) + ") m";
    const std::string how_far =
        q ? FormatFixed(q->corridor.value, 2) + " m from the walkable surface"
          : "outside the map's extent";
    throw InputError(ps.scenario.yaml_path, 0, "estimate",
                     "the walk starts " + how_far + " at " + where +
                         " (East, North, up from the anchor): map and walk are not in one frame "
                         "(another origin or floor height, or a map whose z points down?)");
}

// Road mode: a vehicle's height changes far less than its horizontal travel (roads climb a few
// percent, rarely beyond 12 %). An estimate whose height range exceeds half its horizontal path
// (and 50 m) has its axes read wrongly: the frame (kitti_camera's z forward read as up, or the
// other way round), reported before the solve.
void CheckRoadFrame(const PreparedScenario& ps) {
    if (ps.estimate.size() < 2) return;
    const double path_m = PathLength(ps.estimate);
    const auto [lo, hi] = std::minmax_element(ps.estimate.up_m.begin(), ps.estimate.up_m.end());
    const double range_m = *hi - *lo;
    if (range_m <= std::max(50.0, 0.5 * path_m)) return;
    const std::string frame = ps.scenario.frame == FrameAxes::kEnu ? "enu" : "kitti_camera";
    throw InputError(ps.scenario.yaml_path, 0, "frame",
                     "with frame " + frame + " the estimate's height spans " +
                         FormatFixed(range_m, 1) + " m over " + FormatFixed(path_m, 1) +
                         " m of horizontal path, steeper than any road: are its axes those of "
                         "this frame (enu: x East, y North, z up; kitti_camera: x right, y down, "
                         "z forward)?");
}

// Road mode: the map's roads must lie within the drive's reach. A start farther from every road
// than the drive could be stretched (the scale's bound times its path) plus the field's margin
// is a frame error (lat and lon swapped, a map of another place), reported before the solve.
void CheckRoadsInReach(const PreparedScenario& ps, const PipelineConfig& config) {
    if (ps.network.roads.empty() || ps.estimate.size() == 0) return;
    const double gap_m = ps.network.Bounds().exteriorDistance(ps.estimate.p_en[0]);
    const double path_m = PathLength(ps.estimate);
    if (gap_m <= kScaleMax * path_m + config.field.margin_m) return;
    std::string where = FormatFixed(gap_m / 1000.0, 1) + " km from the nearest road of the map";
    std::string hint = "check the anchor and the map file";
    const io::AnchorSpec& a = ps.scenario.anchor;
    const Eigen::AlignedBox2d& geo = ps.network.lon_lat_deg;
    if (!geo.isEmpty()) {
        where += " (its roads span lat " + FormatFixed(geo.min().y(), 4) + ".." +
                 FormatFixed(geo.max().y(), 4) + ", lon " + FormatFixed(geo.min().x(), 4) + ".." +
                 FormatFixed(geo.max().x(), 4) + ")";
        const Eigen::Vector2d centre = geo.center();
        if (a.lat_deg && a.lon_deg) {
            // The geodesic distance to the nearest point of the roads' extent (the plane's
            // distance means little that far from the anchor).
            const Eigen::Vector2d anchor(*a.lon_deg, *a.lat_deg);
            const Eigen::Vector2d near = anchor.cwiseMax(geo.min()).cwiseMin(geo.max());
            const double m =
                GeodesicDistanceM({anchor.y(), anchor.x(), 0.0}, {near.y(), near.x(), 0.0});
            where = FormatFixed(m / 1000.0, 1) + where.substr(where.find(" km"));
            if (std::abs(*a.lat_deg - centre.x()) < 1.0 &&
                std::abs(*a.lon_deg - centre.y()) < 1.0) {
                hint = "lat and lon look swapped";
            }
        }
    }
    throw InputError(ps.scenario.yaml_path, 0, "anchor",
                     "the drive starts " + where + ", beyond the reach of the " +
                         FormatFixed(path_m / 1000.0, 1) + " km drive: " + hint);
}

}  // namespace

namespace {

PreparedScenario Prepare(io::Scenario scenario, Trajectory estimate_frame,
                         std::optional<Trajectory> gt, const PipelineConfig& config,
                         AnchorCheck when);

// Reads the trajectories (the ground truth beside the estimate when a second thread is allowed)
// and prepares the scenario.
PreparedScenario LoadAndPrepare(io::Scenario scenario, const PipelineConfig& config,
                                AnchorCheck when) {
    const auto t0 = std::chrono::steady_clock::now();
    std::future<std::optional<Trajectory>> gt =
        std::async(SecondThreadLaunch(MapThreads(scenario, config)),
                   [&scenario]() -> std::optional<Trajectory> {
                       if (!scenario.ground_truth) return std::nullopt;
                       return io::LoadTrajectory(*scenario.ground_truth);
                   });
    Trajectory estimate = io::LoadTrajectory(scenario.estimate);
    std::optional<Trajectory> ground_truth = gt.get();
    const double load_s = Since(t0);
    PreparedScenario ps =
        Prepare(std::move(scenario), std::move(estimate), std::move(ground_truth), config, when);
    ps.timings.load_s = load_s;
    return ps;
}

PreparedScenario LoadAndPrepare(const std::string& scenario_path, const PipelineConfig& config,
                                AnchorCheck when) {
    const auto t0 = std::chrono::steady_clock::now();
    io::Scenario scenario = io::LoadScenario(scenario_path);
    const double yaml_s = Since(t0);
    PreparedScenario ps = LoadAndPrepare(std::move(scenario), config, when);
    ps.timings.load_s += yaml_s;
    return ps;
}

}  // namespace

PreparedScenario PrepareScenario(const std::string& scenario_path, const PipelineConfig& config) {
    return LoadAndPrepare(scenario_path, config, AnchorCheck::kInMapStage);
}

PreparedScenario PrepareScenario(io::Scenario scenario, const PipelineConfig& config) {
    return LoadAndPrepare(std::move(scenario), config, AnchorCheck::kInMapStage);
}

PreparedScenario PrepareScenario(io::Scenario scenario, Trajectory estimate_frame,
                                 std::optional<Trajectory> gt, const PipelineConfig& config) {
    return Prepare(std::move(scenario), std::move(estimate_frame), std::move(gt), config,
                   AnchorCheck::kInMapStage);
}

namespace {

PreparedScenario Prepare(io::Scenario scenario, Trajectory estimate_frame,
                         std::optional<Trajectory> gt, const PipelineConfig& config,
                         AnchorCheck when) {
    PreparedScenario ps;
    ps.scenario = std::move(scenario);
    const io::Scenario& sc = ps.scenario;
    ps.estimate_frame = std::move(estimate_frame);
    WorldFrame world = [&] {
        try {
            return WorldFrame(sc.anchor);
        } catch (const InputError& e) {
            throw InputError(sc.yaml_path, 0, e.key(), e.what());
        }
    }();
    ps.anchor = world.planar_anchor();
    ps.estimate = ToPlanar(ps.estimate_frame, sc.frame, ps.anchor);
    // Without yaw the corrector takes the heading from the direction of motion (observables.h).
    if (sc.estimate.heading_from_motion) ps.estimate.yaw_rad.clear();
    ps.heading_from_motion = !ps.estimate.HasYaw();
    if (gt && gt->size() > ps.estimate_frame.size()) {
        // An estimate with gaps (frames where the tracker had no pose): the ground truth's poses
        // at the estimate's times, when each has one.
        if (std::optional<Trajectory> at = PosesAtTimes(*gt, ps.estimate_frame.t_s)) gt = at;
    }
    if (gt && gt->size() != ps.estimate_frame.size()) {
        throw InputError(sc.ground_truth ? sc.ground_truth->path : "", 0,
                         sc.ground_truth ? "" : "ground_truth",
                         "ground truth has " + std::to_string(gt->size()) +
                             " poses, the estimate " + std::to_string(ps.estimate_frame.size()));
    }

    const auto t0 = std::chrono::steady_clock::now();
    if (sc.anchor.scale_auto) {
        PlaceScale(world, config, ps);
    } else if (sc.anchor.scale != 1.0) {
        ps.global_scale = sc.anchor.scale;
        ps.estimate =
            ScaleAbout(ps.estimate, ps.anchor.origin_en, ps.anchor.origin_up_m, ps.global_scale);
    } else if (!sc.anchor.scale_given) {
        CheckMetricSpeeds(ps, config);
    }
    if (!sc.anchor.yaw_deg || sc.anchor.position_search_m > 0.0) {
        PlaceStart(world, config, ps);
        if (gt) {
            ps.scenario.warnings.push_back(
                "the ground truth is placed with the start estimated from the map (the anchor "
                "gives none): its errors do not include an error of that start");
        }
    }
    // The ground truth shares the estimate's frame, so the anchor places both.
    if (gt) ps.ground_truth = ToPlanar(*gt, sc.frame, ps.anchor);
    std::vector<double> up = ps.estimate.up_m;
    std::nth_element(up.begin(), up.begin() + up.size() / 2, up.end());
    const std::vector<FieldDisc> corridor =
        FieldCorridor(ps.estimate, ps.anchor.origin_en, AnchorFitFor(sc, config), config.field);
    ps.field = LoadMapField(sc, world, config, BoundsOf(ps.estimate), up[up.size() / 2], ps.network,
                            &corridor, WalkHeights(ps.estimate, config.indoor_field));
    if (sc.mode == io::ScenarioMode::kIndoor3d) {
        CheckWalkStart(ps);
    } else {
        CheckRoadFrame(ps);
        CheckRoadsInReach(ps, config);
    }
    if (ps.network.missing_node_refs > 0) {
        ps.scenario.warnings.push_back(
            "map: " + std::to_string(ps.network.missing_node_refs) +
            " node reference(s) of highway ways have no <node> in the file (an extract cut at "
            "its edge?): those ways are split there, not joined across the gap");
    }
    const bool beside = when == AnchorCheck::kBesideCorrectionIfAllowed &&
                        SecondThreadAllowed(MapThreads(sc, config));
    if (!ps.anchor_fit && !beside) ps.anchor_fit = CheckAnchor(ps, config);
    ps.timings.map_s = Since(t0);
    return ps;
}

}  // namespace

ScaleFitResult FitGlobalScale(const io::Scenario& sc, const PipelineConfig& config,
                              const PlanarTrajectory& estimate, const PlanarAnchor& anchor,
                              const TraversableField& lead_field) {
    const double v = MedianMovingSpeed(estimate, CorrectorFor(sc, config).stationary_m);
    if (!(v > 0.0)) {
        throw InputError(sc.yaml_path, 0, "anchor.scale",
                         "`scale: auto` needs an estimate that moves (every step is a stop)");
    }
    const SpeedBand band = PlausibleSpeeds(sc);
    AnchorFitConfig fit_cfg = AnchorFitFor(sc, config);
    fit_cfg.lead_path_m = kScaleLeadPathM;
    ScaleFitResult fit =
        FitScale(estimate, anchor.origin_en, anchor.origin_up_m, lead_field, !sc.anchor.yaw_deg,
                 band.lo_mps / v, band.hi_mps / v, kScaleStepRatio, kScaleCandidates, fit_cfg);
    if (fit.candidates.empty()) {
        throw InputError(sc.yaml_path, 0, "anchor.scale", "no scale of the estimate fits the map");
    }
    return fit;
}

GlobalScale FindGlobalScale(const io::Scenario& sc, const PipelineConfig& config,
                            const PlanarTrajectory& estimate, const PlanarAnchor& anchor,
                            const TraversableField& lead_field, const TrialField& field_for) {
    return ChooseGlobalScale(sc, config, estimate, anchor,
                             FitGlobalScale(sc, config, estimate, anchor, lead_field), field_for);
}

GlobalScale ChooseGlobalScale(const io::Scenario& sc, const PipelineConfig& config,
                              const PlanarTrajectory& estimate, const PlanarAnchor& anchor,
                              ScaleFitResult fit, const TrialField& field_for) {
    DRIFTCORR_CHECK(!fit.candidates.empty(), "ChooseGlobalScale needs a candidate");
    const Eigen::Vector2d c = anchor.origin_en;
    GlobalScale out;
    out.fit = std::move(fit);
    std::vector<ScaleCandidate>& candidates = out.fit.candidates;
    // The leading path alone may fit several scales about as well, and tells the scale only as
    // well as its first kilometre does: each candidate is corrected whole (its start placed as
    // the fit placed it), the one of lowest NLL is kept, and the global scale is its scale times
    // the ratio of that correction's path to the scaled estimate's.
    // A trial is scored, not written: no window restarts, final solve or covariance.
    CorrectorConfig corrector = CorrectorFor(sc, config);
    corrector.restart_nll_per_pose = std::numeric_limits<double>::infinity();
    corrector.restart_offroad_share = 1.0;
    corrector.refine = false;
    corrector.compute_covariance = false;
    std::size_t kept = 0;
    double best_nll = std::numeric_limits<double>::infinity(), kept_ratio = 1.0;
    for (std::size_t k = 0; k < candidates.size(); ++k) {
        const PlanarTrajectory trial =
            ApplyPlacement(ScaleAbout(estimate, c, anchor.origin_up_m, candidates[k].scale), c,
                           candidates[k].placement);
        std::optional<TraversableField> storage;
        const TraversableField& field = field_for(trial, storage);
        const CorrectionResult r = CorrectTrajectory(trial, &field, corrector);
        candidates[k].nll = Usable(r.status) ? r.nll : std::numeric_limits<double>::infinity();
        if (candidates[k].nll < best_nll) {
            best_nll = candidates[k].nll, kept = k;
            kept_ratio = PathLength(r.corrected) / std::max(PathLength(trial), 1e-9);
        }
    }
    out.fit.kept = kept;
    out.scale = candidates[kept].scale * (std::isfinite(best_nll) ? kept_ratio : 1.0);
    return out;
}

double ScaleLeadPathM() { return kScaleLeadPathM; }

TraversableField LoadMapField(const io::Scenario& sc, const WorldFrame& world,
                              const PipelineConfig& config, const Eigen::AlignedBox2d& region_en,
                              double up_m, RoadNetwork& network,
                              const std::vector<FieldDisc>* corridor,
                              const std::optional<HeightRange>& heights) {
    if (sc.mode == io::ScenarioMode::kIndoor3d) {
        if (IsSurfaceLayer(sc.map.front())) return LoadSurfaceField(sc, config.surface_field);
        TraversableField field = LoadIndoorField(sc, config.indoor_field, up_m, network, heights);
        field.set_floor_heights_m(FloorHeights(sc, config));
        return field;
    }
    network = LoadRoads(sc, world, config.roads);
    return RoadField(sc, network, config, region_en, corridor);
}

std::vector<double> FloorHeights(const io::Scenario& sc, const PipelineConfig& config) {
    std::vector<double> heights;
    if (sc.mode != io::ScenarioMode::kIndoor3d) return heights;
    for (const io::MapLayerSpec& layer : sc.map) {
        if (layer.format != io::MapFormat::kGeoJson || !layer.floor_z_m) continue;
        const double z = *layer.floor_z_m + config.indoor_field.device_height_m;
        if (std::find(heights.begin(), heights.end(), z) == heights.end()) heights.push_back(z);
    }
    return heights;
}

CorrectorConfig CorrectorFor(const io::Scenario& sc, const PipelineConfig& config) {
    return sc.mode == io::ScenarioMode::kIndoor3d ? config.indoor_corrector : config.corrector;
}

CorrectionResult Correct(const PreparedScenario& ps, const PipelineConfig& config,
                         const ProgressCallback& progress) {
    if (config.solver == Solver::kPaper) {
        return CorrectWithPaperMethod(ps.estimate, &ps.field, config.paper, progress);
    }
    return CorrectTrajectory(ps.estimate, &ps.field, CorrectorFor(ps.scenario, config), progress);
}

Verdict JudgeResult(const PreparedScenario& ps, const PipelineConfig& config,
                    const CorrectionResult& result) {
    const io::AnchorSpec& a = ps.scenario.anchor;
    const bool start_estimated = !a.yaw_deg || a.position_search_m > 0.0;
    return JudgeCorrection(ps.estimate, &ps.field, CorrectorFor(ps.scenario, config).model, result,
                           ps.anchor_fit ? &*ps.anchor_fit : nullptr, start_estimated,
                           config.solver == Solver::kDriftcorr, config.verdict);
}

CorrectionRun RunCorrection(const std::string& scenario_path, const PipelineConfig& config,
                            const ProgressCallback& progress) {
    return RunCorrection(
        LoadAndPrepare(scenario_path, config, AnchorCheck::kBesideCorrectionIfAllowed), config,
        progress);
}

CorrectionRun RunCorrection(io::Scenario scenario, const PipelineConfig& config,
                            const ProgressCallback& progress) {
    return RunCorrection(
        LoadAndPrepare(std::move(scenario), config, AnchorCheck::kBesideCorrectionIfAllowed),
        config, progress);
}

namespace {

// The corrected trajectory in the estimate's frame. A heading taken from the motion is the
// reference the solved heading is compared with (the orientations, if any, turn by the
// difference); without orientations the poses get the solved heading (FromPlanar).
Trajectory CorrectedInFrame(const PreparedScenario& ps, const PipelineConfig& config,
                            PlanarTrajectory corrected) {
    PlanarTrajectory reference = ps.estimate;
    const double stationary_m = CorrectorFor(ps.scenario, config).stationary_m;
    if (!reference.HasYaw()) reference.yaw_rad = UnwrappedHeadings(reference, stationary_m);
    if (!corrected.HasYaw()) corrected.yaw_rad = UnwrappedHeadings(corrected, stationary_m);
    return FromPlanar(corrected, reference, ps.estimate_frame, ps.scenario.frame, ps.anchor);
}

}  // namespace

DriveScale DriveScaleOf(const CorrectionRun& run) {
    DriveScale d;
    if (!Usable(run.result.status) || run.result.input_kept) return d;
    d.value = run.global_scale * PathLength(run.result.corrected) /
              std::max(PathLength(run.estimate), 1e-9);
    if (run.result.covariance.status == CovarianceStatus::kOk)
        d.sd = run.global_scale * run.result.covariance.mean_scale_sd;
    return d;
}

CorrectionRun RunCorrection(PreparedScenario ps, const PipelineConfig& config,
                            const ProgressCallback& progress) {
    CorrectionRun run;
    run.timings = ps.timings;
    run.map_grid_cells = ps.field.Samples();
    run.global_scale = ps.global_scale;
    run.scale_fit = ps.scale_fit;

    // A scenario prepared without its anchor check has it done here, beside the correction.
    std::future<AnchorFitResult> check;
    if (!ps.anchor_fit) {
        check = std::async(SecondThreadLaunch(MapThreads(ps.scenario, config)),
                           [&ps, &config] { return CheckAnchor(ps, config); });
    }
    const auto t0 = std::chrono::steady_clock::now();
    run.result = Correct(ps, config, progress);
    run.timings.solve_s = Since(t0);
    if (check.valid()) ps.anchor_fit = check.get();
    run.verdict = JudgeResult(ps, config, run.result);
    if (Usable(run.result.status)) {
        run.corrected_frame = CorrectedInFrame(ps, config, run.result.corrected);
        if (ps.ground_truth) run.after = ComputeMetrics(run.result.corrected, *ps.ground_truth);
    }
    if (ps.ground_truth) run.before = ComputeMetrics(ps.estimate, *ps.ground_truth);
    run.scenario = std::move(ps.scenario);
    run.estimate_frame = std::move(ps.estimate_frame);
    run.estimate = std::move(ps.estimate);
    run.ground_truth = std::move(ps.ground_truth);
    run.network = std::move(ps.network);
    run.anchor = ps.anchor;
    run.anchor_fit = ps.anchor_fit;
    run.heading_from_motion = ps.heading_from_motion;
    return run;
}

}  // namespace driftcorr::pipeline
