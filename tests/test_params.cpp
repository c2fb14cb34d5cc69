// The parameter tables (core/params.h) against the params.yaml reader and docs/parameters.md: every
// key of every section, mistyped, out of range or of the wrong type, gives one message naming the
// file, the line and the key as written; docs/parameters.md lists exactly what the tables say.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr {
namespace {

namespace fs = std::filesystem;

fs::path TempFile(const std::string& name) {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "test_params";
    fs::create_directories(dir);
    return dir / name;
}

void WriteFile(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

/// One bad params.yaml: what the file says and the key the message must name.
struct BadCase {
    std::string what;  ///< "model.step_sigma_m out of range", for the failure message
    std::string yaml;  ///< the whole file; the bad key is on line 3
    std::string key;   ///< the key as written, dotted
};

/// A value of row `p` below (or above) its range, or not whole, as YAML text; empty when every
/// value of the row's kind is allowed.
template <class Config>
std::vector<std::string> OutOfRange(const Param<Config>& p) {
    std::vector<std::string> values;
    const ParamRange& r = p.range;
    const bool whole = p.kind() == ParamKind::kSize || p.kind() == ParamKind::kInt;
    if (std::isfinite(r.min)) values.push_back(FormatParamNumber(r.min_open ? r.min : r.min - 1));
    if (std::isfinite(r.max)) values.push_back(FormatParamNumber(r.max_open ? r.max : r.max + 1));
    if (!std::isfinite(r.min) && !std::isfinite(r.max)) values.push_back(".inf");
    if (whole) {
        values.push_back(FormatParamNumber(WholeRange(p).min + 0.5));
        values.push_back("-1");
        values.push_back("1e30");  // does not fit the member
    }
    return values;
}

/// The bad files for one row of section `section`.
template <class Config>
std::vector<BadCase> CasesFor(const std::string& section, const Param<Config>& p) {
    const std::string head = "# line 1\n" + section + ":\n  ";
    const std::string key = section + "." + p.key;
    std::vector<BadCase> cases;
    cases.push_back({key + " mistyped", head + p.key + "x: 1\n", key + "x"});
    cases.push_back({key + " a list", head + p.key + ": [1, 2]\n", key});
    if (p.kind() != ParamKind::kRealByName) {
        cases.push_back({key + " a map", head + p.key + ": {a: 1}\n", key});
    }
    switch (p.kind()) {
        case ParamKind::kReal:
        case ParamKind::kSize:
        case ParamKind::kInt:
            cases.push_back({key + " a word", head + p.key + ": abc\n", key});
            for (const std::string& v : OutOfRange(p)) {
                cases.push_back({key + " = " + v, head + p.key + ": " + v + "\n", key});
            }
            break;
        case ParamKind::kFlag:
            cases.push_back({key + " a word", head + p.key + ": maybe\n", key});
            cases.push_back({key + " a number", head + p.key + ": 2\n", key});
            break;
        case ParamKind::kChoice:
            cases.push_back({key + " not a choice", head + p.key + ": tank\n", key});
            break;
        case ParamKind::kRealByName:
            cases.push_back({key + " a word", head + p.key + ": abc\n", key});
            cases.push_back({key + ".x a word", head + p.key + ": {x: abc}\n", key + ".x"});
            cases.push_back({key + ".x a map", head + p.key + ": {x: {b: 1}}\n", key + ".x"});
            for (const std::string& v : OutOfRange(p)) {
                cases.push_back(
                    {key + ".x = " + v, head + p.key + ": {x: " + v + "}\n", key + ".x"});
            }
            break;
    }
    return cases;
}

std::vector<BadCase> EveryBadCase() {
    std::vector<BadCase> cases;
    const pipeline::PipelineConfig defaults;
    pipeline::ForEachParamSection(
        defaults, [&](const char* section, const auto& table, const auto&, const char*) {
            for (const auto& p : table) {
                for (BadCase& c : CasesFor(section, p)) cases.push_back(std::move(c));
            }
        });
    return cases;
}

TEST(ParamsYaml, EveryBadKeyOfEveryTableNamesFileLineAndKey) {
    const fs::path path = TempFile("params.yaml");
    const std::vector<BadCase> cases = EveryBadCase();
    std::size_t rows = 0;
    pipeline::ForEachParamSection(
        pipeline::PipelineConfig{},
        [&](const char*, const auto& table, const auto&, const char*) { rows += table.count; });
    EXPECT_GE(cases.size(), 4 * rows);  // every row: mistyped, a list, a map and one more
    for (const BadCase& c : cases) {
        WriteFile(path, c.yaml);
        try {
            pipeline::LoadPipelineConfig(path.string());
            ADD_FAILURE() << c.what << ": accepted\n" << c.yaml;
        } catch (const InputError& e) {
            const std::string expected = path.string() + ":3: " + c.key + ": ";
            EXPECT_EQ(e.file(), path.string()) << c.what;
            EXPECT_EQ(e.line(), 3) << c.what << ": " << e.what();
            EXPECT_EQ(e.key(), c.key) << c.what << ": " << e.what();
            EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << c.what << ": " << e.what();
            EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
        }
    }
}

TEST(ParamsYaml, ValuesOutOfRangeSayTheRuleAndTheValue) {
    const fs::path path = TempFile("range.yaml");
    WriteFile(path, "indoor_field: {resolution_m: -1}\n");
    try {
        pipeline::LoadPipelineConfig(path.string());
        ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()),
                  path.string() + ":1: indoor_field.resolution_m: must be > 0 (got -1)");
    }
}

