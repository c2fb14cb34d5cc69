// The definitions of what driftcorr/io/scenario.h declares.
#include "driftcorr/io/scenario.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <utility>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/io/text_file.h"
#include "driftcorr/mapping/geodesy.h"
#include "parse_number.h"

namespace driftcorr::io {
namespace {

namespace fs = std::filesystem;

/// 1-based line of a node, 0 when yaml-cpp has no position for it.
long LineOf(const YAML::Node& node) {
    const YAML::Mark mark = node.Mark();
    return mark.line >= 0 ? mark.line + 1 : 0;
}

std::string Lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

/// One YAML mapping of the scenario file (the root, `estimate`, `anchor`, `map[i]`, ...) with the
/// key path used in messages. Every accessor throws InputError naming file, line and key.
class Block {
public:
    Block(const std::string& file, YAML::Node node, std::string prefix, long parent_line)
        : file_(file), node_(std::move(node)), prefix_(std::move(prefix)) {
        const long own_line = LineOf(node_);
        line_ = own_line > 0 ? own_line : parent_line;
        if (!node_.IsMap()) Fail("", "must be a mapping of keys to values");
        CheckNoDuplicateKeys();
    }

    /// "prefix.key" (just "prefix" for an empty key).
    std::string Key(const std::string& key) const {
        if (key.empty()) return prefix_;
        return prefix_.empty() ? key : prefix_ + "." + key;
    }
    /// Throws InputError at the key's line (or the block's line when the key is absent).
    [[noreturn]] void Fail(const std::string& key, const std::string& message) const {
        const std::optional<YAML::Node> child = key.empty() ? std::nullopt : Find(key);
        throw InputError(file_, child ? LineOf(*child) : line_, Key(key), message);
    }
    /// The value of `key`, std::nullopt when it is absent or null (`key:` with nothing after it).
    std::optional<YAML::Node> Find(const std::string& key) const {
        const YAML::Node child = node_[key];
        if (!child.IsDefined() || child.IsNull()) return std::nullopt;
        return child;
    }
    YAML::Node Get(const std::string& key) const {
        std::optional<YAML::Node> child = Find(key);
        if (!child) Fail(key, "missing required key");
        return *child;
    }
    Block Child(const std::string& key) const { return Block(file_, Get(key), Key(key), line_); }

    std::string String(const std::string& key) const { return Scalar(key, Get(key)); }
    std::optional<std::string> OptString(const std::string& key) const {
        const std::optional<YAML::Node> child = Find(key);
        return child ? std::optional<std::string>(Scalar(key, *child)) : std::nullopt;
    }
    double Double(const std::string& key) const { return ToDouble(key, String(key)); }
    std::optional<double> OptDouble(const std::string& key) const {
        const std::optional<std::string> text = OptString(key);
        return text ? std::optional<double>(ToDouble(key, *text)) : std::nullopt;
    }
    bool Has(const std::string& key) const { return Find(key).has_value(); }
    const std::string& file() const { return file_; }
    /// `key: [[a, b, ...], ...]`: a list of lists of `n` finite numbers each; empty when absent.
    std::vector<std::vector<double>> NumberLists(const std::string& key, std::size_t n) const {
        std::vector<std::vector<double>> lists;
        const std::optional<YAML::Node> list = Find(key);
        if (!list) return lists;
        const std::string shape = "must be a list of lists of " + std::to_string(n) + " numbers";
        if (!list->IsSequence()) Fail(key, shape);
        for (std::size_t i = 0; i < list->size(); ++i) {
            const YAML::Node entry = (*list)[i];
            const std::string entry_key = key + "[" + std::to_string(i) + "]";
            if (!entry.IsSequence() || entry.size() != n) Fail(key, shape + " (" + entry_key + ")");
            std::vector<double> values;
            for (std::size_t k = 0; k < n; ++k) {
                if (!entry[k].IsScalar()) Fail(key, shape + " (" + entry_key + ")");
                values.push_back(ToDouble(entry_key, entry[k].Scalar()));
            }
            lists.push_back(std::move(values));
        }
        return lists;
    }

