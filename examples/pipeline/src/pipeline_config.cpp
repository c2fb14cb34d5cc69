// params.yaml -> PipelineConfig. Every key maps to one field; unknown keys are errors.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "driftcorr/core/errors.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::pipeline {
namespace {

using Setter = std::function<void(const YAML::Node&, const std::string& key)>;

struct Context {
    std::string file;
};

long Line(const YAML::Node& n) { return n.Mark().line >= 0 ? n.Mark().line + 1 : 0; }

double Number(const Context& c, const YAML::Node& n, const std::string& key) {
    try {
        const double v = n.as<double>();
        if (!std::isfinite(v)) throw InputError(c.file, Line(n), key, "must be a finite number");
        return v;
    } catch (const YAML::Exception&) {
        throw InputError(c.file, Line(n), key, "must be a number");
    }
}

/// The text of a mapping key; a list or mapping used as a key is an error naming its line.
std::string KeyText(const Context& c, const YAML::Node& key, const std::string& where) {
    if (!key.IsScalar()) {
        throw InputError(c.file, Line(key), where, "keys must be plain names, not lists or maps");
    }
    return key.Scalar();
}

/// Throws when `key` was already seen in the same mapping (yaml-cpp would keep both entries and
/// the last one would silently win).
void CheckOnce(const Context& c, std::set<std::string>& seen, const YAML::Node& key_node,
               const std::string& key) {
    if (!seen.insert(key).second) throw InputError(c.file, Line(key_node), key, "key given twice");
}

bool Bool(const Context& c, const YAML::Node& n, const std::string& key) {
    try {
        return n.as<bool>();
    } catch (const YAML::Exception&) {
        throw InputError(c.file, Line(n), key, "must be true or false");
    }
}

// Registers keys that each set one double field (finite, else InputError naming file, line, key).
struct NumberKeys {
    std::map<std::string, Setter>& setters;
    const Context& context;
    void operator()(const char* name, double* field) const {
        const Context& c = context;
        setters[name] = [&c, field](const YAML::Node& n, const std::string& k) {
            *field = Number(c, n, k);
        };
    }
};

std::map<std::string, Setter> ModelSetters(const Context& c, ModelConfig& m) {
    std::map<std::string, Setter> s;
    const NumberKeys num{s, c};
    num("step_sigma_m", &m.step_sigma_m);
    num("step_sigma_rel", &m.step_sigma_rel);
    num("step_robust_k", &m.step_robust_k);
    num("accel_sigma_mps2", &m.accel_sigma_mps2);
    num("speed_weight", &m.speed_weight);
    num("max_speed_mps", &m.max_speed_mps);
    num("outlier_accel_mps2", &m.outlier_accel_mps2);
    num("outlier_sigma_rel", &m.outlier_sigma_rel);
    num("lateral_sigma_m", &m.lateral_sigma_m);
    num("lateral_sigma_rel", &m.lateral_sigma_rel);
    num("heading_rw_rad_per_sqrt_s", &m.heading_rw_rad_per_sqrt_s);
    num("heading_sigma_rel", &m.heading_sigma_rel);
    num("heading_sigma_min_rad", &m.heading_sigma_min_rad);
    num("preservation_sigma_rad", &m.preservation_sigma_rad);
    num("height_sigma_m", &m.height_sigma_m);
    num("height_sigma_rel", &m.height_sigma_rel);
    num("map_sigma_m", &m.map_sigma_m);
    num("map_giveup_m", &m.map_giveup_m);
    num("scale_segment_m", &m.scale_segment_m);
    num("scale_prior_sigma", &m.scale_prior_sigma);
    num("scale_rw_sigma", &m.scale_rw_sigma);
    num("scale_rw_robust_k", &m.scale_rw_robust_k);
    num("scale_range_min", &m.scale_range_min);
    num("scale_range_max", &m.scale_range_max);
    num("scale_range_sigma", &m.scale_range_sigma);
    num("heading_bias_segment_s", &m.heading_bias_segment_s);
    num("heading_bias_prior_rad_s", &m.heading_bias_prior_rad_s);
    num("heading_bias_rw_rad_s", &m.heading_bias_rw_rad_s);
    num("step_weight", &m.step_weight);
    num("heading_weight", &m.heading_weight);
    num("preservation_weight", &m.preservation_weight);
    num("map_weight", &m.map_weight);
    num("height_weight", &m.height_weight);
    num("corridor_gate_m", &m.corridor_gate_m);
    num("corridor_slack_m", &m.corridor_slack_m);
    s["hard_corridor"] = [&c, &m](const YAML::Node& n, const std::string& k) { m.hard_corridor = Bool(c, n, k); };
    return s;
}

// A whole-number key: negative, fractional or too large values are rejected.
template <typename Count>
void AddCountKey(std::map<std::string, Setter>& s, const Context& c, const char* name,
                 Count* field) {
    s[name] = [&c, field](const YAML::Node& n, const std::string& k) {
        // 2^digits is the first whole number Count cannot hold; casting a double at or above
        // it is undefined behaviour, so it is rejected before the cast (found by fuzzing).
        const double limit = std::ldexp(1.0, std::numeric_limits<Count>::digits);
        const double v = Number(c, n, k);
        if (v < 0 || v != std::floor(v) || !(v < limit)) {
            throw InputError(c.file, Line(n), k,
                             "must be a whole number in [0, " +
                                 std::to_string(std::numeric_limits<Count>::max()) + "]");
        }
        *field = static_cast<Count>(v);
    };
}

std::map<std::string, Setter> CorrectorSetters(const Context& c, CorrectorConfig& cc) {
    std::map<std::string, Setter> s;
    const NumberKeys num{s, c};
    auto count = [&](const char* name, auto* field) { AddCountKey(s, c, name, field); };
    num("chunk_m", &cc.chunk_m);
    num("window_m", &cc.window_m);
    num("stationary_m", &cc.stationary_m);
    count("max_chunk_poses", &cc.max_chunk_poses);
    count("max_window_poses", &cc.max_window_poses);
    count("window_max_iterations", &cc.window_ipopt.max_iterations);
    count("refine_max_iterations", &cc.refine_ipopt.max_iterations);
    num("refine_max_cpu_time_s", &cc.refine_ipopt.max_cpu_time_s);
    num("window_max_cpu_time_s", &cc.window_ipopt.max_cpu_time_s);
    s["refine"] = [&c, &cc](const YAML::Node& n, const std::string& k) { cc.refine = Bool(c, n, k); };
    return s;
}

std::map<std::string, Setter> OnlineSetters(const Context& c, OnlineConfig& o) {
    std::map<std::string, Setter> s;
    const NumberKeys num{s, c};
    num("update_fraction", &o.update_fraction);
    num("gap_warn_s", &o.gap_warn_s);
    AddCountKey(s, c, "max_lag_epochs", &o.max_lag_epochs);
    s["project_output"] = [&c, &o](const YAML::Node& n, const std::string& k) {
        o.project_output = Bool(c, n, k);
    };
    s["boundary_prior"] = [&c, &o](const YAML::Node& n, const std::string& k) {
        o.boundary_prior = Bool(c, n, k);
    };
    s["hold_live_input"] = [&c, &o](const YAML::Node& n, const std::string& k) {
        o.hold_live_input = Bool(c, n, k);
    };
    return s;
}

std::map<std::string, Setter> FieldSetters(const Context& c, RoadFieldConfig& f) {
    std::map<std::string, Setter> s;
    const NumberKeys num{s, c};
    num("resolution_m", &f.resolution_m);
    num("margin_m", &f.margin_m);
    num("truncation_m", &f.truncation_m);
    num("exact_band_m", &f.exact_band_m);
    num("max_memory_mb", &f.max_memory_mb);
    num("tile_m", &f.tile_m);
    return s;
}

// The keys both voxel fields have (IndoorFieldConfig, SurfaceFieldConfig).
template <typename VoxelFieldConfig>
void VoxelFieldKeys(const NumberKeys& num, VoxelFieldConfig& f) {
    num("resolution_m", &f.resolution_m);
    num("resolution_z_m", &f.resolution_z_m);
    num("device_height_m", &f.device_height_m);
    num("vertical_tolerance_m", &f.vertical_tolerance_m);
    num("margin_m", &f.margin_m);
    num("vertical_margin_m", &f.vertical_margin_m);
    num("truncation_m", &f.truncation_m);
    num("max_memory_mb", &f.max_memory_mb);
}

std::map<std::string, Setter> IndoorFieldSetters(const Context& c, IndoorFieldConfig& f) {
    std::map<std::string, Setter> s;
    const NumberKeys num{s, c};
    VoxelFieldKeys(num, f);
    num("walkway_half_width_m", &f.walkway_half_width_m);
    num("exact_band_m", &f.exact_band_m);
    return s;
}

std::map<std::string, Setter> SurfaceFieldSetters(const Context& c, SurfaceFieldConfig& f) {
    std::map<std::string, Setter> s;
    const NumberKeys num{s, c};
    VoxelFieldKeys(num, f);
    num("wall_clearance_m", &f.wall_clearance_m);
    return s;
}

std::map<std::string, Setter> PaperSetters(const Context& c, PaperSolverConfig& p) {
    std::map<std::string, Setter> s;
    const NumberKeys num{s, c};
    num("learning_rate", &p.learning_rate);
    num("turn_weight", &p.turn_weight);
    num("step_weight", &p.step_weight);
    num("map_weight", &p.map_weight);
    num("preservation_weight", &p.preservation_weight);
    num("turn_sigma_rad", &p.turn_sigma_rad);
    num("step_sigma_m", &p.step_sigma_m);
    num("map_sigma_m", &p.map_sigma_m);
    num("preservation_sigma_rad", &p.preservation_sigma_rad);
    num("map_truncation_m", &p.map_truncation_m);
    num("min_step_m", &p.min_step_m);
    num("stationary_m", &p.stationary_m);
    s["iterations_per_epoch"] = [&c, &p](const YAML::Node& n, const std::string& k) {
        const double v = Number(c, n, k);
        if (v != std::floor(v) || v < 1 || v > 1e6) {
            throw InputError(c.file, Line(n), k, "must be an integer in [1, 1000000]");
        }
        p.iterations_per_epoch = static_cast<int>(v);
    };
    return s;
}

std::map<std::string, Setter> RoadSetters(const Context& c, RoadClassConfig& r) {
    std::map<std::string, Setter> s;
    s["profile"] = [&c, &r](const YAML::Node& n, const std::string& k) {
        if (!n.IsScalar()) throw InputError(c.file, Line(n), k, "must be vehicle, pedestrian or all");
        r.profile = n.Scalar();
    };
    s["default_half_width_m"] = [&c, &r](const YAML::Node& n, const std::string& k) {
        r.default_half_width_m = Number(c, n, k);
    };
    s["half_width_m"] = [&c, &r](const YAML::Node& n, const std::string& k) {
        if (!n.IsMap()) throw InputError(c.file, Line(n), k, "must be a map of highway class to metres");
        std::set<std::string> seen;
        for (const auto& kv : n) {
            const std::string cls = KeyText(c, kv.first, k);
            CheckOnce(c, seen, kv.first, k + "." + cls);
            r.half_width_overrides_m[cls] = Number(c, kv.second, k + "." + cls);
        }
    };
    return s;
}

void ApplySection(const Context& c, const YAML::Node& key_node, const YAML::Node& node,
                  const std::string& section, const std::map<std::string, Setter>& setters) {
    if (!node.IsMap()) throw InputError(c.file, Line(key_node), section, "must be a map");
    std::set<std::string> seen;
    for (const auto& kv : node) {
        const std::string key = KeyText(c, kv.first, section);
        CheckOnce(c, seen, kv.first, section + "." + key);
        auto it = setters.find(key);
        if (it == setters.end()) {
            throw InputError(c.file, Line(kv.first), section + "." + key, "unknown parameter");
        }
        it->second(kv.second, section + "." + key);
    }
}

/// RoadClassConfig::Validate names its fields road_profile / road_half_width_m.<class>; in the
/// parameter file they are roads.profile / roads.half_width_m.<class>.
std::string RoadsKeyInFile(std::string m) {
    for (const auto& [field, key] : {std::pair<std::string, std::string>{"road_profile", "profile"},
                                     {"road_half_width_m", "half_width_m"}}) {
        if (m.compare(0, field.size(), field) == 0) return key + m.substr(field.size());
    }
    return m;
}

/// Line of the dotted key path a Validate() message starts with ("model.step_sigma_m: ..."),
/// 0 when the key is not in the file (a default value failed, or the message names no key).
long LineOfMessageKey(const YAML::Node& root, const std::string& message) {
    const std::size_t colon = message.find(": ");
    if (colon == std::string::npos) return 0;
    std::istringstream path(message.substr(0, colon));
    YAML::Node node = root;
    for (std::string part; std::getline(path, part, '.');) {
        if (!node.IsMap()) return 0;
        bool found = false;
        for (const auto& kv : node) {
            if (kv.first.IsScalar() && kv.first.Scalar() == part) {
                node = kv.second;
                found = true;
                break;
            }
        }
        if (!found) return 0;
    }
    return Line(node);
}

PipelineConfig ParseConfig(const Context& c, const YAML::Node& root) {
    PipelineConfig cfg;
    if (root.IsNull()) return cfg;
    if (!root.IsMap()) throw InputError(c.file, Line(root), "", "must be a map of sections");
    std::set<std::string> seen;
    for (const auto& kv : root) {
        const std::string section = KeyText(c, kv.first, "");
        CheckOnce(c, seen, kv.first, section);
        const YAML::Node& body = kv.second;
        if (section == "model") {
            ApplySection(c, kv.first, body, section, ModelSetters(c, cfg.corrector.model));
        } else if (section == "corrector") {
            ApplySection(c, kv.first, body, section, CorrectorSetters(c, cfg.corrector));
        } else if (section == "indoor_model") {
            ApplySection(c, kv.first, body, section, ModelSetters(c, cfg.indoor_corrector.model));
        } else if (section == "indoor_corrector") {
            ApplySection(c, kv.first, body, section, CorrectorSetters(c, cfg.indoor_corrector));
        } else if (section == "indoor_field") {
            ApplySection(c, kv.first, body, section, IndoorFieldSetters(c, cfg.indoor_field));
        } else if (section == "surface_field") {
            ApplySection(c, kv.first, body, section, SurfaceFieldSetters(c, cfg.surface_field));
        } else if (section == "paper") {
            ApplySection(c, kv.first, body, section, PaperSetters(c, cfg.paper));
        } else if (section == "roads") {
            ApplySection(c, kv.first, body, section, RoadSetters(c, cfg.roads));
        } else if (section == "field") {
            ApplySection(c, kv.first, body, section, FieldSetters(c, cfg.field));
        } else if (section == "online") {
            ApplySection(c, kv.first, body, section, OnlineSetters(c, cfg.online));
        } else {
            throw InputError(c.file, Line(kv.first), section,
                             "unknown section (model, corrector, paper, roads, field, indoor_model, "
                             "indoor_corrector, indoor_field, surface_field, online)");
        }
    }
    if (std::string m = cfg.Validate(); !m.empty()) {
        throw InputError(c.file, LineOfMessageKey(root, m), "", m);
    }
    return cfg;
}

}  // namespace