/// A rule between two keys is reported at the line of the key the file sets, naming it.
TEST(ParamsYaml, RulesBetweenKeysNameTheKeyTheFileSets) {
    struct Case {
        std::string yaml;
        long line;
        std::string key;
    };
    const std::vector<Case> cases = {
        {"corrector:\n  window_m: 50\n", 2, "corrector.window_m"},
        {"corrector:\n  chunk_m: 500\n", 2, "corrector.chunk_m"},
        {"indoor_corrector:\n\n  max_chunk_poses: 2000\n", 3, "indoor_corrector.max_chunk_poses"},
        {"model: {scale_range_min: 2}\n", 1, "model.scale_range_min"},
        {"indoor_model:\n  scale_range_max: 0.5\n", 2, "indoor_model.scale_range_max"},
        {"surface_field:\n  resolution_z_m: 2\n", 2, "surface_field.resolution_z_m"},
        {"indoor_field:\n  vertical_tolerance_m: 0.1\n", 2, "indoor_field.vertical_tolerance_m"},
        {"paper:\n  stationary_m: 1\n", 2, "paper.stationary_m"},
        {"paper:\n  learning_rate: 1\n", 2, "paper.learning_rate"},
    };
    const fs::path path = TempFile("rules.yaml");
    for (const Case& c : cases) {
        WriteFile(path, c.yaml);
        try {
            pipeline::LoadPipelineConfig(path.string());
            ADD_FAILURE() << c.yaml << "accepted";
        } catch (const InputError& e) {
            EXPECT_EQ(e.line(), c.line) << e.what();
            EXPECT_EQ(e.key(), c.key) << e.what();
        }
    }
}

TEST(ParameterReference, ReadsBackToTheConfigItWasMadeFrom) {
    pipeline::PipelineConfig changed;
    changed.corrector.model.step_sigma_m = 0.037;
    changed.corrector.max_chunk_poses = 123;
    changed.paper.iterations_per_epoch = 77;
    changed.roads.profile = "all";
    changed.roads.half_width_overrides_m = {{"track", 0.0}, {"residential", 4.25}};
    changed.online.project_output = false;
    for (const pipeline::PipelineConfig& config : {pipeline::PipelineConfig{}, changed}) {
        const std::string text = pipeline::ParameterReference(config);
        const fs::path path = TempFile("reference.yaml");
        WriteFile(path, text);
        const pipeline::PipelineConfig read = pipeline::LoadPipelineConfig(path.string());
        EXPECT_EQ(pipeline::ParameterReference(read), text);
    }
    EXPECT_NE(pipeline::ParameterReference(changed), pipeline::ParameterReference());
}

TEST(ParameterReference, ListsEveryRowOfEveryTable) {
    const std::string text = "\n" + pipeline::ParameterReference();
    pipeline::ForEachParamSection(pipeline::PipelineConfig{}, [&](const char* section,
                                                                  const auto& table, const auto&,
                                                                  const char*) {
        EXPECT_NE(text.find("\n" + std::string(section) + ":  # "), std::string::npos) << section;
        for (const auto& p : table) {
            EXPECT_NE(text.find("\n  " + std::string(p.key) + ": "), std::string::npos) << p.key;
        }
    });
}

/// Every value of `a` and `b` that a row of `table` holds, as params.yaml writes it (the shortest
/// text that reads back as the same double: equal texts are equal values).
template <class Config>
void ExpectRowsEqual(const ParamTable<Config>& table, const Config& a, const Config& b) {
    for (const Param<Config>& p : table) {
        EXPECT_EQ(FormatParamValue(p, a), FormatParamValue(p, b)) << table.section << "." << p.key;
    }
}

