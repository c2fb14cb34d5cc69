// Degenerate trajectories and maps end with a clear status and warning instead of garbage:
// all poses equal, a straight line that disagrees with the map, a map that covers none of the
// drive, a huge jump between two poses.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/pipeline/pipeline.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace driftcorr;

namespace {

using Lines = std::vector<std::vector<std::string>>;

Lines ReadFields(const fs::path& p) {
    Lines out;
    std::ifstream in(p);
    for (std::string line; std::getline(in, line);) {
        std::istringstream ss(line);
        std::vector<std::string> f;
        for (std::string x; ss >> x;) f.push_back(x);
        if (!f.empty()) out.push_back(f);
    }
    return out;
}

void WriteFields(const fs::path& p, const Lines& lines) {
    std::ofstream out(p);
    for (const auto& f : lines) {
        for (std::size_t k = 0; k < f.size(); ++k) out << (k ? " " : "") << f[k];
        out << "\n";
    }
}

class Degenerate : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        base_ = test::FreshProcessDir("degenerate");
        const std::string cmd = test::RoadGeneratorCommand(base_ / "base", "--duration-s 60");
        ASSERT_EQ(std::system(cmd.c_str()), 0);
    }
    static void TearDownTestSuite() { fs::remove_all(base_); }

    // A copy of the valid scenario with its estimate (and scenario text) changed.
    static pipeline::CorrectionRun Run(const std::string& name,
                                       const std::function<void(Lines&)>& edit_estimate,
                                       const std::function<void(std::string&)>& edit_yaml = {}) {
        const fs::path dir = base_ / name;
        fs::copy(base_ / "base", dir, fs::copy_options::recursive);
        Lines est = ReadFields(dir / "estimate.tum");
        edit_estimate(est);
        WriteFields(dir / "estimate.tum", est);
        if (edit_yaml) {
            std::ifstream in(dir / "scenario.yaml");
            std::string text((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
            edit_yaml(text);
            std::ofstream(dir / "scenario.yaml") << text;
        }
        return pipeline::RunCorrection(dir.string(), pipeline::PipelineConfig{});
    }
    static bool HasWarning(const CorrectionResult& r, const std::string& text) {
        for (const std::string& w : r.warnings) {
            if (w.find(text) != std::string::npos) return true;
        }
        return false;
    }
    static fs::path base_;
};
fs::path Degenerate::base_;

TEST_F(Degenerate, AllPosesEqual) {
    const pipeline::CorrectionRun run = Run("all_equal", [](Lines& est) {
        for (auto& f : est) std::copy(est[0].begin() + 1, est[0].end(), f.begin() + 1);
    });
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    EXPECT_TRUE(HasWarning(run.result, "does not move"));
    // Pose 0 (fixed) is the ground truth 1.5 m right of the centre line; the map may pull the
    // stationary poses towards the centre line, but no farther than that lane offset.
    for (const auto& p : run.result.corrected.p_en)
        EXPECT_LT((p - run.estimate.p_en[0]).norm(), 2.0);
}

TEST_F(Degenerate, StraightLineThatDisagreesWithTheMap) {
    const pipeline::CorrectionRun run = Run("straight", [](Lines& est) {
        for (std::size_t i = 0; i < est.size(); ++i) {
            est[i] = {est[i][0], std::to_string(0.8 * i), "0", "0", "0", "0", "0", "1"};
        }
    });
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    // The drive is squeezed onto the map: a scale far outside the plausible range (the range
    // prior makes it cost, it does not forbid it), so the verdict refuses the result.
    EXPECT_LT(run.result.scale_min, 0.6);
    EXPECT_EQ(run.verdict.level, VerdictLevel::kFailed);
}

// A map out of any reach of the drive (111 km away for a drive of a few hundred metres) is bad
// input before the solve; one within its reach that it never comes near is corrected by the
// odometry alone, with a warning. The generator's map spans lat 48.9755..48.9845.
TEST_F(Degenerate, MapCoversNoneOfTheDrive) {
    try {
        Run(
            "far_map", [](Lines&) {},
            [](std::string& yaml) {
                const std::size_t at = yaml.find("lat_deg: 48.98");
                ASSERT_NE(at, std::string::npos);
                yaml.replace(at, 14, "lat_deg: 49.98");  // 111 km north of the map
            });
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("from the nearest road of the map"), std::string::npos)
            << e.what();
    }
    const pipeline::CorrectionRun run = Run(
        "near_map", [](Lines&) {},
        [](std::string& yaml) {
            const std::size_t at = yaml.find("lat_deg: 48.98");
            ASSERT_NE(at, std::string::npos);
            yaml.replace(at, 14, "lat_deg: 48.9985");  // 1.6 km north of the map's edge
        });
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    EXPECT_TRUE(HasWarning(run.result, "covers none of the drive"));
    ASSERT_TRUE(run.before && run.after);
    EXPECT_NEAR(run.after->ate_m, run.before->ate_m, 1e-3);  // the odometry, unchanged
}

TEST_F(Degenerate, HugeJumpBetweenTwoPoses) {
    const pipeline::CorrectionRun run = Run("jump", [](Lines& est) {
        for (std::size_t i = est.size() / 2; i < est.size(); ++i) {
            est[i][1] = std::to_string(std::stod(est[i][1]) + 3000.0);
        }
    });
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    EXPECT_TRUE(HasWarning(run.result, "treated as discontinuities"));
    // The jump is not scaled by the learned step-length scale: it stays 3 km within a metre.
    const std::size_t k = run.estimate.size() / 2;
    const double jump = (run.result.corrected.p_en[k] - run.result.corrected.p_en[k - 1]).norm();
    EXPECT_NEAR(jump, (run.estimate.p_en[k] - run.estimate.p_en[k - 1]).norm(), 1.0);
}

}  // namespace