    /// One warning per key not in `known` ("file:line: key: unknown key, ignored"): docs/FORMAT.md
    /// allows extensions, but a misspelt optional key (yaw_dge) must not pass unnoticed.
    void WarnUnknownKeys(std::initializer_list<const char*> known,
                         std::vector<std::string>& warnings) const {
        for (const auto& entry : node_) {
            const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : "?";
            const bool is_known =
                std::any_of(known.begin(), known.end(), [&](const char* k) { return key == k; });
            if (is_known) continue;
            warnings.push_back(file_ + ":" + std::to_string(LineOf(entry.first)) + ": " + Key(key) +
                               ": unknown key, ignored");
        }
    }

private:
    /// yaml-cpp keeps the first of two equal keys; a repeated key is almost surely a mistake.
    void CheckNoDuplicateKeys() const {
        std::vector<std::string> seen;
        for (const auto& entry : node_) {
            if (!entry.first.IsScalar()) continue;
            const std::string& key = entry.first.Scalar();
            if (std::find(seen.begin(), seen.end(), key) != seen.end()) {
                throw InputError(file_, LineOf(entry.first), Key(key), "key given twice");
            }
            seen.push_back(key);
        }
    }
    std::string Scalar(const std::string& key, const YAML::Node& node) const {
        if (!node.IsScalar()) Fail(key, "must be a single value, not a list or mapping");
        return node.Scalar();
    }
    double ToDouble(const std::string& key, const std::string& text) const {
        const std::optional<double> value = internal::ParseDouble(internal::Trim(text));
        const std::string lower = Lower(text);
        const bool special = lower.find("nan") != std::string::npos ||
                             lower.find("inf") != std::string::npos;  // also YAML's .nan, .inf
        if (!value && !special) Fail(key, "'" + text + "' is not a number");
        if (!value || !std::isfinite(*value)) Fail(key, "'" + text + "' is not a finite number");
        return *value;
    }

    std::string file_;
    YAML::Node node_;
    std::string prefix_;
    long line_ = 0;
};

template <typename E>
using Choices = std::vector<std::pair<const char*, E>>;

/// Looks `text` up in `choices`; throws naming the key and the accepted values otherwise.
template <typename E>
E ParseChoice(const Block& block, const std::string& key, const std::string& text,
              const Choices<E>& choices) {
    std::string accepted;
    for (const auto& [name, value] : choices) {
        if (text == name) return value;
        accepted += (accepted.empty() ? "" : " | ") + std::string(name);
    }
    block.Fail(key, "unknown value '" + text + "' (expected " + accepted + ")");
}

template <typename E>
E ParseChoice(const Block& block, const std::string& key, const Choices<E>& choices) {
    return ParseChoice(block, key, block.String(key), choices);
}

/// The scenario.yaml to read: `path` itself (.yaml/.yml) or `path`/scenario.yaml for a folder.
std::string ResolveYamlPath(const std::string& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        const std::string yaml = (fs::path(path) / "scenario.yaml").string();
        if (!fs::exists(yaml, ec)) {
            throw InputError(yaml, 0, "", "scenario folder has no scenario.yaml");
        }
        return yaml;
    }
    if (!fs::exists(path, ec)) throw InputError(path, 0, "", "no such file or folder");
    const std::string ext = Lower(fs::path(path).extension().string());
    if (ext != ".yaml" && ext != ".yml") {
        throw InputError(path, 0, "", "expected a scenario folder or a .yaml/.yml file");
    }
    return path;
}

YAML::Node ParseYamlFile(const std::string& file) {
    const std::string text = ReadTextFile(file, kScenarioLimits);
    if (const std::optional<long> line = SecondYamlDocumentLine(text)) {
        throw InputError(file, *line, "", "a second YAML document ('---'); the file holds one");
    }
    try {
        return YAML::Load(text);
    } catch (const YAML::Exception& e) {
        throw InputError(file, e.mark.line >= 0 ? e.mark.line + 1 : 0, "",
                         "YAML error: " + YamlParserMessage(e.msg));
    }
}

std::string ResolvePath(const fs::path& dir, const std::string& path) {
    const fs::path p(path);
    return (p.is_absolute() ? p : dir / p).lexically_normal().string();
}

TrajectorySource ParseSource(const Block& block, const fs::path& dir,
                             std::vector<std::string>& warnings) {
    TrajectorySource src;
    src.path = ResolvePath(dir, block.String("path"));
    src.format = ParseChoice<TrajectoryFormat>(block, "format",
                                               {{"kitti", TrajectoryFormat::kKitti},
                                                {"tum", TrajectoryFormat::kTum},
                                                {"csv", TrajectoryFormat::kCsv},
                                                {"euroc", TrajectoryFormat::kEuroc}});
    block.WarnUnknownKeys({"path", "format", "rate_hz", "times", "heading"}, warnings);
    if (block.Has("heading")) {
        src.heading_from_motion =
            ParseChoice<bool>(block, "heading", {{"orientation", false}, {"motion", true}});
    }
    src.rate_hz = block.OptDouble("rate_hz");
    const std::optional<std::string> times = block.OptString("times");
    if (times) src.times_path = ResolvePath(dir, *times);
    if (src.rate_hz && !(*src.rate_hz > 0.0)) block.Fail("rate_hz", "must be positive");
    if (src.format != TrajectoryFormat::kKitti) {
        for (const char* key : {"rate_hz", "times"}) {
            if (block.Has(key)) block.Fail(key, "only valid with format: kitti");
        }
    } else if (!src.rate_hz && !src.times_path) {
        block.Fail("", "a kitti trajectory needs rate_hz or times");
    }
    return src;
}

void ParseGeographicAnchor(const Block& block, AnchorSpec& anchor) {
    anchor.lat_deg = block.Double("lat_deg");
    anchor.lon_deg = block.Double("lon_deg");
    anchor.alt_m = block.OptDouble("alt_m").value_or(0.0);
}

void ParseGridAnchor(const Block& block, AnchorSpec& anchor) {
    anchor.crs = block.String("crs");
    anchor.easting_m = block.Double("easting_m");
    anchor.northing_m = block.Double("northing_m");
}

}  // namespace