// The pipeline corrects indoor3d walks with the pedestrian preset: every field, the rows of
// the model, corrector and covariance tables and the members that are no params.yaml key.
TEST(CorrectorConfig, PedestrianPresetIsThePipelinesIndoorCorrector) {
    const CorrectorConfig preset = CorrectorConfig::Pedestrian();
    const CorrectorConfig indoor = pipeline::PipelineConfig{}.indoor_corrector;
    EXPECT_EQ(preset.Validate(), "");
    ExpectRowsEqual(kModelParams, preset.model, indoor.model);
    ExpectRowsEqual(kModelParams, preset.model, ModelConfig::Pedestrian());
    ExpectRowsEqual(kCorrectorParams, preset, indoor);
    ExpectRowsEqual(kCovarianceParams, preset.covariance, indoor.covariance);
    EXPECT_EQ(preset.start_scales, indoor.start_scales);
    EXPECT_EQ(preset.restart_scale_factors, indoor.restart_scale_factors);
    EXPECT_EQ(preset.restart_height_gains, indoor.restart_height_gains);
    EXPECT_EQ(preset.restart_height_change_m, indoor.restart_height_change_m);
    // It is a preset, not the struct's defaults.
    EXPECT_NE(CorrectorConfig{}.model.max_speed_mps, preset.model.max_speed_mps);
    EXPECT_NE(CorrectorConfig{}.start_scales, preset.start_scales);
}

// CorrectorReference writes a preset as the sections model and corrector of a params.yaml:
// read back, they set the road2d corrector's keys to the preset's values and nothing else.
TEST(CorrectorReference, ReadsBackToThePresetsKeys) {
    const CorrectorConfig preset = CorrectorConfig::Pedestrian();
    const std::string text = pipeline::CorrectorReference(preset);
    EXPECT_EQ(text.rfind("model:  # ", 0), 0u) << text;
    EXPECT_NE(text.find("\ncorrector:  # "), std::string::npos) << text;
    EXPECT_EQ(text.find("indoor_"), std::string::npos) << text;
    const fs::path path = TempFile("preset.yaml");
    WriteFile(path, text);
    const pipeline::PipelineConfig read = pipeline::LoadPipelineConfig(path.string());
    ExpectRowsEqual(kModelParams, read.corrector.model, preset.model);
    ExpectRowsEqual(kCorrectorParams, read.corrector, preset);
    pipeline::PipelineConfig expected;
    expected.corrector = preset;
    EXPECT_EQ(pipeline::ParameterReference(read), pipeline::ParameterReference(expected));
    // The defaults' two sections are where ParameterReference begins.
    EXPECT_EQ(pipeline::ParameterReference().rfind(pipeline::CorrectorReference({}), 0), 0u);
}

std::string ReadText(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// The text between `begin` and `end` in `text`, or "" when a marker is missing.
std::string Between(const std::string& text, const std::string& begin, const std::string& end) {
    const std::size_t a = text.find(begin);
    const std::size_t b = a == std::string::npos ? a : text.find(end, a + begin.size());
    if (b == std::string::npos) return "";
    return text.substr(a + begin.size(), b - a - begin.size());
}

TEST(ParameterReference, ParametersDocListsEveryParameter) {
    const std::string doc = ReadText(DRIFTCORR_PARAMETERS_DOC);
    const std::string listed = Between(doc, "<!-- BEGIN driftcorr params -->\n```yaml\n",
                                       "```\n<!-- END driftcorr params -->");
    EXPECT_EQ(listed, pipeline::ParameterReference())
        << "docs/parameters.md's parameter list differs from the tables: replace the block "
           "between the BEGIN/END driftcorr params markers with the output of `driftcorr params`";
}

TEST(ParameterReference, ParametersDocExampleIsAValidParameterFile) {
    const std::string doc = ReadText(DRIFTCORR_PARAMETERS_DOC);
    const std::string example =
        Between(doc, "A file sets only the keys it names, e.g.\n\n```yaml\n", "```");
    ASSERT_FALSE(example.empty());
    const fs::path path = TempFile("example.yaml");
    WriteFile(path, example);
    EXPECT_NO_THROW(pipeline::LoadPipelineConfig(path.string()));
}

// The start scales of the batch correction (no params.yaml key: a list) are checked by
// Validate like the keys: at least one, each inside the scale variables' bounds.
TEST(CorrectorConfig, StartScalesMustBeListedAndInsideTheScaleBounds) {
    CorrectorConfig c;
    EXPECT_EQ(c.Validate(), "");
    c.start_scales.clear();
    EXPECT_NE(c.Validate().find("start_scales"), std::string::npos) << c.Validate();
    c.start_scales = {1.0, kScaleMax + 1.0};
    EXPECT_NE(c.Validate().find("start_scales"), std::string::npos) << c.Validate();
    c.start_scales = {1.0, kScaleMin, kScaleMax};
    EXPECT_EQ(c.Validate(), "");
}

// The scale prior's mean is a scale too: inside the scale variables' bounds.
TEST(ModelConfig, ScalePriorMeanMustLieInsideTheScaleBounds) {
    ModelConfig m;
    m.scale_prior_mean = kScaleMax;
    EXPECT_EQ(m.Validate(), "");
    m.scale_prior_mean = kScaleMax * 1.01;
    EXPECT_NE(m.Validate().find("scale_prior_mean"), std::string::npos) << m.Validate();
    m.scale_prior_mean = kScaleMin * 0.99;
    EXPECT_NE(m.Validate().find("scale_prior_mean"), std::string::npos) << m.Validate();
}

}  // namespace
}  // namespace driftcorr
