// The definitions of what convert.h declares.
#include "convert.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "driftcorr/core/frames.h"
#include "driftcorr/mapping/geodesy.h"

namespace driftcorr::python {
namespace {

namespace fs = std::filesystem;
using Rows = py::array_t<double, py::array::c_style | py::array::forcecast>;

[[noreturn]] void Fail(const std::string& name, const std::string& message) {
    throw py::value_error(name + ": " + message);
}

std::string ShapeText(const py::array& a) {
    std::string s = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

// `obj` as a C-contiguous float64 array; anything numpy cannot convert is a type_error.
Rows AsRows(const py::handle& obj, const std::string& name) {
    if (obj.is_none()) Fail(name, "missing (None)");
    py::array raw;
    try {
        raw = py::array::ensure(obj);
    } catch (const py::error_already_set&) {
    }
    if (!raw || raw.dtype().kind() == 'O' || raw.dtype().kind() == 'U' ||
        raw.dtype().kind() == 'S' || raw.dtype().kind() == 'c') {
        throw py::type_error(name + ": expected an array of real numbers");
    }
    return Rows::ensure(raw);
}

// Checks a 2-D array with one of two column counts and finite values; names the bad entry.
Rows CheckTable(const py::handle& obj, const std::string& name, py::ssize_t cols_full,
                py::ssize_t cols_short, const char* const* columns, const std::string& layout,
                std::size_t min_rows) {
    Rows a = AsRows(obj, name);
    if (a.ndim() != 2 || (a.shape(1) != cols_full && a.shape(1) != cols_short)) {
        Fail(name, "expected " + layout + ", got shape " + ShapeText(a));
    }
    if (std::size_t(a.shape(0)) < min_rows) {
        Fail(name, std::to_string(a.shape(0)) + " rows, need at least " + std::to_string(min_rows));
    }
    auto r = a.unchecked<2>();
    for (py::ssize_t i = 0; i < r.shape(0); ++i) {
        for (py::ssize_t j = 0; j < r.shape(1); ++j) {
            if (!std::isfinite(r(i, j))) {
                Fail(name, "row " + std::to_string(i) + ", column " + std::to_string(j) + " (" +
                               columns[j] + ") is " + (std::isnan(r(i, j)) ? "NaN" : "infinite"));
            }
        }
        if (i > 0 && !(r(i, 0) > r(i - 1, 0))) {
            char msg[160];
            std::snprintf(msg, sizeof(msg),
                          "row %zd: timestamp %.9g does not increase (previous %.9g)", i, r(i, 0),
                          r(i - 1, 0));
            Fail(name, msg);
        }
    }
    return a;
}

Eigen::Quaterniond UnitQuaternion(double x, double y, double z, double w, const std::string& name,
                                  py::ssize_t row) {
    const Eigen::Quaterniond q(w, x, y, z);
    if (!(q.norm() > 1e-9)) {
        Fail(name, "row " + std::to_string(row) + ": quaternion (qx qy qz qw) has zero norm");
    }
    return q.normalized();
}

double DoubleOf(const py::handle& value, const std::string& key) {
    if (py::isinstance<py::bool_>(value) ||
        !(py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value) ||
          py::hasattr(value, "__float__"))) {
        throw py::type_error(key + ": expected a number, got " +
                             std::string(py::str(py::type::handle_of(value).attr("__name__"))));
    }
    const double v = value.cast<double>();
    if (!std::isfinite(v)) Fail(key, "is not a finite number");
    return v;
}

std::string StringOf(const py::handle& value, const std::string& key) {
    if (!py::isinstance<py::str>(value)) throw py::type_error(key + ": expected a string");
    return value.cast<std::string>();
}

// A path a layer names: str or os.PathLike, made absolute; the file must exist.
std::string ExistingPath(const py::handle& value, const std::string& key) {
    const std::string path = PathOf(value, key);
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) Fail(key, "no such file '" + path + "'");
    return fs::absolute(path).lexically_normal().string();
}

void CheckKeys(const py::dict& d, std::initializer_list<const char*> known,
               const std::string& name) {
    for (const auto& item : d) {
        const std::string key = py::str(item.first);
        bool ok = false;
        for (const char* k : known) ok = ok || key == k;
        if (!ok) Fail(name, "unknown key '" + key + "'");
    }
}

py::dict DictOf(const py::handle& obj, const std::string& name) {
    if (obj.is_none()) Fail(name, "missing (None)");
    if (!py::isinstance<py::dict>(obj)) throw py::type_error(name + ": expected a dict");
    return py::reinterpret_borrow<py::dict>(obj);
}

io::AnchorSpec AnchorFromDict(const py::handle& obj, io::ScenarioMode mode) {
    const py::dict d = DictOf(obj, "anchor");
    CheckKeys(d,
              {"lat_deg", "lon_deg", "alt_m", "crs", "easting_m", "northing_m", "yaw_deg", "z_m",
               "position_search_m", "scale"},
              "anchor");
    auto has = [&d](const char* k) { return d.contains(k) && !d[k].is_none(); };
    auto num = [&d](const char* k) { return DoubleOf(d[k], std::string("anchor['") + k + "']"); };
    const bool geographic = has("lat_deg") || has("lon_deg") || has("alt_m");
    const bool grid = has("crs") || has("easting_m") || has("northing_m");
    if (geographic && grid)
        Fail("anchor", "give either lat_deg/lon_deg[/alt_m] or crs/easting_m/northing_m, not both");
    if (!geographic && !grid)
        Fail("anchor", "needs lat_deg and lon_deg, or crs, easting_m and northing_m");
    io::AnchorSpec a;
    const std::vector<const char*> required =
        geographic ? std::vector<const char*>{"lat_deg", "lon_deg"}
                   : std::vector<const char*>{"crs", "easting_m", "northing_m"};
    for (const char* k : required) {
        if (!has(k)) Fail(std::string("anchor['") + k + "']", "missing");
    }
    if (geographic) {
        a.lat_deg = num("lat_deg");
        a.lon_deg = num("lon_deg");
        a.alt_m = has("alt_m") ? num("alt_m") : 0.0;
    } else {
        a.crs = StringOf(d["crs"], "anchor['crs']");
        a.easting_m = num("easting_m");
        a.northing_m = num("northing_m");
    }
    if (!has("yaw_deg")) {
        Fail("anchor['yaw_deg']",
             "missing (the heading of the trajectory frame in East-North, "
             "degrees counter-clockwise, or 'auto' to estimate it from the map)");
    }
    const py::handle yaw = d["yaw_deg"];
    if (py::isinstance<py::str>(yaw)) {
        if (yaw.cast<std::string>() != "auto") Fail("anchor['yaw_deg']", "a number or 'auto'");
    } else {
        a.yaw_deg = num("yaw_deg");
    }
    if (has("scale")) {
        const py::handle scale = d["scale"];
        const std::string text = py::isinstance<py::str>(scale)
                                     ? scale.cast<std::string>()
                                     : py::str(scale).cast<std::string>();
        const std::string problem = io::ParseAnchorScale(text, a);
        if (!problem.empty()) Fail("anchor['scale']", problem);
    }
    a.position_search_m = has("position_search_m") ? num("position_search_m") : 0.0;
    if (const std::optional<io::AnchorProblem> problem = io::FindAnchorProblem(a)) {
        Fail("anchor['" + problem->key + "']", problem->rule);
    }
    if (mode == io::ScenarioMode::kIndoor3d && !has("z_m")) {
        Fail("anchor['z_m']",
             "missing in indoor3d mode (the height of the trajectory frame's "
             "origin in the map's height datum: it picks the floor)");
    }
    a.z_m = has("z_m") ? num("z_m") : 0.0;
    return a;
}

io::MapLayerSpec LayerFrom(const py::handle& item, const std::string& key) {
    io::MapLayerSpec layer;
    if (!py::isinstance<py::dict>(item)) {
        layer.path = ExistingPath(item, key);
        const auto format = io::MapFormatFromExtension(layer.path);
        if (!format)
            Fail(key, "the extension of '" + layer.path +
                          "' names no known map format "
                          "(give a dict with 'path' and 'format')");
        layer.format = *format;
        return layer;
    }
    const py::dict d = py::reinterpret_borrow<py::dict>(item);
    CheckKeys(d, {"path", "format", "role", "floor_z_m", "lifts"}, key);
    if (!d.contains("path") || d["path"].is_none()) Fail(key + "['path']", "missing");
    layer.path = ExistingPath(d["path"], key + "['path']");
    if (d.contains("format") && !d["format"].is_none()) {
        const std::string name = StringOf(d["format"], key + "['format']");
        const auto format = io::ParseMapFormat(name);
        if (!format)
            Fail(key + "['format']",
                 "unknown value '" + name +
                     "' (expected osm | geojson | pcd | ply | bt | ot | octomap)");
        layer.format = *format;
    } else {
        const auto format = io::MapFormatFromExtension(layer.path);
        if (!format)
            Fail(key + "['format']",
                 "missing, and the extension of '" + layer.path + "' names no known map format");
        layer.format = *format;
    }
    if (d.contains("role") && !d["role"].is_none()) {
        const std::string name = StringOf(d["role"], key + "['role']");
        const auto role = io::ParseLayerRole(name);
        if (!role)
            Fail(key + "['role']", "unknown value '" + name + "' (expected walkways | floorplan)");
        layer.role = *role;
    }
    if (d.contains("floor_z_m") && !d["floor_z_m"].is_none()) {
        layer.floor_z_m = DoubleOf(d["floor_z_m"], key + "['floor_z_m']");
    }
    if (d.contains("lifts") && !d["lifts"].is_none()) {
        const std::string lifts_key = key + "['lifts']";
        const py::handle lifts = d["lifts"];
        const std::string shape = "expected a list of [x0, y0, x1, y1] lists";
        if (!py::isinstance<py::sequence>(lifts) || py::isinstance<py::str>(lifts)) {
            Fail(lifts_key, shape);
        }
        const py::sequence seq = py::reinterpret_borrow<py::sequence>(lifts);
        for (std::size_t i = 0; i < seq.size(); ++i) {
            const std::string item_key = lifts_key + "[" + std::to_string(i) + "]";
            const py::handle item = seq[i];
            if (!py::isinstance<py::sequence>(item) || py::isinstance<py::str>(item) ||
                py::len(item) != 4) {
                Fail(item_key, shape);
            }
            const py::sequence v = py::reinterpret_borrow<py::sequence>(item);
            auto at = [&](std::size_t k) {
                return DoubleOf(v[k], item_key + "[" + std::to_string(k) + "]");
            };
            layer.lifts.push_back({at(0), at(1), at(2), at(3)});
        }
        const std::string problem = io::CheckLayerLifts(layer.format, layer.lifts);
        if (!problem.empty()) Fail(lifts_key, problem);
    }
    return layer;
}

std::vector<io::MapLayerSpec> MapFrom(const py::handle& map) {
    if (map.is_none()) Fail("map", "missing (None): give a layer path or a list of layers");
    std::vector<io::MapLayerSpec> layers;
    if (py::isinstance<py::list>(map) || py::isinstance<py::tuple>(map)) {
        const py::sequence seq = py::reinterpret_borrow<py::sequence>(map);
        if (seq.size() == 0) Fail("map", "must list at least one layer");
        for (std::size_t i = 0; i < seq.size(); ++i) {
            layers.push_back(LayerFrom(seq[i], "map[" + std::to_string(i) + "]"));
        }
    } else {
        layers.push_back(LayerFrom(map, "map"));
    }
    return layers;
}

const char* const kFrameColumns[] = {"t", "x", "y", "z", "qx", "qy", "qz", "qw"};
const char* const kPlanarColumns[] = {"t", "east", "north", "up", "yaw"};

}  // namespace