std::optional<AnchorProblem> FindAnchorProblem(const AnchorSpec& anchor) {
    if (anchor.lat_deg && !(std::abs(*anchor.lat_deg) <= 90.0)) {
        return AnchorProblem{"lat_deg", "must be within [-90, 90]"};
    }
    if (anchor.lon_deg && !(std::abs(*anchor.lon_deg) <= 180.0)) {
        return AnchorProblem{"lon_deg", "must be within [-180, 180]"};
    }
    if (anchor.crs && NormaliseCrsName(*anchor.crs).empty()) {
        return AnchorProblem{
            "crs", "unknown CRS spelling '" + *anchor.crs + "' (expected e.g. EPSG:32632)"};
    }
    if (!(anchor.position_search_m >= 0.0 && anchor.position_search_m <= 1000.0)) {
        return AnchorProblem{"position_search_m", "must be within [0, 1000] m"};
    }
    return std::nullopt;
}

std::string ParseAnchorScale(const std::string& text, AnchorSpec& anchor) {
    if (Lower(text) == "auto") {
        anchor.scale_given = anchor.scale_auto = true;
        return "";
    }
    const std::optional<double> v = internal::ParseDouble(internal::Trim(text));
    if (!v || !(*v > 0.0 && *v < 1e6)) {
        return std::string("must be auto or a number in (0, 1e6): the estimate's positions ") +
               "times it are metres (got '" + text + "')";
    }
    anchor.scale_given = true;
    anchor.scale_auto = false;
    anchor.scale = *v;
    return "";
}

