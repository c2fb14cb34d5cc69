// Tests of the synthetic road scenario generator (datasets/synth_road): determinism for a seed,
// the seed changing only the estimate, the shape of the TUM files, the documented error range.
// The generator is run as a program (std::system); it must be built before this test
// (add_dependencies(test_synth_road driftcorr_make_road_scenario)).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"

namespace {

namespace fs = std::filesystem;

const std::string kGenerator = DRIFTCORR_BINARY_DIR "/datasets/driftcorr_make_road_scenario";

// Documented in datasets/README.md for the default parameters.
constexpr std::size_t kDefaultPoses = 4201;  // 420 s at 10 Hz, both ends included
constexpr double kFirstTimestamp_s = 1000.0;
constexpr double kDocumentedMaxErrorMin_m = 30.0;
constexpr double kDocumentedMaxErrorMax_m = 80.0;
constexpr double kMaxSpeed_mps = 14.0;
constexpr double kStopMin_s = 19.0;  // the stop lasts ~20 s
constexpr double kStopMax_s = 21.0;
constexpr double kPrintTolerance_m = 2e-6;  // positions are printed with 6 decimals

const char* const kFiles[] = {"map.osm", "ground_truth.tum", "estimate.tum", "scenario.yaml"};

struct TumRow {
    double t_s = 0.0;
    double x_m = 0.0, y_m = 0.0, z_m = 0.0;
    double qx = 0.0, qy = 0.0, qz = 0.0, qw = 1.0;
};

/// Runs the generator with `args`; returns its exit code (-1 if it did not exit normally).
int RunGenerator(const std::string& args) {
    const std::string command = "\"" + kGenerator + "\" " + args + " > /dev/null 2>&1";
    const int status = std::system(command.c_str());
    return (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
}

std::string ReadBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Minimal TUM reader: 8 numbers a line; a malformed line is a test failure.
std::vector<TumRow> ReadTum(const fs::path& path) {
    std::ifstream in(path);
    std::vector<TumRow> rows;
    std::string line;
    for (int line_no = 1; std::getline(in, line); ++line_no) {
        std::istringstream fields(line);
        TumRow r;
        fields >> r.t_s >> r.x_m >> r.y_m >> r.z_m >> r.qx >> r.qy >> r.qz >> r.qw;
        std::string extra;
        if (!fields || (fields >> extra)) {
            ADD_FAILURE() << path << ":" << line_no << ": not 8 numbers: " << line;
            break;
        }
        rows.push_back(r);
    }
    return rows;
}

double HorizontalError_m(const TumRow& a, const TumRow& b) {
    return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}

/// Generates three scenarios once per test process (ctest runs every test in its own process,
/// hence the process id in the folder name): two with the default seed, one with seed 7.
class SynthRoadTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        root_ = driftcorr::test::FreshProcessDir("synth_road");
        exit_a_ = RunGenerator("\"" + (root_ / "a").string() + "\"");
        exit_b_ = RunGenerator("\"" + (root_ / "b").string() + "\"");
        exit_c_ = RunGenerator("\"" + (root_ / "c").string() + "\" --seed 7");
    }
    static void TearDownTestSuite() { fs::remove_all(root_); }

    void SetUp() override {
        ASSERT_TRUE(fs::exists(kGenerator)) << kGenerator << " is not built";
        ASSERT_EQ(exit_a_, 0);
        ASSERT_EQ(exit_b_, 0);
        ASSERT_EQ(exit_c_, 0);
    }

    static inline fs::path root_;
    static inline int exit_a_ = -1, exit_b_ = -1, exit_c_ = -1;
};

TEST_F(SynthRoadTest, WritesAllFourFiles) {
    for (const char* name : kFiles) {
        EXPECT_TRUE(fs::is_regular_file(root_ / "a" / name)) << name;
        EXPECT_FALSE(fs::exists(root_ / "a" / (std::string(name) + ".tmp"))) << name;
    }
}

TEST_F(SynthRoadTest, SameSeedGivesByteIdenticalFiles) {
    for (const char* name : kFiles) {
        const std::string a = ReadBytes(root_ / "a" / name);
        EXPECT_FALSE(a.empty()) << name;
        EXPECT_TRUE(a == ReadBytes(root_ / "b" / name)) << name << " differs between two runs";
    }
}

TEST_F(SynthRoadTest, DifferentSeedChangesTheEstimateOnly) {
    EXPECT_NE(ReadBytes(root_ / "a" / "estimate.tum"), ReadBytes(root_ / "c" / "estimate.tum"));
    EXPECT_TRUE(ReadBytes(root_ / "a" / "ground_truth.tum") ==
                ReadBytes(root_ / "c" / "ground_truth.tum"));
    EXPECT_TRUE(ReadBytes(root_ / "a" / "map.osm") == ReadBytes(root_ / "c" / "map.osm"));
}

