// Tests of `driftcorr eval`'s library (examples/eval): a short generated synthetic scenario, the
// same scenario without ground truth, and a broken scenario folder are evaluated in one run; the
// broken one must not stop the others and every file of the report must hold what it promises.
#include <cairo.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "driftcorr/eval/evaluation.h"
#include "driftcorr/eval/report.h"
#include "test_support.h"

namespace driftcorr::eval {
namespace {

namespace fs = std::filesystem;

const std::string kGenerator = DRIFTCORR_BINARY_DIR "/datasets/driftcorr_make_road_scenario";

using driftcorr::test::ReadFile;
using driftcorr::test::WriteFile;

class EvalReport : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        root_ = test::FreshProcessDir("eval_report");
        const std::string cmd = kGenerator + " " + (root_ / "synth").string() +
                                " --duration-s 60 > " + (root_ / "gen.log").string();
        ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
        // The same drive without ground truth.
        fs::copy(root_ / "synth", root_ / "no_gt", fs::copy_options::recursive);
        std::string yaml = ReadFile(root_ / "no_gt" / "scenario.yaml");
        const std::string gt_block = "ground_truth:\n  path: ground_truth.tum\n  format: tum\n";
        const std::size_t at = yaml.find(gt_block);
        ASSERT_NE(at, std::string::npos) << "generator output changed";
        yaml.erase(at, gt_block.size());
        WriteFile(root_ / "no_gt" / "scenario.yaml", yaml);
        // A broken scenario: its estimate file is missing.
        fs::copy(root_ / "synth", root_ / "broken", fs::copy_options::recursive);
        fs::remove(root_ / "broken" / "estimate.tum");

        std::vector<EvalProgress> progress;
        evals_ = EvaluateScenarios(
            {(root_ / "synth").string(), (root_ / "broken").string(), (root_ / "no_gt").string()},
            EvalConfig{}, [&](const EvalProgress& p) { progress.push_back(p); });
        progress_count_ = progress.size();
        report_ = root_ / "report";
        written_ = WriteReport(report_.string(), evals_);
    }
    static void TearDownTestSuite() { fs::remove_all(root_); }

    static inline fs::path root_, report_;
    static inline std::vector<ScenarioEvaluation> evals_;
    static inline std::vector<std::string> written_;
    static inline std::size_t progress_count_ = 0;
};

TEST_F(EvalReport, EveryScenarioIsEvaluatedOrReportedAsFailed) {
    ASSERT_EQ(evals_.size(), 3u);
    EXPECT_GT(progress_count_, 6u);
    const ScenarioEvaluation& good = evals_[0];
    ASSERT_TRUE(good.ok()) << good.error;
    EXPECT_EQ(good.label, "synth");
    EXPECT_EQ(good.poses, 601u);
    ASSERT_EQ(good.methods.size(), 4u);  // estimate, paper, driftcorr, online
    for (const MethodResult& m : good.methods) {
        EXPECT_TRUE(m.ok) << ToString(m.method) << ": " << m.message;
        ASSERT_TRUE(m.metrics.has_value());
        EXPECT_EQ(m.errors_m.size(), 601u);
        ASSERT_TRUE(m.mean_map_distance_m.has_value());
    }
    // driftcorr corrects the 60 s drive (tolerance: better than the estimate's ATE).
    EXPECT_LT(good.Find(Method::kDriftcorr)->metrics->ate_m,
              good.Find(Method::kEstimate)->metrics->ate_m);
    EXPECT_LT(good.Find(Method::kOnline)->metrics->ate_m,
              good.Find(Method::kEstimate)->metrics->ate_m);

    const ScenarioEvaluation& broken = evals_[1];
    EXPECT_FALSE(broken.ok());
    EXPECT_NE(broken.error.find("estimate.tum"), std::string::npos) << broken.error;
    EXPECT_TRUE(broken.AnyFailed());

    const ScenarioEvaluation& no_gt = evals_[2];
    ASSERT_TRUE(no_gt.ok()) << no_gt.error;
    EXPECT_FALSE(no_gt.has_ground_truth);
    for (const MethodResult& m : no_gt.methods) {
        EXPECT_FALSE(m.metrics.has_value());
        EXPECT_TRUE(m.mean_map_distance_m.has_value());
    }
}

TEST_F(EvalReport, SummaryHasARowPerScenarioWithTheFailureAndTheMissingGroundTruth) {
    const std::string md = ReadFile(report_ / "summary.md");
    EXPECT_NE(md.find("| synth | road2d | 601 | yes |"), std::string::npos) << md;
    EXPECT_NE(md.find("| broken |"), std::string::npos) << md;
    EXPECT_NE(md.find("**FAILED**: " + evals_[1].error), std::string::npos) << md;
    EXPECT_NE(md.find("| no_gt | road2d | 601 | **no**"), std::string::npos) << md;
    EXPECT_NE(md.find("driftcorr ATE [m]"), std::string::npos);
    EXPECT_NE(md.find("paper ATE [m]"), std::string::npos);
    EXPECT_NE(md.find("poses/s"), std::string::npos);
    // The console table has the same rows.
    const std::string table = FormatTable(evals_);
    EXPECT_NE(table.find("broken"), std::string::npos);
    EXPECT_NE(table.find("FAILED: " + evals_[1].error), std::string::npos) << table;
}