namespace {

AnchorSpec ParseAnchor(const Block& block, ScenarioMode mode, std::vector<std::string>& warnings) {
    block.WarnUnknownKeys({"lat_deg", "lon_deg", "alt_m", "crs", "easting_m", "northing_m",
                           "yaw_deg", "z_m", "position_search_m", "scale"},
                          warnings);
    const bool geographic = block.Has("lat_deg") || block.Has("lon_deg") || block.Has("alt_m");
    const bool grid = block.Has("crs") || block.Has("easting_m") || block.Has("northing_m");
    if (geographic && grid) {
        block.Fail("", "give either lat_deg/lon_deg[/alt_m] or crs/easting_m/northing_m, not both");
    }
    if (!geographic && !grid) {
        block.Fail("", "needs lat_deg and lon_deg, or crs, easting_m and northing_m");
    }
    AnchorSpec anchor;
    if (geographic) {
        ParseGeographicAnchor(block, anchor);
    } else {
        ParseGridAnchor(block, anchor);
    }
    if (!block.Has("yaw_deg")) {
        block.Fail("yaw_deg",
                   "missing required key (the heading of the trajectory frame in "
                   "East-North, degrees counter-clockwise, or `auto` to estimate it "
                   "from the map)");
    }
    if (Lower(block.String("yaw_deg")) != "auto") anchor.yaw_deg = block.Double("yaw_deg");
    if (block.Has("scale")) {
        const std::string problem = ParseAnchorScale(block.String("scale"), anchor);
        if (!problem.empty()) block.Fail("scale", problem);
    }
    anchor.position_search_m = block.OptDouble("position_search_m").value_or(0.0);
    if (const std::optional<AnchorProblem> problem = FindAnchorProblem(anchor)) {
        block.Fail(problem->key, problem->rule);
    }
    if (mode == ScenarioMode::kIndoor3d && !block.Has("z_m")) {
        block.Fail("z_m",
                   "missing required key in indoor3d mode (the height of the trajectory "
                   "frame's origin in the map's height datum: it picks the floor)");
    }
    anchor.z_m = block.OptDouble("z_m").value_or(0.0);
    return anchor;
}

const Choices<ScenarioMode>& ScenarioModes() {
    static const Choices<ScenarioMode> modes = {{"road2d", ScenarioMode::kRoad2d},
                                                {"indoor3d", ScenarioMode::kIndoor3d}};
    return modes;
}

const Choices<LayerRole>& LayerRoles() {
    static const Choices<LayerRole> roles = {{"walkways", LayerRole::kWalkways},
                                             {"floorplan", LayerRole::kFloorplan}};
    return roles;
}

template <typename E>
std::optional<E> FindChoice(const std::string& name, const Choices<E>& choices) {
    for (const auto& [text, value] : choices) {
        if (name == text) return value;
    }
    return std::nullopt;
}

const Choices<MapFormat>& MapFormats() {
    static const Choices<MapFormat> formats = {
        {"osm", MapFormat::kOsm},         {"pbf", MapFormat::kOsm},
        {"geojson", MapFormat::kGeoJson}, {"pcd", MapFormat::kPcd},
        {"ply", MapFormat::kPly},         {"bt", MapFormat::kOctomap},
        {"ot", MapFormat::kOctomap},      {"octomap", MapFormat::kOctomap}};
    return formats;
}

/// `format:` when given, otherwise the layer file's extension (.json counts as GeoJSON).
MapFormat ParseMapFormat(const Block& block, const std::string& path) {
    if (block.Has("format")) return ParseChoice(block, "format", MapFormats());
    if (const std::optional<MapFormat> format = MapFormatFromExtension(path)) return *format;
    block.Fail("format", "missing, and the extension of '" + path + "' names no known map format");
}

// `lifts:` of a point-cloud / OctoMap layer: [[x0, y0, x1, y1], ...], each shaft's footprint in the
// layer's frame.
std::vector<LiftShaft> ParseLifts(const Block& block, MapFormat format) {
    std::vector<LiftShaft> lifts;
    for (const std::vector<double>& v : block.NumberLists("lifts", 4)) {
        lifts.push_back({v[0], v[1], v[2], v[3]});
    }
    const std::string problem = CheckLayerLifts(format, lifts);
    if (!problem.empty()) block.Fail("lifts", problem);
    return lifts;
}

MapLayerSpec ParseLayer(const Block& block, const fs::path& dir,
                        std::vector<std::string>& warnings) {
    block.WarnUnknownKeys({"path", "format", "role", "floor_z_m", "lifts"}, warnings);
    MapLayerSpec layer;
    const std::string path = block.String("path");
    layer.path = ResolvePath(dir, path);
    layer.format = ParseMapFormat(block, path);
    if (block.Has("role")) {
        layer.role = ParseChoice(block, "role", LayerRoles());
    }
    layer.floor_z_m = block.OptDouble("floor_z_m");
    layer.lifts = ParseLifts(block, layer.format);
    return layer;
}

std::vector<MapLayerSpec> ParseMap(const Block& root, const fs::path& dir,
                                   std::vector<std::string>& warnings) {
    const YAML::Node list = root.Get("map");
    if (!list.IsSequence()) root.Fail("map", "must be a list of layers");
    if (list.size() == 0) root.Fail("map", "must list at least one layer");
    std::vector<MapLayerSpec> layers;
    for (std::size_t i = 0; i < list.size(); ++i) {
        const Block layer(root.file(), list[i], "map[" + std::to_string(i) + "]", LineOf(list));
        layers.push_back(ParseLayer(layer, dir, warnings));
    }
    return layers;
}

void ParseRoot(const Block& root, Scenario& s) {
    const fs::path dir(s.dir);
    root.WarnUnknownKeys({"name", "mode", "estimate", "ground_truth", "frame", "anchor", "map"},
                         s.warnings);
    s.name = root.OptString("name").value_or(dir.filename().string());
    s.mode = ParseChoice(root, "mode", ScenarioModes());
    s.estimate = ParseSource(root.Child("estimate"), dir, s.warnings);
    if (root.Has("ground_truth")) {
        s.ground_truth = ParseSource(root.Child("ground_truth"), dir, s.warnings);
    }
    const std::string frame = root.String("frame");
    const std::optional<FrameAxes> axes = ParseFrameAxes(frame);
    if (!axes) root.Fail("frame", "unknown value '" + frame + "' (expected kitti_camera | enu)");
    s.frame = *axes;
    s.anchor = ParseAnchor(root.Child("anchor"), s.mode, s.warnings);
    s.map = ParseMap(root, dir, s.warnings);
}

}  // namespace

