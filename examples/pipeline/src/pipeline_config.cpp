// params.yaml -> PipelineConfig, made from the parameter tables (core/params.h): a section is one
// config struct, its keys are the rows of that struct's table. Unknown keys are errors; every
// error names the file, the line and the key as written.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "driftcorr/core/errors.h"
#include "driftcorr/io/text_file.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::pipeline {
namespace {

/// The file being read and the line of every key read so far ("model.step_sigma_m"; a section
/// under its own name), for the messages of rules between two keys.
struct Reader {
    std::string file;
    std::map<std::string, long> lines;

    [[noreturn]] void Fail(const YAML::Node& at, const std::string& key,
                           const std::string& message) const {
        throw InputError(file, Line(at), key, message);
    }
    static long Line(const YAML::Node& n) { return n.Mark().line >= 0 ? n.Mark().line + 1 : 0; }
};

/// What a node is, for "(got ...)": the scalar quoted, or "a list" / "a map" / "nothing".
std::string Shown(const YAML::Node& n) {
    if (n.IsScalar()) return "'" + n.Scalar() + "'";
    if (n.IsSequence()) return "a list";
    if (n.IsMap()) return "a map";
    return "nothing";
}

/// The text of a mapping key; a list or mapping used as a key is an error naming its line.
std::string KeyText(const Reader& r, const YAML::Node& key, const std::string& where) {
    if (!key.IsScalar()) r.Fail(key, where, "keys must be plain names, not lists or maps");
    return key.Scalar();
}

/// Throws when `key` was already seen in the same mapping (yaml-cpp would keep both entries and
/// the last one would silently win).
void CheckOnce(const Reader& r, std::set<std::string>& seen, const YAML::Node& key_node,
               const std::string& key) {
    if (!seen.insert(key).second) r.Fail(key_node, key, "key given twice");
}

double Number(const Reader& r, const YAML::Node& n, const std::string& key) {
    if (n.IsScalar()) {
        try {
            return n.as<double>();
        } catch (const YAML::Exception&) {
        }
    }
    r.Fail(n, key, "must be a number (got " + Shown(n) + ")");
}

/// A number for row `p`, in its range (NumberProblem also rejects non-finite values).
template <class Config>
double CheckedNumber(const Reader& r, const Param<Config>& p, const YAML::Node& n,
                     const std::string& key) {
    const double v = Number(r, n, key);
    if (auto problem = NumberProblem(p, v)) r.Fail(n, key, *problem);
    return v;
}

template <class Config>
void ReadValue(Reader& r, const Param<Config>& p, const YAML::Node& n, const std::string& key,
               Config& config) {
    switch (p.kind()) {
        case ParamKind::kReal:
            p.template Ref<double>(config) = CheckedNumber(r, p, n, key);
            break;
        case ParamKind::kSize:
            p.template Ref<std::size_t>(config) = std::size_t(CheckedNumber(r, p, n, key));
            break;
        case ParamKind::kInt:
            p.template Ref<int>(config) = int(CheckedNumber(r, p, n, key));
            break;
        case ParamKind::kFlag:
            try {
                if (n.IsScalar()) {
                    p.template Ref<bool>(config) = n.as<bool>();
                    break;
                }
            } catch (const YAML::Exception&) {
            }
            r.Fail(n, key, RuleText(p) + " (got " + Shown(n) + ")");
        case ParamKind::kChoice:
            if (!n.IsScalar() || !IsChoice(p, n.Scalar())) {
                r.Fail(n, key, RuleText(p) + " (got " + Shown(n) + ")");
            }
            p.template Ref<std::string>(config) = n.Scalar();
            break;
        case ParamKind::kRealByName: {
            if (!n.IsMap())
                r.Fail(n, key, "must be a map of name to number (got " + Shown(n) + ")");
            std::set<std::string> seen;
            for (const auto& kv : n) {
                const std::string entry = key + "." + KeyText(r, kv.first, key);
                CheckOnce(r, seen, kv.first, entry);
                r.lines[entry] = Reader::Line(kv.first);
                p.template Ref<std::map<std::string, double>>(config)[kv.first.Scalar()] =
                    CheckedNumber(r, p, kv.second, entry);
            }
            break;
        }
    }
}

template <class Config>
void ReadSection(Reader& r, const YAML::Node& key_node, const YAML::Node& body,
                 const std::string& section, const ParamTable<Config>& table, Config& config) {
    if (!body.IsMap()) r.Fail(key_node, section, "must be a map (got " + Shown(body) + ")");
    r.lines[section] = Reader::Line(key_node);
    std::set<std::string> seen;
    for (const auto& kv : body) {
        const std::string name = KeyText(r, kv.first, section);
        const std::string key = section + "." + name;
        CheckOnce(r, seen, kv.first, key);
        const Param<Config>* p = table.Find(name);
        if (!p) r.Fail(kv.first, key, "unknown parameter");
        r.lines[key] = Reader::Line(kv.first);
        ReadValue(r, *p, kv.second, key, config);
    }
}

/// A broken rule between two keys (or of a value the file did not set), at the line of the
/// key it names when the file has it, else of the other key, else of the section.
[[noreturn]] void FailProblem(const Reader& r, const std::string& section,
                              const ParamProblem& problem) {
    const std::string key = section + "." + problem.key;
    const std::string related = section + "." + problem.related_key;
    if (auto it = r.lines.find(key); it != r.lines.end()) {
        throw InputError(r.file, it->second, key, problem.message);
    }
    if (auto it = r.lines.find(related); !problem.related_key.empty() && it != r.lines.end()) {
        throw InputError(r.file, it->second, related, key + " " + problem.message);
    }
    const auto it = r.lines.find(section);
    throw InputError(r.file, it == r.lines.end() ? 0 : it->second, key, problem.message);
}

std::string SectionNames() {
    std::string names;
    PipelineConfig defaults;
    ForEachParamSection(defaults, [&](const char* section, const auto&, const auto&, const char*) {
        names += (names.empty() ? "" : ", ") + std::string(section);
    });
    return names;
}

PipelineConfig ParseConfig(Reader& r, const YAML::Node& root) {
    PipelineConfig cfg;
    if (root.IsNull()) return cfg;
    if (!root.IsMap()) r.Fail(root, "", "must be a map of sections");
    std::set<std::string> seen;
    for (const auto& kv : root) {
        const std::string section = KeyText(r, kv.first, "");
        CheckOnce(r, seen, kv.first, section);
        bool known = false;
        ForEachParamSection(cfg, [&](const char* name, const auto& table, auto& part, const char*) {
            if (section != name) return;
            ReadSection(r, kv.first, kv.second, section, table, part);
            known = true;
        });
        if (!known) r.Fail(kv.first, section, "unknown section (" + SectionNames() + ")");
    }
    ForEachParamSection(cfg, [&](const char* section, const auto&, const auto& part, const char*) {
        if (auto problem = part.FindProblem()) FailProblem(r, section, *problem);
    });
    if (std::string m = cfg.Validate(); !m.empty()) throw InputError(r.file, 0, "", m);
    return cfg;
}

/// "  key: value", padded to the comment column, then "# rule; doc".
template <class Config>
std::string ReferenceLine(const Param<Config>& p, const Config& part) {
    std::string line = std::string("  ") + p.key + ": " + FormatParamValue(p, part);
    line.resize(std::max<std::size_t>(line.size() + 1, 34), ' ');
    std::string rule = RuleText(p);
    if (p.kind() == ParamKind::kRealByName) rule = "{name: value}, each " + rule;
    return line + "# " + rule.substr(rule.rfind("must be ", 0) == 0 ? 8 : 0) + "; " + p.doc;
}

/// The sections of `config` whose name `keep` accepts, each under a line with its name and
/// what it sets, then a line per key.
template <class Keep>
std::string Reference(const PipelineConfig& config, Keep keep) {
    std::string out;
    ForEachParamSection(
        config, [&](const char* section, const auto& table, const auto& part, const char* about) {
            if (!keep(std::string(section))) return;
            out += std::string(section) + ":  # " + about + "\n";
            for (const auto& p : table) out += ReferenceLine(p, part) + "\n";
        });
    return out;
}

}  // namespace