TEST_F(EvalReport, ResultsJsonHasTheExpectedKeysAndBalancedBrackets) {
    const std::string json = ReadFile(report_ / "results.json");
    for (const char* key :
         {"\"scenarios\"", "\"label\": \"synth\"", "\"status\": \"failed\"",
          "\"has_ground_truth\": false", "\"estimate\"", "\"paper\"", "\"driftcorr\"", "\"ate_m\"",
          "\"final_m\"", "\"p90_m\"", "\"drift_pct\"", "\"wall_s\"", "\"poses_per_s\"",
          "\"speed_ratio_paper_over_driftcorr\"", "\"any_failed\": true"}) {
        EXPECT_NE(json.find(key), std::string::npos) << key;
    }
    // JSON-ish: balanced braces and brackets outside strings, no NaN/inf literals.
    int braces = 0, brackets = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < json.size(); ++i) {
        const char c = json[i];
        if (in_string) {
            if (c == '\\')
                ++i;
            else if (c == '"')
                in_string = false;
            continue;
        }
        if (c == '"') in_string = true;
        braces += (c == '{') - (c == '}');
        brackets += (c == '[') - (c == ']');
        ASSERT_GE(braces, 0);
        ASSERT_GE(brackets, 0);
    }
    EXPECT_EQ(braces, 0);
    EXPECT_EQ(brackets, 0);
    EXPECT_FALSE(in_string);
    EXPECT_EQ(json.find("nan"), std::string::npos);
    EXPECT_EQ(json.find("inf"), std::string::npos);
}

TEST_F(EvalReport, PlotsAreSvgWithPolylines) {
    for (const char* name : {"synth_map.svg", "synth_error.svg", "no_gt_map.svg"}) {
        const std::string svg = ReadFile(report_ / name);
        EXPECT_NE(svg.find("<svg"), std::string::npos) << name;
        EXPECT_NE(svg.find("<polyline"), std::string::npos) << name;
        EXPECT_NE(svg.find("</svg>"), std::string::npos) << name;
    }
    // No error plot without ground truth, no plots for the failed scenario.
    EXPECT_FALSE(fs::exists(report_ / "no_gt_error.svg"));
    EXPECT_FALSE(fs::exists(report_ / "broken_map.svg"));
    EXPECT_EQ(written_.size(), 8u);
    // The map plot has every method's colour and a scale bar in metres.
    const std::string map = ReadFile(report_ / "synth_map.svg");
    for (const char* colour : {"#000", "#d62728", "#ff7f0e", "#1f77b4"}) {
        EXPECT_NE(map.find(colour), std::string::npos) << colour;
    }
    EXPECT_NE(map.find(" m</text>"), std::string::npos);
}

// Each plot also as a PNG of the SVG's size in pixels, drawn: its page (white, the map's plot
// area #fafafa) and the estimate's red line (#d62728) are among its pixels.
TEST_F(EvalReport, EveryPlotIsAlsoAPngOfItsSvg) {
    for (const char* name : {"synth_map", "synth_error", "no_gt_map"}) {
        const fs::path png = report_ / (std::string(name) + ".png");
        ASSERT_TRUE(fs::exists(png)) << name;
        cairo_surface_t* image = cairo_image_surface_create_from_png(png.c_str());
        ASSERT_EQ(cairo_surface_status(image), CAIRO_STATUS_SUCCESS) << name;
        const std::string svg = ReadFile(report_ / (std::string(name) + ".svg"));
        const int w = cairo_image_surface_get_width(image),
                  h = cairo_image_surface_get_height(image);
        EXPECT_NE(svg.find("width=\"" + std::to_string(w) + "\""), std::string::npos) << name;
        EXPECT_NE(svg.find("height=\"" + std::to_string(h) + "\""), std::string::npos) << name;
        const unsigned char* data = cairo_image_surface_get_data(image);
        const int stride = cairo_image_surface_get_stride(image);
        int page = 0, red = 0;
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                const std::uint32_t argb =
                    *reinterpret_cast<const std::uint32_t*>(data + y * stride + 4 * x);
                page += (argb & 0xFFFFFFu) == 0xFFFFFFu || (argb & 0xFFFFFFu) == 0xFAFAFAu;
                red += (argb & 0xFFFFFFu) == 0xD62728u;
            }
        }
        EXPECT_GT(page, w * h / 2) << name;
        EXPECT_GT(red, 20) << name << ": the estimate's line";
        cairo_surface_destroy(image);
    }
    EXPECT_FALSE(fs::exists(report_ / "no_gt_error.png"));
    EXPECT_THROW(SvgToPng("<svg"), std::runtime_error);
}

}  // namespace
}  // namespace driftcorr::eval