Scenario LoadScenario(const std::string& path) {
    Scenario s;
    s.yaml_path = ResolveYamlPath(path);
    s.dir = fs::absolute(s.yaml_path).lexically_normal().parent_path().string();
    const YAML::Node doc = ParseYamlFile(s.yaml_path);
    try {
        ParseRoot(Block(s.yaml_path, doc, "", 1), s);
    } catch (const YAML::Exception& e) {  // safety net: yaml-cpp access errors carry a position
        throw InputError(s.yaml_path, e.mark.line >= 0 ? e.mark.line + 1 : 0, "", e.msg);
    }
    return s;
}

std::optional<ScenarioMode> ParseScenarioMode(const std::string& name) {
    return FindChoice(name, ScenarioModes());
}

std::optional<MapFormat> ParseMapFormat(const std::string& name) {
    return FindChoice(name, MapFormats());
}

std::optional<LayerRole> ParseLayerRole(const std::string& name) {
    return FindChoice(name, LayerRoles());
}

std::optional<MapFormat> MapFormatFromExtension(const std::string& path) {
    std::string ext = Lower(fs::path(path).extension().string());
    if (!ext.empty()) ext.erase(0, 1);
    if (ext == "json") return MapFormat::kGeoJson;
    return FindChoice(ext, MapFormats());
}

std::string ToString(ScenarioMode mode) {
    return mode == ScenarioMode::kRoad2d ? "road2d" : "indoor3d";
}

std::string ToString(TrajectoryFormat format) {
    switch (format) {
        case TrajectoryFormat::kKitti:
            return "kitti";
        case TrajectoryFormat::kTum:
            return "tum";
        case TrajectoryFormat::kCsv:
            return "csv";
        case TrajectoryFormat::kEuroc:
            return "euroc";
    }
    return "unknown";
}

std::string CheckLayerLifts(MapFormat format, const std::vector<LiftShaft>& lifts) {
    if (lifts.empty()) return "";
    if (format != MapFormat::kPcd && format != MapFormat::kPly && format != MapFormat::kOctomap) {
        return "only valid on a point-cloud or OctoMap layer (a floor plan marks its lifts with "
               "Type: Lift)";
    }
    for (const LiftShaft& l : lifts) {
        const bool finite = std::isfinite(l.x0) && std::isfinite(l.y0) && std::isfinite(l.x1) &&
                            std::isfinite(l.y1);
        if (!finite || !(l.x1 > l.x0 && l.y1 > l.y0)) {
            return "a shaft [x0, y0, x1, y1] needs x1 > x0 and y1 > y0";
        }
    }
    return "";
}

std::optional<TrajectoryFormat> ParseTrajectoryFormat(const std::string& name) {
    for (const TrajectoryFormat f : {TrajectoryFormat::kKitti, TrajectoryFormat::kTum,
                                     TrajectoryFormat::kCsv, TrajectoryFormat::kEuroc}) {
        if (ToString(f) == name) return f;
    }
    return std::nullopt;
}

std::string ToString(MapFormat format) {
    switch (format) {
        case MapFormat::kOsm:
            return "osm";
        case MapFormat::kGeoJson:
            return "geojson";
        case MapFormat::kPcd:
            return "pcd";
        case MapFormat::kPly:
            return "ply";
        case MapFormat::kOctomap:
            return "octomap";
    }
    return "unknown";
}

std::vector<InputFile> InputFiles(const Scenario& scenario) {
    std::vector<InputFile> files;
    if (!scenario.yaml_path.empty() && scenario.yaml_path.front() != '<') {
        files.push_back({"the scenario file", scenario.yaml_path});
    }
    const auto add_source = [&files](const std::string& what, const TrajectorySource& src) {
        files.push_back({what, src.path});
        if (src.times_path) files.push_back({what + "'s times", *src.times_path});
    };
    add_source("the estimate", scenario.estimate);
    if (scenario.ground_truth) add_source("the ground truth", *scenario.ground_truth);
    for (std::size_t i = 0; i < scenario.map.size(); ++i) {
        files.push_back({"map layer " + std::to_string(i + 1), scenario.map[i].path});
    }
    return files;
}

}  // namespace driftcorr::io