std::string PathOf(const py::handle& value, const std::string& name) {
    if (value.is_none()) Fail(name, "missing (None)");
    try {
        return py::module_::import("os").attr("fspath")(value).cast<std::string>();
    } catch (const py::error_already_set&) {
    } catch (const py::cast_error&) {  // bytes
    }
    throw py::type_error(name + ": expected a path (str or os.PathLike)");
}

Trajectory TrajectoryFromArray(const py::handle& obj, const std::string& name,
                               std::size_t min_poses) {
    const Rows a =
        CheckTable(obj, name, 8, 4, kFrameColumns,
                   "an (N, 8) array `t x y z qx qy qz qw` or (N, 4) `t x y z`", min_poses);
    auto r = a.unchecked<2>();
    Trajectory traj;
    for (py::ssize_t i = 0; i < r.shape(0); ++i) {
        traj.t_s.push_back(r(i, 0));
        traj.p_frame.emplace_back(r(i, 1), r(i, 2), r(i, 3));
        if (r.shape(1) == 8) {
            traj.q_frame_body.push_back(
                UnitQuaternion(r(i, 4), r(i, 5), r(i, 6), r(i, 7), name, i));
        }
    }
    return traj;
}

py::array_t<double> TrajectoryToArray(const Trajectory& traj) {
    const py::ssize_t n = py::ssize_t(traj.size()), cols = traj.HasOrientation() ? 8 : 4;
    py::array_t<double> out({n, cols});
    auto w = out.mutable_unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i) {
        w(i, 0) = traj.t_s[i];
        for (int k = 0; k < 3; ++k) w(i, 1 + k) = traj.p_frame[i][k];
        if (cols == 8) {
            const Eigen::Quaterniond& q = traj.q_frame_body[i];
            w(i, 4) = q.x(), w(i, 5) = q.y(), w(i, 6) = q.z(), w(i, 7) = q.w();
        }
    }
    return out;
}