std::string PipelineConfig::Validate() const {
    if (std::string m = corrector.Validate(); !m.empty()) return m;
    if (std::string m = paper.Validate(); !m.empty()) return "paper." + m;
    if (std::string m = roads.Validate(); !m.empty()) return "roads." + RoadsKeyInFile(m);
    if (std::string m = field.Validate(); !m.empty()) return m;
    if (std::string m = indoor_corrector.Validate(); !m.empty()) return "indoor_" + m;
    if (std::string m = indoor_field.Validate(); !m.empty()) return "indoor_field." + m;
    if (std::string m = surface_field.Validate(); !m.empty()) return "surface_field." + m;
    if (std::string m = online.Validate(); !m.empty()) return m;  // "online.<key>: ..."
    if (std::string m = anchor_fit.Validate(); !m.empty()) return m;  // "anchor_fit.<key>: ..."
    if (std::string m = verdict.Validate(); !m.empty()) return m;  // "verdict.<key>: ..."
    return "";
}

PipelineConfig LoadPipelineConfig(const std::string& path) {
    Context c{path};
    YAML::Node root;
    try {
        root = YAML::LoadFile(path);
    } catch (const YAML::BadFile&) {
        throw InputError(path, 0, "", "cannot open the parameter file");
    } catch (const YAML::ParserException& e) {
        throw InputError(path, e.mark.line + 1, "", "YAML syntax error: " + e.msg);
    }
    try {
        return ParseConfig(c, root);
    } catch (const YAML::Exception& e) {  // safety net: yaml-cpp access errors carry a position
        throw InputError(path, e.mark.line >= 0 ? e.mark.line + 1 : 0, "", e.msg);
    }
}

}  // namespace driftcorr::pipeline
