#pragma once
// The parser harnesses shared by the libFuzzer targets (fuzz_*.cpp) and the corpus regression test
// (tests/test_fuzz_regressions.cpp), so both run every input through exactly the same code.
//
// Each harness writes the input to a per-process temp file (the parsers take paths), calls the
// parser and swallows driftcorr::InputError, the documented outcome for bad input. Anything else
// escapes: a crash, a sanitizer report, another exception (std::terminate under libFuzzer, a test
// failure in gtest). On success the result is checked against what the header promises (finite
// values, unit quaternions, increasing timestamps, ...); a broken promise throws
// FuzzInvariantError, i.e. a finding like any other.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "driftcorr/core/errors.h"
#include "driftcorr/io/scenario.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/mapping/geojson_reader.h"
#include "driftcorr/mapping/osm_reader.h"
#include "driftcorr/mapping/surface_io.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::fuzz {

/// A parser returned without error but broke a promise of its header.
class FuzzInvariantError : public std::logic_error {
public:
    using std::logic_error::logic_error;
};

inline void Require(bool ok, const std::string& what) {
    if (!ok) throw FuzzInvariantError("invariant violated: " + what);
}

/// `<dir>/driftcorr_fuzz_<pid>_<name>`, holding `bytes`; removed on destruction.
class TempFile {
public:
    TempFile(const std::string& dir, const std::string& name, std::string_view bytes)
        : path_(dir + "/driftcorr_fuzz_" + std::to_string(::getpid()) + "_" + name) {
        std::FILE* file = std::fopen(path_.c_str(), "wb");
        if (file == nullptr) throw std::runtime_error("cannot create " + path_);
        const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), file) == bytes.size();
        if (std::fclose(file) != 0 || !ok) throw std::runtime_error("cannot write " + path_);
    }
    ~TempFile() { std::remove(path_.c_str()); }
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;
    const std::string& path() const { return path_; }

private:
    std::string path_;
};

/// Where the harnesses put their temp files under libFuzzer: $TMPDIR, else /tmp.
inline std::string DefaultTempDir() {
    const char* dir = std::getenv("TMPDIR");
    return dir != nullptr && *dir != '\0' ? std::string(dir) : std::string("/tmp");
}