PlanarTrajectory PlanarFromArray(const py::handle& obj, const std::string& name) {
    const Rows a =
        CheckTable(obj, name, 5, 4, kPlanarColumns,
                   "an (N, 5) array `t east north up yaw` or (N, 4) `t east north up`", 2);
    auto r = a.unchecked<2>();
    PlanarTrajectory traj;
    for (py::ssize_t i = 0; i < r.shape(0); ++i) {
        traj.t_s.push_back(r(i, 0));
        traj.p_en.emplace_back(r(i, 1), r(i, 2));
        traj.up_m.push_back(r(i, 3));
        if (r.shape(1) == 5) traj.yaw_rad.push_back(r(i, 4));
    }
    return traj;
}

py::array_t<double> PlanarToArray(const PlanarTrajectory& traj) {
    const py::ssize_t n = py::ssize_t(traj.size()), cols = traj.HasYaw() ? 5 : 4;
    py::array_t<double> out({n, cols});
    auto w = out.mutable_unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i) {
        w(i, 0) = traj.t_s[i];
        w(i, 1) = traj.p_en[i].x();
        w(i, 2) = traj.p_en[i].y();
        w(i, 3) = traj.up_m[i];
        if (cols == 5) w(i, 4) = traj.yaw_rad[i];
    }
    return out;
}