std::string PipelineConfig::Validate() const {
    std::string m;
    ForEachParamSection(*this,
                        [&](const char* section, const auto&, const auto& part, const char*) {
                            if (m.empty()) m = ToMessage(section, part.FindProblem());
                        });
    // Parts that are no params.yaml section: their defaults, or what the caller set.
    for (const std::string& rest :
         {corrector.covariance.Validate(), indoor_corrector.covariance.Validate(),
          online.corrector.Validate(), anchor_fit.Validate(), verdict.Validate()}) {
        if (m.empty()) m = rest;
    }
    return m;
}

std::string ParameterReference(const PipelineConfig& config) {
    return Reference(config, [](const std::string&) { return true; });
}

std::string CorrectorReference(const CorrectorConfig& corrector) {
    PipelineConfig config;
    config.corrector = corrector;
    return Reference(config, [](const std::string& section) {
        return section == kModelParams.section || section == kCorrectorParams.section;
    });
}

PipelineConfig LoadPipelineConfig(const std::string& path) {
    Reader r{path, {}};
    std::error_code ec;
    if (!std::filesystem::is_directory(path, ec) && !std::ifstream(path)) {
        throw InputError(path, 0, "", "cannot open the parameter file");
    }
    const std::string text = io::ReadTextFile(path, io::kParameterLimits);
    if (const std::optional<long> line = io::SecondYamlDocumentLine(text)) {
        throw InputError(path, *line, "", "a second YAML document ('---'); the file holds one");
    }
    YAML::Node root;
    try {
        root = YAML::Load(text);
    } catch (const YAML::ParserException& e) {
        throw InputError(path, e.mark.line + 1, "",
                         "YAML syntax error: " + io::YamlParserMessage(e.msg));
    }
    try {
        return ParseConfig(r, root);
    } catch (const YAML::Exception& e) {  // safety net: yaml-cpp access errors carry a position
        throw InputError(path, e.mark.line >= 0 ? e.mark.line + 1 : 0, "", e.msg);
    }
}

}  // namespace driftcorr::pipeline
