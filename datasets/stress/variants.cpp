// The definitions of what variants.h declares.
#include "variants.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/geodesy.h"
#include "driftcorr/mapping/osm_reader.h"
#include "road_removal.h"
#include "synth_common.h"

namespace driftcorr::stress {
namespace {

using synth::Format;

// Streams of the seeded random numbers, one per variant that draws any.
constexpr std::uint64_t kDropStepsStream = 1;
constexpr std::uint64_t kAnchorOffsetStream = 2;
// The monocular variants' normal numbers: seeded by the seed plus this, one sequence per scale.
constexpr std::uint64_t kMonocularSeedOffset = 1000;

VariantOutcome Skipped(const std::string& name, const std::string& reason) {
    return {name, std::nullopt, reason};
}

VariantSpec BaseSpec(const InputScenario& input, const std::string& name) {
    VariantSpec spec;
    spec.name = name;
    spec.anchor = input.scenario.anchor;
    return spec;
}

double PathLength_m(const Trajectory& traj) {
    double length_m = 0.0;
    for (std::size_t i = 1; i < traj.size(); ++i) {
        length_m += (traj.p_frame[i] - traj.p_frame[i - 1]).norm();
    }
    return length_m;
}

VariantOutcome Clean(const InputScenario& input) {
    VariantSpec spec = BaseSpec(input, "clean");
    spec.description = {
        "variant clean: a faithful copy of the input (every file copied byte for byte, "
        "scenario.yaml re-written with paths relative to this folder)"};
    return {spec.name, spec, "a faithful copy of the input"};
}

VariantOutcome DropSteps(const InputScenario& input, const StressConfig& config) {
    const std::string name = "drop_steps";
    const DropStepsConfig& d = config.drop;
    UniformSource random(config.seed, kDropStepsStream);
    const std::vector<DropEpisode> episodes = PlanDropEpisodes(input.estimate.size(), d, random);
    if (episodes.empty()) {
        return Skipped(name, Format("the estimate has %zu poses, too few for one episode of up to "
                                    "%zu steps in %.0f %% of its steps",
                                    input.estimate.size(), d.max_steps, 100.0 * d.max_share));
    }
    VariantSpec spec = BaseSpec(input, name);
    spec.estimate = ShortenSteps(input.estimate, episodes);
    spec.description = {
        Format("variant drop_steps (seed %llu): odometry that drops motion, as when "
               "frame-to-frame registration fails:",
               static_cast<unsigned long long>(config.seed)),
        Format("in %zu episodes of %zu-%zu consecutive steps the estimate's relative translations "
               "are shortened to a ratio in [%g, %g)",
               episodes.size(), d.min_steps, d.max_steps, d.min_ratio, d.max_ratio),
        "of their length (relative rotations unchanged), then the estimate is re-integrated from "
        "its relative poses,",
        "so every later pose shifts; step i is the motion from pose i-1 to pose i.",
        Format("estimate path length %.1f m -> %.1f m", PathLength_m(input.estimate),
               PathLength_m(*spec.estimate))};
    for (const DropEpisode& e : episodes) {
        spec.description.push_back(Format("drop episode: first_step %zu, steps %zu, ratio %s",
                                          e.first_step, e.steps, ExactNumber(e.ratio).c_str()));
    }
    return {name, spec, Format("%zu episode%s", episodes.size(), episodes.size() == 1 ? "" : "s")};
}

VariantOutcome HeadingBias(const InputScenario& input, FrameAxes axes, double bias_deg_per_s) {
    const std::string name = Format("heading_bias_%g", bias_deg_per_s);
    VariantSpec spec = BaseSpec(input, name);
    spec.estimate = ApplyHeadingBias(input.estimate, axes, DegToRad(bias_deg_per_s));
    const double duration_s = input.estimate.t_s.back() - input.estimate.t_s.front();
    spec.description = {
        Format("variant %s: a steady heading-rate bias of %g deg/s about the frame's Up axis "
               "(%s): each step's relative motion",
               name.c_str(), bias_deg_per_s,
               axes == FrameAxes::kKittiCamera ? "-y of kitti_camera" : "z of enu"),
        "is turned by bias * (t - t_0) and the estimate re-integrated (body-frame step "
        "translations unchanged);",
        Format("bias_deg_per_s %s; the heading is off by %.2f deg at the last pose (t - t_0 = "
               "%.2f s)",
               ExactNumber(bias_deg_per_s).c_str(), bias_deg_per_s * duration_s, duration_s)};
    return {name, spec, Format("heading off by %.1f deg at the end", bias_deg_per_s * duration_s)};
}

/// Yaw in (-180, 180].
double WrapDeg(double yaw_deg) {
    while (yaw_deg > 180.0) yaw_deg -= 360.0;
    while (yaw_deg <= -180.0) yaw_deg += 360.0;
    return yaw_deg;
}

VariantOutcome YawOffset(const InputScenario& input, double offset_deg) {
    const std::string name = Format("yaw_off_%g", offset_deg);
    if (!input.ground_truth) {
        return Skipped(name, "the input has no ground truth to keep in its place in the world");
    }
    VariantSpec spec = BaseSpec(input, name);
    const double old_yaw_deg = *input.scenario.anchor.yaw_deg;
    spec.anchor.yaw_deg = WrapDeg(old_yaw_deg + offset_deg);
    // R(new) uv' = R(old) uv  =>  uv' = R(old - new) uv, with the radians ToPlanar will use.
    const double turn_rad = DegToRad(old_yaw_deg) - DegToRad(*spec.anchor.yaw_deg);
    spec.ground_truth = RotateAboutUp(*input.ground_truth, input.scenario.frame, turn_rad);
    spec.description = {
        Format("variant %s: a wrong anchor heading: anchor yaw_deg %s -> %s (%+g deg); the "
               "estimate file is unchanged.",
               name.c_str(), ExactNumber(old_yaw_deg).c_str(),
               ExactNumber(*spec.anchor.yaw_deg).c_str(), offset_deg),
        Format("The ground truth is turned by %+g deg about the frame's Up axis at its origin, so "
               "that placed with this",
               -offset_deg),
        "anchor it lands exactly where the input's ground truth lands with the input's anchor."};
    return {name, spec, Format("anchor yaw %+g deg", offset_deg)};
}

/// Ground truth in a frame whose lat/lon anchor moved from `from` to `to` (same yaw): every pose
/// goes through WGS84, so it stays in place exactly (the two tangent planes are turned against
/// each other by a few microradians). Returns the largest departure from a pure translation.
double MoveGeographic(const Trajectory& gt, FrameAxes axes, double yaw_rad,
                      const LocalTangentPlane& from, const LocalTangentPlane& to,
                      const Eigen::Vector2d& shift_uv, Trajectory& moved) {
    const Eigen::Rotation2Dd r(yaw_rad);
    moved = gt;
    double departure_m = 0.0;
    for (std::size_t i = 0; i < gt.size(); ++i) {
        const Eigen::Vector3d uvh = FrameToUvh(axes, gt.p_frame[i]);
        const Eigen::Vector2d en = r * uvh.head<2>();
        const Eigen::Vector3d enu_to =
            to.ToEnu(from.ToGeo(Eigen::Vector3d(en.x(), en.y(), uvh.z())));
        const Eigen::Vector2d uv_to = r.inverse() * enu_to.head<2>();
        moved.p_frame[i] = UvhToFrame(axes, Eigen::Vector3d(uv_to.x(), uv_to.y(), enu_to.z()));
        departure_m = std::max(departure_m, (uv_to - (uvh.head<2>() - shift_uv)).norm());
    }
    // East of the old plane, seen in the new one.
    const Eigen::Vector3d a = to.ToEnu(from.ToGeo(Eigen::Vector3d::Zero()));
    const Eigen::Vector3d b = to.ToEnu(from.ToGeo(Eigen::Vector3d(1000.0, 0.0, 0.0)));
    const double turn_rad = std::atan2(b.y() - a.y(), b.x() - a.x());
    if (moved.HasOrientation()) {
        for (Eigen::Quaterniond& q : moved.q_frame_body) q = UpRotation(axes, turn_rad) * q;
    }
    return departure_m;
}

VariantOutcome AnchorOffset(const InputScenario& input, const StressConfig& config) {
    const std::string name = Format("anchor_off_%gm", config.anchor_offset_m);
    if (!input.ground_truth) {
        return Skipped(name, "the input has no ground truth to keep in its place in the world");
    }
    const io::Scenario& sc = input.scenario;
    UniformSource random(config.seed, kAnchorOffsetStream);
    const double direction_rad = random.Range(0.0, 2.0 * kPi);
    const Eigen::Vector2d shift_en =
        config.anchor_offset_m * Eigen::Vector2d(std::cos(direction_rad), std::sin(direction_rad));
    const double yaw_rad = DegToRad(*sc.anchor.yaw_deg);
    const Eigen::Vector2d shift_uv = Eigen::Rotation2Dd(-yaw_rad) * shift_en;
    VariantSpec spec = BaseSpec(input, name);
    std::string moved_how;
    if (sc.anchor.IsGeographic()) {
        const LocalTangentPlane from({*sc.anchor.lat_deg, *sc.anchor.lon_deg, *sc.anchor.alt_m});
        const GeoPoint moved = from.ToGeo(Eigen::Vector3d(shift_en.x(), shift_en.y(), 0.0));
        spec.anchor.lat_deg = moved.lat_deg;
        spec.anchor.lon_deg = moved.lon_deg;
        const LocalTangentPlane to({moved.lat_deg, moved.lon_deg, *sc.anchor.alt_m});
        Trajectory gt;
        const double departure_m =
            MoveGeographic(*input.ground_truth, sc.frame, yaw_rad, from, to, shift_uv, gt);
        spec.ground_truth = gt;
        moved_how = Format(
            "lat/lon %.10f, %.10f -> %.10f, %.10f (alt_m unchanged); through WGS84, "
            "within %.4f m of a pure translation",
            *sc.anchor.lat_deg, *sc.anchor.lon_deg, moved.lat_deg, moved.lon_deg, departure_m);
    } else {
        *spec.anchor.easting_m += shift_en.x();
        *spec.anchor.northing_m += shift_en.y();
        spec.ground_truth = TranslateHorizontal(*input.ground_truth, sc.frame, -shift_uv);
        moved_how = Format("easting/northing %.3f, %.3f -> %.3f, %.3f", *sc.anchor.easting_m,
                           *sc.anchor.northing_m, *spec.anchor.easting_m, *spec.anchor.northing_m);
    }
    spec.description = {
        Format("variant %s (seed %llu): a wrong anchor position: moved %g m towards %.2f deg "
               "(counter-clockwise from East),",
               name.c_str(), static_cast<unsigned long long>(config.seed), config.anchor_offset_m,
               RadToDeg(direction_rad)),
        Format("i.e. dE %+.3f m, dN %+.3f m: %s.", shift_en.x(), shift_en.y(), moved_how.c_str()),
        Format("The estimate file is unchanged; the ground truth is moved by (%+.3f, %+.3f) m in "
               "the frame's horizontal",
               -shift_uv.x(), -shift_uv.y()),
        "plane (u, v), so that placed with this anchor it lands where the input's ground truth "
        "lands with the input's anchor."};
    return {name, spec,
            Format("anchor moved %g m (dE %+.1f, dN %+.1f)", config.anchor_offset_m, shift_en.x(),
                   shift_en.y())};
}

/// The anchor's East-North plane, with an unknown CRS reported against the scenario.yaml.
AnchorPlane MakePlane(const io::Scenario& sc) {
    try {
        return AnchorPlane(sc.anchor);
    } catch (const std::invalid_argument& e) {
        throw InputError(sc.yaml_path, 0, "anchor.crs", e.what());
    }
}

struct LongestWay {
    std::size_t layer = 0;
    WayAlong way;
    double gt_length_m = 0.0;
};

std::optional<LongestWay> FindLongestWay(const InputScenario& input, double radius_m) {
    const io::Scenario& sc = input.scenario;
    const AnchorPlane plane = MakePlane(sc);
    PlanarAnchor anchor;
    anchor.yaw_rad = DegToRad(*sc.anchor.yaw_deg);
    const std::vector<Eigen::Vector2d> gt_en = ToPlanar(*input.ground_truth, sc.frame, anchor).p_en;
    std::optional<LongestWay> best;
    for (std::size_t layer = 0; layer < sc.map.size(); ++layer) {
        if (sc.map[layer].format != io::MapFormat::kOsm) continue;
        const OsmRoads roads = ReadOsmRoads(sc.map[layer].path);
        std::vector<std::vector<Eigen::Vector2d>> ways_en;
        for (const OsmWay& way : roads.ways) {
            ways_en.emplace_back();
            for (const GeoPoint& g : way.nodes) ways_en.back().push_back(plane.ToEn(g));
        }
        const auto longest =
            LongestAlong(GroundTruthAlongWays(roads.ways, ways_en, gt_en, radius_m));
        if (longest && (!best || longest->along_m > best->way.along_m)) {
            best = LongestWay{layer, *longest, 0.0};
        }
    }
    if (best) {
        for (std::size_t k = 1; k < gt_en.size(); ++k)
            best->gt_length_m += (gt_en[k] - gt_en[k - 1]).norm();
    }
    return best;
}

VariantOutcome RoadRemoved(const InputScenario& input, const StressConfig& config) {
    const std::string name = "road_removed";
    const io::Scenario& sc = input.scenario;
    if (sc.mode != io::ScenarioMode::kRoad2d) {
        return Skipped(name, "mode " + io::ToString(sc.mode) + ": its map layers are not roads");
    }
    if (!input.ground_truth) return Skipped(name, "the input has no ground truth to find a road");
    const bool has_osm = std::any_of(sc.map.begin(), sc.map.end(), [](const auto& layer) {
        return layer.format == io::MapFormat::kOsm;
    });
    if (!has_osm) return Skipped(name, "the map has no OSM layer");
    const std::optional<LongestWay> best = FindLongestWay(input, config.road_radius_m);
    if (!best) {
        return Skipped(name, Format("the ground truth lies within %g m of no highway way",
                                    config.road_radius_m));
    }
    const std::string& path = sc.map[best->layer].path;
    const std::optional<std::string> text = RemoveOsmWay(input.file_bytes.at(path), best->way.id);
    if (!text) {
        return Skipped(name, Format("way %lld is not exactly one <way> element in ",
                                    static_cast<long long>(best->way.id)) +
                                 path);
    }
    VariantSpec spec = BaseSpec(input, name);
    spec.map_text[best->layer] = *text;
    spec.description = {
        Format("variant road_removed: one mapped road missing: removed way: %lld (highway=%s) "
               "from %s (map layer %zu);",
               static_cast<long long>(best->way.id), best->way.highway.c_str(),
               std::filesystem::path(path).filename().c_str(), best->layer),
        Format("ground truth along it: %.1f m of %.1f m (steps whose both poses lie within %g m "
               "of the way's polyline",
               best->way.along_m, best->gt_length_m, config.road_radius_m),
        "in the anchor's East-North plane); the longest such way is removed, its nodes stay in "
        "the file."};
    return {name, spec,
            Format("way %lld removed (%.0f m of ground truth along it)",
                   static_cast<long long>(best->way.id), best->way.along_m)};
}

// A monocular tracker's frame has its origin at the first pose: an input that starts elsewhere
// (`start_uv` in the frame's horizontal plane; a generated drive in its map's frame) gets the frame
// moved there, horizontally, with the anchor moved to the start's place (through WGS84, as
// anchor_off moves it) and the ground truth kept in its place in the world. Returns what it did
// ("" for an input that starts at its origin); nothing when it cannot (not a lat/lon anchor with a
// yaw).
std::optional<std::string> MoveOriginToStart(const InputScenario& input,
                                             const Eigen::Vector2d& start_uv, VariantSpec& spec) {
    const io::Scenario& sc = input.scenario;
    if (start_uv.norm() == 0.0) return std::string();
    if (!sc.anchor.IsGeographic() || !sc.anchor.yaw_deg) return std::nullopt;
    const double yaw_rad = DegToRad(*sc.anchor.yaw_deg);
    const Eigen::Vector2d start_en = Eigen::Rotation2Dd(yaw_rad) * start_uv;
    const LocalTangentPlane from({*sc.anchor.lat_deg, *sc.anchor.lon_deg, *sc.anchor.alt_m});
    const GeoPoint moved = from.ToGeo(Eigen::Vector3d(start_en.x(), start_en.y(), 0.0));
    spec.anchor.lat_deg = moved.lat_deg;
    spec.anchor.lon_deg = moved.lon_deg;
    if (input.ground_truth) {
        const LocalTangentPlane to({moved.lat_deg, moved.lon_deg, *sc.anchor.alt_m});
        Trajectory gt;
        MoveGeographic(*input.ground_truth, sc.frame, yaw_rad, from, to, start_uv, gt);
        spec.ground_truth = gt;
    }
    return Format(
        "the frame's origin moved to the estimate's start (%.3f, %.3f m in the frame), "
        "the anchor to lat/lon %.10f, %.10f",
        start_uv.x(), start_uv.y(), moved.lat_deg, moved.lon_deg);
}

// mono_<g> and mono_<g>_auto: the estimate as a monocular tracker would have written it, with
// the anchor as given and with `scale: auto`. Both share one draw of the scale's walk.
std::vector<VariantOutcome> Monocular(const InputScenario& input, const StressConfig& config,
                                      std::size_t index) {
    const double g = config.monocular_scales[index];
    const std::string name = Format("mono_%g", g);
    synth::NormalSampler normal(config.seed + kMonocularSeedOffset + index);
    std::vector<double> scales;
    VariantSpec spec = BaseSpec(input, name);
    const Eigen::Vector2d start_uv =
        FrameToUvh(input.scenario.frame, input.estimate.p_frame.front()).head<2>();
    const std::optional<std::string> moved = MoveOriginToStart(input, start_uv, spec);
    if (!moved) {
        const std::string why =
            "the estimate does not start at its frame's origin and the anchor is not lat/lon "
            "with a yaw: the frame cannot be moved to the start, as a tracker's is";
        return {Skipped(name, why), Skipped(name + "_auto", why)};
    }
    spec.estimate =
        ScaleLikeMonocular(TranslateHorizontal(input.estimate, input.scenario.frame, -start_uv), g,
                           config.monocular_drift_per_100m, normal, &scales);
    const auto [lo, hi] = std::minmax_element(scales.begin(), scales.end());
    spec.description = {
        Format("variant %s (seed %llu): a monocular tracker's estimate: every step's translation "
               "multiplied by",
               name.c_str(), static_cast<unsigned long long>(config.seed)),
        Format("s_i = %s * exp(w_i), w_i a random walk of %s per sqrt(100 m) of the step's length, "
               "and the estimate re-integrated",
               ExactNumber(g).c_str(), ExactNumber(config.monocular_drift_per_100m).c_str()),
        Format("(orientations unchanged); s_i ranges over %.4f..%.4f (%.3f..%.3f of %s); path "
               "length %.1f m -> %.1f m",
               *lo, *hi, *lo / g, *hi / g, ExactNumber(g).c_str(), PathLength_m(input.estimate),
               PathLength_m(*spec.estimate))};
    if (!moved->empty()) spec.description.push_back(*moved);
    VariantSpec with_auto = spec;
    with_auto.name = name + "_auto";
    with_auto.anchor.scale_auto = true;
    with_auto.description.push_back("the anchor says `scale: auto`");
    const std::string note = Format("scale %.4f..%.4f", *lo, *hi);
    return {{spec.name, spec, note}, {with_auto.name, with_auto, note + ", scale: auto"}};
}

}  // namespace

std::vector<VariantOutcome> MakeVariants(const InputScenario& input, const StressConfig& config) {
    const FrameAxes axes = input.scenario.frame;
    std::vector<VariantOutcome> out;
    if (!config.monocular_scales.empty()) {
        for (std::size_t k = 0; k < config.monocular_scales.size(); ++k) {
            for (VariantOutcome& v : Monocular(input, config, k)) out.push_back(std::move(v));
        }
        return out;
    }
    out.push_back(Clean(input));
    out.push_back(DropSteps(input, config));
    for (double bias : config.heading_bias_deg_per_s) out.push_back(HeadingBias(input, axes, bias));
    for (double offset : config.yaw_offset_deg) out.push_back(YawOffset(input, offset));
    out.push_back(AnchorOffset(input, config));
    out.push_back(RoadRemoved(input, config));
    return out;
}

}  // namespace driftcorr::stress