FramePose FramePoseFromArray(const py::handle& obj, const std::string& name) {
    const Rows a = AsRows(obj, name);
    if (a.ndim() != 1 || a.shape(0) != 8) {
        Fail(name, "expected 8 values `t x y z qx qy qz qw`, got shape " + ShapeText(a));
    }
    auto r = a.unchecked<1>();
    for (py::ssize_t j = 0; j < 8; ++j) {
        if (!std::isfinite(r(j))) {
            Fail(name, std::string("value ") + std::to_string(j) + " (" + kFrameColumns[j] +
                           ") is " + (std::isnan(r(j)) ? "NaN" : "infinite"));
        }
    }
    FramePose pose;
    pose.t_s = r(0);
    pose.p_frame = Eigen::Vector3d(r(1), r(2), r(3));
    pose.q_frame_body = UnitQuaternion(r(4), r(5), r(6), r(7), name, 0);
    return pose;
}

py::array_t<double> FramePoseToArray(double t_s, const Eigen::Vector3d& p,
                                     const Eigen::Quaterniond& q) {
    py::array_t<double> out(8);
    auto w = out.mutable_unchecked<1>();
    w(0) = t_s, w(1) = p.x(), w(2) = p.y(), w(3) = p.z();
    w(4) = q.x(), w(5) = q.y(), w(6) = q.z(), w(7) = q.w();
    return out;
}

py::array_t<double> PlanarPoseToArray(const PlanarPose& pose) {
    py::array_t<double> out(5);
    auto w = out.mutable_unchecked<1>();
    w(0) = pose.t_s, w(1) = pose.p_en.x(), w(2) = pose.p_en.y(), w(3) = pose.up_m;
    w(4) = pose.yaw_rad.value_or(std::nan(""));  // PushResult::corrected always has a heading
    return out;
}

namespace {
// var_e cov_en var_n var_up var_yaw cov_e_yaw cov_n_yaw, as w(0) .. w(6).
template <typename Row>
void WriteCovariance(const PoseCovariance& c, Row&& w) {
    w(0) = c.xy_m2(0, 0), w(1) = c.xy_m2(0, 1), w(2) = c.xy_m2(1, 1);
    w(3) = c.z_m2, w(4) = c.yaw_rad2;
    w(5) = c.xy_yaw_m_rad.x(), w(6) = c.xy_yaw_m_rad.y();
}
}  // namespace