inline std::string_view AsText(const std::uint8_t* data, std::size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

/// ReadTum/ReadKitti promise: equal lengths (no orientations at all for a positions-only TUM
/// file, core/types.h), finite values, unit quaternions, increasing time.
inline void CheckTrajectory(const Trajectory& traj, std::size_t min_poses) {
    Require(traj.size() >= min_poses, "fewer poses than min_poses");
    Require(traj.p_frame.size() == traj.size() &&
                (!traj.HasOrientation() || traj.q_frame_body.size() == traj.size()),
            "trajectory arrays differ in length");
    for (std::size_t i = 0; i < traj.size(); ++i) {
        Require(std::isfinite(traj.t_s[i]), "timestamp not finite");
        Require(i == 0 || traj.t_s[i] > traj.t_s[i - 1], "timestamps do not increase");
        Require(traj.p_frame[i].allFinite(), "position not finite");
        if (!traj.HasOrientation()) continue;
        Require(traj.q_frame_body[i].coeffs().allFinite(), "quaternion not finite");
        Require(std::abs(traj.q_frame_body[i].norm() - 1.0) < 1e-6, "quaternion not unit");
    }
}

/// TUM: the whole input is the trajectory file.
inline void RunTum(std::string_view input, const std::string& tmp_dir) {
    const TempFile file(tmp_dir, "tum.txt", input);
    try {
        CheckTrajectory(io::ReadTum(file.path()), 3);
    } catch (const InputError&) {
    }
}

/// KITTI: the input up to the first 0x00 byte is the poses file, the rest the times file. Without
/// a 0x00 byte there is no times file and the timestamps come from rate_hz = 10.
inline void RunKitti(std::string_view input, const std::string& tmp_dir) {
    const std::size_t split = input.find('\0');
    const TempFile poses(tmp_dir, "kitti_poses.txt", input.substr(0, split));
    std::optional<TempFile> times;
    if (split != std::string_view::npos) {
        times.emplace(tmp_dir, "kitti_times.txt", input.substr(split + 1));
    }
    const std::optional<std::string> times_path =
        times ? std::optional<std::string>(times->path()) : std::nullopt;
    const std::optional<double> rate_hz = times ? std::nullopt : std::optional<double>(10.0);
    try {
        CheckTrajectory(io::ReadKitti(poses.path(), times_path, rate_hz, 3), 3);
    } catch (const InputError&) {
    }
}

/// scenario.yaml (the file name must end in .yaml). The files it names are not opened.
inline void RunScenarioYaml(std::string_view input, const std::string& tmp_dir) {
    const TempFile file(tmp_dir, "scenario.yaml", input);
    try {
        const io::Scenario s = io::LoadScenario(file.path());
        Require(!s.map.empty(), "scenario without map layers");
        Require(s.anchor.lat_deg.has_value() != s.anchor.crs.has_value(),
                "anchor must be geographic xor grid");
        Require(
            (!s.anchor.yaw_deg || std::isfinite(*s.anchor.yaw_deg)) && std::isfinite(s.anchor.z_m),
            "anchor yaw/z not finite");
        if (s.anchor.lat_deg) {
            Require(std::abs(*s.anchor.lat_deg) <= 90.0 && std::abs(*s.anchor.lon_deg) <= 180.0,
                    "anchor lat/lon out of range");
        } else {
            Require(std::isfinite(*s.anchor.easting_m) && std::isfinite(*s.anchor.northing_m),
                    "anchor easting/northing not finite");
        }
        for (const io::MapLayerSpec& layer : s.map) {
            Require(layer.lifts.empty() || layer.format == io::MapFormat::kPcd ||
                        layer.format == io::MapFormat::kPly ||
                        layer.format == io::MapFormat::kOctomap,
                    "lifts on a layer that is no point cloud or OctoMap");
            for (const LiftShaft& l : layer.lifts) {
                Require(std::isfinite(l.x0) && std::isfinite(l.y0) && l.x1 > l.x0 && l.y1 > l.y0 &&
                            std::isfinite(l.x1) && std::isfinite(l.y1),
                        "lift footprint not finite or empty");
            }
        }
        for (const io::TrajectorySource* src :
             {&s.estimate, s.ground_truth ? &*s.ground_truth : nullptr}) {
            if (src == nullptr) continue;
            Require(!src->rate_hz || (std::isfinite(*src->rate_hz) && *src->rate_hz > 0.0),
                    "rate_hz not positive and finite");
            const bool kitti = src->format == io::TrajectoryFormat::kKitti;
            Require(!kitti || src->rate_hz || src->times_path,
                    "kitti source without rate_hz or times");
            Require(kitti || (!src->rate_hz && !src->times_path),
                    "rate_hz or times on a source that is not kitti");
        }
    } catch (const InputError&) {
    }
}

/// OpenStreetMap XML.
inline void RunOsm(std::string_view input, const std::string& tmp_dir) {
    const TempFile file(tmp_dir, "map.osm", input);
    try {
        const OsmRoads roads = ReadOsmRoads(file.path());
        Require(roads.report.ways_highway == roads.ways.size(), "ways_highway != ways.size()");
        for (const OsmWay& way : roads.ways) {
            Require(way.nodes.size() >= 2, "way with fewer than 2 nodes returned");
            Require(std::isfinite(way.width_m) && way.width_m >= 0.0, "bad width_m");
            Require(way.lanes >= 0, "negative lanes");
            for (const GeoPoint& p : way.nodes) {
                Require(std::abs(p.lat_deg) <= 90.0 && std::abs(p.lon_deg) <= 180.0,
                        "node coordinates out of range");
            }
        }
    } catch (const InputError&) {
    }
}

/// GeoJSON floor plans / walkways: a layer that loads has a known CRS and finite coordinates.
inline void RunGeoJson(std::string_view input, const std::string& tmp_dir) {
    const TempFile file(tmp_dir, "layer.geojson", input);
    try {
        const GeoJsonLayer layer = ReadGeoJson(file.path());
        Require(!layer.crs.empty(), "layer without a normalised CRS");
        for (const GeoJsonLine& l : layer.lines) {
            for (const auto& p : l.points) Require(p.allFinite(), "line point not finite");
        }
        for (const GeoJsonPolygon& poly : layer.polygons) {
            Require(poly.outer.size() >= 3, "polygon with fewer than 3 points");
            for (const auto& p : poly.outer) Require(p.allFinite(), "polygon point not finite");
        }
    } catch (const InputError&) {
    }
}

/// Point clouds (PCD, PLY) and OctoMap files of walkable surfaces: what loads is non-empty and
/// finite. The file name's extension selects the reader, as in a scenario.
inline void RunSurface(std::string_view input, const std::string& tmp_dir, const char* name) {
    const TempFile file(tmp_dir, name, input);
    try {
        const std::vector<Eigen::Vector3d> points = ReadSurfacePoints(file.path());
        Require(!points.empty(), "surface reader returned no point");
        for (const auto& p : points) Require(p.allFinite(), "surface point not finite");
    } catch (const InputError&) {
    }
}
inline void RunPcd(std::string_view input, const std::string& tmp_dir) {
    RunSurface(input, tmp_dir, "surface.pcd");
}
inline void RunPly(std::string_view input, const std::string& tmp_dir) {
    RunSurface(input, tmp_dir, "surface.ply");
}
inline void RunOctomap(std::string_view input, const std::string& tmp_dir) {
    RunSurface(input, tmp_dir, "surface.bt");
}
inline void RunOctomapOt(std::string_view input, const std::string& tmp_dir) {
    RunSurface(input, tmp_dir, "surface.ot");
}

/// params.yaml. A config that loads must pass its own Validate().
inline void RunParamsYaml(std::string_view input, const std::string& tmp_dir) {
    const TempFile file(tmp_dir, "params.yaml", input);
    try {
        const pipeline::PipelineConfig config = pipeline::LoadPipelineConfig(file.path());
        Require(config.Validate().empty(), "loaded config fails Validate(): " + config.Validate());
    } catch (const InputError&) {
    }
}

}  // namespace driftcorr::fuzz
