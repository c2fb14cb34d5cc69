// driftcorr_make_building_scenario: writes the deterministic synthetic building scenario
// (building.pcd/.ply/.bt/.ot, ground_truth.tum, estimate.tum, scenario.yaml, scenario_ply.yaml,
// scenario_octomap.yaml, scenario_ot.yaml) and a raw scan of the building (building_raw.pcd)
// into a folder. See datasets/README.md, "Synthetic building".
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "building.h"
#include "driftcorr/core/angles.h"
#include "driftcorr/mapping/atomic_file.h"
#include "driftcorr/mapping/surface_io.h"
#include "raw_building.h"
#include "synth_common.h"
#include "walk.h"

namespace driftcorr::synth {
namespace {

constexpr double kSurfaceSpacing_m = 0.1;  // point lattice of the map
constexpr double kOctomapResolution_m = 0.1;
constexpr double kAnchorEasting_m = 456500.0;  // EPSG:32632 (UTM 32N), Karlsruhe area
constexpr double kAnchorNorthing_m = 5427500.0;
/// The raw scan's seed is the PDR seed plus this ("raw" in ASCII), so it follows --seed.
constexpr std::uint64_t kRawScanSeedOffset = 0x726177;

struct Options {
    std::string out_dir;
    PdrDriftConfig drift;
    RawScanConfig raw;  ///< its seed follows drift.seed (ParseArgs)
};

void PrintUsage(std::FILE* stream) {
    const PdrDriftConfig d;
    const RawScanConfig r;
    std::fprintf(stream,
                 "usage: driftcorr_make_building_scenario <out_dir> [--seed N] [--scale-error X]\n"
                 "         [--heading-bias-deg-per-sqrt-s X] [--height-drift-m-per-sqrt-s X]\n"
                 "         [--raw-spacing-m X]\n"
                 "  --seed N                          noise seed, unsigned 64-bit (default %llu)\n"
                 "  --scale-error X                   step length factor, in [0.5, 1.5] "
                 "(default %g)\n"
                 "  --heading-bias-deg-per-sqrt-s X   random walk of the heading-rate bias, in "
                 "[0, 1] (default %g)\n"
                 "  --height-drift-m-per-sqrt-s X     random walk of the height offset, in [0, 1] "
                 "(default %g)\n"
                 "  --raw-spacing-m X                 sample spacing of building_raw.pcd [m], in "
                 "(0.01, 0.5] (default %g)\n",
                 static_cast<unsigned long long>(d.seed), d.scale_error,
                 d.heading_bias_deg_per_sqrt_s, d.height_drift_m_per_sqrt_s, r.spacing_m);
}

std::string ParseArgs(int argc, char** argv, Options& opt) {
    const std::string error = ParseGeneratorArgs(
        argc, argv, opt.out_dir, [&](const std::string& flag, const char* value) {
            return ApplySeedOrNumberFlag(
                flag, value, opt.drift.seed,
                {{"--scale-error", &opt.drift.scale_error},
                 {"--heading-bias-deg-per-sqrt-s", &opt.drift.heading_bias_deg_per_sqrt_s},
                 {"--height-drift-m-per-sqrt-s", &opt.drift.height_drift_m_per_sqrt_s},
                 {"--raw-spacing-m", &opt.raw.spacing_m}});
        });
    if (!error.empty()) return error;
    if (const std::string e = opt.drift.Validate(); !e.empty()) return e;
    if (const std::string e = opt.raw.Validate(); !e.empty()) return "raw scan: " + e;
    opt.raw.seed = opt.drift.seed + kRawScanSeedOffset;
    return "";
}

void WriteTumFile(const std::string& path, const std::vector<WalkPose>& poses) {
    std::string text;
    for (const WalkPose& p : poses) {
        const double half_yaw_rad = 0.5 * WrapAngle(p.yaw_rad);
        text += Format("%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", p.t_s, p.p_enu.x(), p.p_enu.y(),
                       p.p_enu.z(), 0.0, 0.0, std::sin(half_yaw_rad), std::cos(half_yaw_rad));
    }
    WriteFileAtomically(path, text);
}

struct ErrorSummary {
    double distance_m = 0.0, final_error_m = 0.0, max_error_m = 0.0, ate_m = 0.0;
    double max_height_error_m = 0.0, floor_share = 0.0;
};

ErrorSummary Compare(const std::vector<WalkPose>& gt, const std::vector<WalkPose>& est) {
    ErrorSummary s;
    double sum2 = 0.0;
    std::size_t on_floor = 0;
    for (std::size_t k = 0; k < gt.size(); ++k) {
        if (k > 0) s.distance_m += (gt[k].p_enu - gt[k - 1].p_enu).head<2>().norm();
        const double e = (est[k].p_enu - gt[k].p_enu).head<2>().norm();
        const double ez = std::abs(est[k].p_enu.z() - gt[k].p_enu.z());
        sum2 += e * e;
        s.max_error_m = std::max(s.max_error_m, e);
        s.max_height_error_m = std::max(s.max_height_error_m, ez);
        s.final_error_m = e;
        on_floor += ez <= 1.5;
    }
    s.ate_m = std::sqrt(sum2 / double(gt.size()));
    s.floor_share = double(on_floor) / double(gt.size());
    return s;
}

// The map layer declares the building's lift shaft (a scan does not show it; see docs/FORMAT.md).
std::string ScenarioYaml(const std::vector<std::string>& header, const std::string& map_path,
                         const std::string& map_format, const Rect& lift) {
    std::string yaml;
    for (const std::string& line : header) yaml += "# " + line + "\n";
    yaml += "name: synthetic-building-" + map_format + "\n";
    yaml += "mode: indoor3d\n";
    yaml += "estimate:\n  path: estimate.tum\n  format: tum\n";
    yaml += "ground_truth:\n  path: ground_truth.tum\n  format: tum\n";
    yaml += "frame: enu\n";
    yaml += "anchor:\n  crs: EPSG:32632\n";
    yaml += Format("  easting_m: %.3f\n  northing_m: %.3f\n", kAnchorEasting_m, kAnchorNorthing_m);
    yaml += "  yaw_deg: 0.0\n  z_m: 0.0\n";
    yaml += "map:\n  - path: " + map_path + "\n    format: " + map_format + "\n";
    yaml +=
        Format("    lifts: [[%.15g, %.15g, %.15g, %.15g]]\n", lift.x0, lift.y0, lift.x1, lift.y1);
    return yaml;
}

std::vector<std::string> YamlHeader(const Options& opt, std::size_t poses, std::size_t points,
                                    std::size_t raw_points, const ErrorSummary& s) {
    const PdrDriftConfig& d = opt.drift;
    const RawScanConfig& r = opt.raw;
    return {
        "Synthetic building scenario, generated by driftcorr_make_building_scenario",
        "(driftcorr repository, datasets/synth_building); do not edit, regenerate instead.",
        "Three floors (0, 4, 8 m) of 60 m x 30 m: corridor, rooms, a staircase and a lift.",
        "The maps (building.pcd, .ply, .bt and .ot) hold the same walkable surface in",
        "the anchor's local East-North-Up frame [m] (the trajectory frame: yaw 0, z_m 0).",
        Format("seed %llu, scale error %.15g, step noise %.15g, heading bias %.15g deg/s +",
               static_cast<unsigned long long>(d.seed), d.scale_error, d.step_noise_rel,
               d.heading_bias0_deg_per_s),
        Format("random walk %.15g deg/s per sqrt(s), heading noise %.15g deg, height drift %.15g "
               "m per sqrt(s)",
               d.heading_bias_deg_per_sqrt_s, d.heading_noise_deg, d.height_drift_m_per_sqrt_s),
        Format("regenerate: driftcorr_make_building_scenario <out_dir> --seed %llu --scale-error "
               "%.15g --heading-bias-deg-per-sqrt-s %.15g --height-drift-m-per-sqrt-s %.15g",
               static_cast<unsigned long long>(d.seed), d.scale_error,
               d.heading_bias_deg_per_sqrt_s, d.height_drift_m_per_sqrt_s),
        Format("%zu poses, %.1f m walked, %zu surface points; uncorrected estimate: ATE %.2f m, "
               "final %.2f m, max %.2f m, max height error %.2f m",
               poses, s.distance_m, points, s.ate_m, s.final_error_m, s.max_error_m,
               s.max_height_error_m),
        Format("building_raw.pcd (in no scenario): a raw scan of this building (its walkable "
               "surface: building_raw_walkable.pcd, building.pcd without the floor under its "
               "furniture), %zu points, --raw-spacing-m %.15g, noise %.15g m, dropout "
               "%.15g, hole share %.15g, seed %llu",
               raw_points, r.spacing_m, r.noise_sigma_m, r.dropout, r.hole_share,
               static_cast<unsigned long long>(r.seed)),
    };
}

// The walkable surface of the raw scan's building: the clean surface without the floor under
// the tables and cabinets the scan adds (a person cannot stand there).
std::vector<Eigen::Vector3d> WithoutFurniture(const std::vector<Eigen::Vector3d>& surface,
                                              const BuildingLayout& building,
                                              const RawScanConfig& raw) {
    const std::vector<RoomFurniture> furniture = PlaceFurniture(building, raw);
    std::vector<Eigen::Vector3d> out;
    for (const Eigen::Vector3d& p : surface) {
        const bool under =
            std::any_of(furniture.begin(), furniture.end(), [&](const RoomFurniture& f) {
                return std::abs(p.z() - building.floor_z_m[f.floor]) < 0.01 &&
                       (f.table.Contains(p.x(), p.y()) || f.cabinet.Contains(p.x(), p.y()));
            });
        if (!under) out.push_back(p);
    }
    return out;
}

int Run(const Options& opt) {
    const BuildingLayout building = MakeBuildingLayout();
    const std::vector<Eigen::Vector3d> surface = SampleSurface(building, kSurfaceSpacing_m);
    const std::vector<WalkPose> gt = SimulateWalk(building, WalkConfig{});
    const std::vector<WalkPose> est = IntegrateDriftingPdr(gt, opt.drift);
    const ErrorSummary s = Compare(gt, est);
    const std::filesystem::path dir(opt.out_dir);
    std::filesystem::create_directories(dir);
    WriteSurfacePointsPcd((dir / "building.pcd").string(), surface);
    WriteSurfacePointsPly((dir / "building.ply").string(), surface);
    WriteOctomapFromPoints((dir / "building.bt").string(), surface, kOctomapResolution_m);
    WriteOctomapFromPoints((dir / "building.ot").string(), surface, kOctomapResolution_m);
    WriteTumFile((dir / "ground_truth.tum").string(), gt);
    WriteTumFile((dir / "estimate.tum").string(), est);
    const std::vector<Eigen::Vector3d> raw = SampleRawBuilding(building, opt.raw);
    WriteSurfacePointsPcd((dir / "building_raw.pcd").string(), raw);
    WriteSurfacePointsPcd((dir / "building_raw_walkable.pcd").string(),
                          WithoutFurniture(surface, building, opt.raw));
    const auto header = YamlHeader(opt, gt.size(), surface.size(), raw.size(), s);
    WriteFileAtomically((dir / "scenario_ply.yaml").string(),
                        ScenarioYaml(header, "building.ply", "ply", building.lift));
    WriteFileAtomically((dir / "scenario_octomap.yaml").string(),
                        ScenarioYaml(header, "building.bt", "bt", building.lift));
    WriteFileAtomically((dir / "scenario_ot.yaml").string(),
                        ScenarioYaml(header, "building.ot", "ot", building.lift));
    WriteFileAtomically((dir / "scenario.yaml").string(),
                        ScenarioYaml(header, "building.pcd", "pcd", building.lift));
    std::printf(
        "synthetic-building: %zu poses, %.1f m walked, %zu surface points, %zu raw scan points; "
        "estimate ATE %.2f m, final error %.2f m, max error %.2f m, max height error %.2f m, "
        "%.1f %% of poses on the right floor (seed %llu)\n",
        gt.size(), s.distance_m, surface.size(), raw.size(), s.ate_m, s.final_error_m,
        s.max_error_m, s.max_height_error_m, 100.0 * s.floor_share,
        static_cast<unsigned long long>(opt.drift.seed));
    return 0;
}

}  // namespace
}  // namespace driftcorr::synth

int main(int argc, char** argv) {
    using namespace driftcorr::synth;
    Options opt;
    return GeneratorMain(
        argc, argv, "driftcorr_make_building_scenario", PrintUsage,
        [&opt](int n, char** args) { return ParseArgs(n, args, opt); },
        [&opt] { return Run(opt); });
}