TEST_F(SynthRoadTest, TrajectoriesShareStrictlyIncreasingTimestamps) {
    const std::vector<TumRow> gt = ReadTum(root_ / "a" / "ground_truth.tum");
    const std::vector<TumRow> est = ReadTum(root_ / "a" / "estimate.tum");
    ASSERT_EQ(gt.size(), kDefaultPoses);
    ASSERT_EQ(est.size(), gt.size());
    EXPECT_DOUBLE_EQ(gt.front().t_s, kFirstTimestamp_s);
    for (std::size_t k = 0; k < gt.size(); ++k) {
        ASSERT_EQ(est[k].t_s, gt[k].t_s) << "pose " << k;
        if (k > 0) {
            ASSERT_GT(gt[k].t_s, gt[k - 1].t_s) << "pose " << k;
        }
        ASSERT_EQ(gt[k].z_m, 0.0);
        ASSERT_EQ(est[k].z_m, 0.0);
    }
}

TEST_F(SynthRoadTest, EstimateStartsAtTheFirstGroundTruthPose) {
    const std::vector<TumRow> gt = ReadTum(root_ / "a" / "ground_truth.tum");
    const std::vector<TumRow> est = ReadTum(root_ / "a" / "estimate.tum");
    ASSERT_FALSE(gt.empty());
    ASSERT_FALSE(est.empty());
    EXPECT_EQ(est[0].x_m, gt[0].x_m);
    EXPECT_EQ(est[0].y_m, gt[0].y_m);
    EXPECT_EQ(est[0].qz, gt[0].qz);
    EXPECT_EQ(est[0].qw, gt[0].qw);
}

TEST_F(SynthRoadTest, DefaultMaxErrorIsInTheDocumentedRange) {
    const std::vector<TumRow> gt = ReadTum(root_ / "a" / "ground_truth.tum");
    const std::vector<TumRow> est = ReadTum(root_ / "a" / "estimate.tum");
    ASSERT_EQ(est.size(), gt.size());
    double max_error_m = 0.0;
    for (std::size_t k = 0; k < gt.size(); ++k) {
        max_error_m = std::max(max_error_m, HorizontalError_m(est[k], gt[k]));
    }
    EXPECT_GE(max_error_m, kDocumentedMaxErrorMin_m);
    EXPECT_LE(max_error_m, kDocumentedMaxErrorMax_m);
}

TEST_F(SynthRoadTest, GroundTruthSpeedAndStopAreAsDocumented) {
    const std::vector<TumRow> gt = ReadTum(root_ / "a" / "ground_truth.tum");
    const std::vector<TumRow> est = ReadTum(root_ / "a" / "estimate.tum");
    ASSERT_EQ(est.size(), gt.size());
    double longest_stop_s = 0.0, stop_s = 0.0;
    for (std::size_t k = 1; k < gt.size(); ++k) {
        const double step_m = HorizontalError_m(gt[k], gt[k - 1]);
        const double dt_s = gt[k].t_s - gt[k - 1].t_s;
        EXPECT_LE(step_m / dt_s, kMaxSpeed_mps + kPrintTolerance_m / dt_s) << "pose " << k;
        stop_s = step_m == 0.0 ? stop_s + dt_s : 0.0;
        longest_stop_s = std::max(longest_stop_s, stop_s);
        if (step_m == 0.0) {  // a stop stays a stop in the estimate too
            EXPECT_EQ(HorizontalError_m(est[k], est[k - 1]), 0.0) << "pose " << k;
        }
    }
    EXPECT_GE(longest_stop_s, kStopMin_s);
    EXPECT_LE(longest_stop_s, kStopMax_s);
}

TEST_F(SynthRoadTest, ScenarioYamlAndMapHaveTheAgreedContent) {
    const std::string yaml = ReadBytes(root_ / "a" / "scenario.yaml");
    for (const char* needle : {"name: synthetic-road-grid", "mode: road2d", "frame: enu",
                               "path: estimate.tum", "path: ground_truth.tum", "path: map.osm",
                               "lat_deg: 48.98", "lon_deg: 8.39", "yaw_deg: 0", "seed 42"}) {
        EXPECT_NE(yaml.find(needle), std::string::npos) << needle;
    }
    const std::string osm = ReadBytes(root_ / "a" / "map.osm");
    for (const char* needle :
         {"<osm version=\"0.6\" generator=\"driftcorr synth\">",
          "<tag k=\"highway\" v=\"street_lamp\"/>", "v=\"footway\"", "v=\"cycleway\"",
          "v=\"service\"", "v=\"secondary\"", "v=\"tertiary\"", "k=\"name\""}) {
        EXPECT_NE(osm.find(needle), std::string::npos) << needle;
    }
}

TEST_F(SynthRoadTest, BadArgumentsExitWithTwo) {
    const std::string out = "\"" + (root_ / "bad").string() + "\"";
    EXPECT_EQ(RunGenerator(""), 2);
    EXPECT_EQ(RunGenerator(out + " --seed abc"), 2);
    EXPECT_EQ(RunGenerator(out + " --seed -3"), 2);
    EXPECT_EQ(RunGenerator(out + " --duration-s -5"), 2);
    EXPECT_EQ(RunGenerator(out + " --scale-error"), 2);
    EXPECT_EQ(RunGenerator(out + " --no-such-flag 1"), 2);
    EXPECT_FALSE(fs::exists(root_ / "bad"));
}

}  // namespace