py::array_t<double> CovarianceToArray(const std::vector<double>& t_s,
                                      const std::vector<PoseCovariance>& poses) {
    const py::ssize_t n = py::ssize_t(poses.size());
    py::array_t<double> out({n, py::ssize_t(8)});
    auto w = out.mutable_unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i) {
        w(i, 0) = t_s[i];
        WriteCovariance(poses[i], [&](py::ssize_t k) -> double& { return w(i, k + 1); });
    }
    return out;
}

py::array_t<double> PoseCovarianceToArray(const PoseCovariance& c) {
    py::array_t<double> out(py::ssize_t(7));
    auto w = out.mutable_unchecked<1>();
    WriteCovariance(c, [&](py::ssize_t k) -> double& { return w(k); });
    return out;
}

py::dict MetricsToDict(const ErrorMetrics& m) {
    py::dict d;
    d["poses"] = m.poses;
    d["ate_m"] = m.ate_m;
    d["final_m"] = m.final_m;
    d["max_m"] = m.max_m;
    d["p90_m"] = m.p90_m;
    d["mean_m"] = m.mean_m;
    d["drift_pct"] = m.drift_pct;
    d["floor_accuracy"] = m.floor_accuracy;
    d["path_length_m"] = m.path_length_m;
    return d;
}

io::Scenario ScenarioFromParts(const std::string& name, const py::handle& mode,
                               const py::handle& frame, const py::handle& anchor,
                               const py::handle& map) {
    io::Scenario sc;
    sc.name = name;
    if (mode.is_none()) Fail("mode", "missing (None): 'road2d' or 'indoor3d'");
    const std::string mode_name = StringOf(mode, "mode");
    const auto m = io::ParseScenarioMode(mode_name);
    if (!m) Fail("mode", "unknown value '" + mode_name + "' (expected road2d | indoor3d)");
    sc.mode = *m;
    if (frame.is_none()) Fail("frame", "missing (None): 'kitti_camera' or 'enu'");
    const std::string frame_name = StringOf(frame, "frame");
    const auto axes = ParseFrameAxes(frame_name);
    if (!axes) Fail("frame", "unknown value '" + frame_name + "' (expected kitti_camera | enu)");
    sc.frame = *axes;
    sc.anchor = AnchorFromDict(anchor, sc.mode);
    sc.map = MapFrom(map);
    return sc;
}

py::dict AnchorToDict(const io::AnchorSpec& a) {
    py::dict d;
    if (a.IsGeographic()) {
        d["lat_deg"] = *a.lat_deg;
        d["lon_deg"] = *a.lon_deg;
        d["alt_m"] = a.alt_m.value_or(0.0);
    } else {
        d["crs"] = *a.crs;
        d["easting_m"] = *a.easting_m;
        d["northing_m"] = *a.northing_m;
    }
    if (a.yaw_deg) {
        d["yaw_deg"] = *a.yaw_deg;
    } else {
        d["yaw_deg"] = "auto";
    }
    d["position_search_m"] = a.position_search_m;
    if (a.scale_auto) {
        d["scale"] = "auto";
    } else if (a.scale_given) {
        d["scale"] = a.scale;
    }
    d["z_m"] = a.z_m;
    return d;
}

py::list MapToList(const std::vector<io::MapLayerSpec>& layers) {
    py::list out;
    for (const io::MapLayerSpec& l : layers) {
        py::dict d;
        d["path"] = l.path;
        d["format"] = io::ToString(l.format);
        if (l.role != io::LayerRole::kNone) {
            d["role"] = l.role == io::LayerRole::kWalkways ? "walkways" : "floorplan";
        }
        if (l.floor_z_m) d["floor_z_m"] = *l.floor_z_m;
        if (!l.lifts.empty()) {
            py::list lifts;
            for (const LiftShaft& s : l.lifts) lifts.append(py::make_tuple(s.x0, s.y0, s.x1, s.y1));
            d["lifts"] = lifts;
        }
        out.append(d);
    }
    return out;
}

pipeline::PipelineConfig ConfigFrom(const py::handle& config, const std::string& solver) {
    pipeline::PipelineConfig cfg;
    if (!config.is_none()) {
        cfg = pipeline::LoadPipelineConfig(PathOf(config, "config"));
    }
    if (solver == "paper") {
        cfg.solver = pipeline::Solver::kPaper;
    } else if (solver != "driftcorr") {
        Fail("solver", "unknown value '" + solver + "' (expected driftcorr | paper)");
    }
    return cfg;
}

}  // namespace driftcorr::python
