// Tests of the io edge: trajectory files, scenario.yaml, AtomicFile and the GeoJSON writer.
// Every bad-input case writes its own small file and checks that the InputError names the file
// and the line or key.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/io/geojson_writer.h"
#include "driftcorr/io/scenario.h"
#include "driftcorr/io/text_file.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/mapping/atomic_file.h"

#if __has_include(<nlohmann/json.hpp>)
#include <nlohmann/json.hpp>
#define DRIFTCORR_TEST_HAS_JSON 1
#endif

namespace driftcorr::io {
namespace {

namespace fs = std::filesystem;

/// A fresh folder per test (tests may run in parallel processes under ctest).
fs::path TestDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "_" + info->name();
    for (char& c : name) {
        if (c == '/') c = '_';
    }
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "io" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string WriteText(const fs::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
    return path.string();
}

std::string ReadText(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// Runs `fn`, expects an InputError, and checks that what() contains each of `fragments`.
void ExpectInputError(const std::function<void()>& fn, const std::vector<std::string>& fragments) {
    try {
        fn();
        ADD_FAILURE() << "no InputError thrown";
    } catch (const InputError& e) {
        for (const std::string& f : fragments) {
            EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
                << "'" << f << "' not in: " << e.what();
        }
    }
}

Trajectory SmallTrajectory() {
    Trajectory traj;
    for (int i = 0; i < 4; ++i) {
        traj.t_s.push_back(1606391913.755 + 0.25 * i);
        traj.p_frame.emplace_back(1.5 * i, -0.125 * i, 1e-3 * i);
        traj.q_frame_body.push_back(Eigen::Quaterniond(
            Eigen::AngleAxisd(0.3 * i - 0.2, Eigen::Vector3d(1, 2, 3).normalized())));
    }
    return traj;
}

// ---------------------------------------------------------------------------------------------
// Trajectory readers and writer

TEST(TrajectoryIo, TumRoundTrip) {
    const fs::path dir = TestDir();
    const Trajectory traj = SmallTrajectory();
    const std::string path = (dir / "traj.tum").string();
    WriteTum(path, traj);
    const Trajectory back = ReadTum(path);
    ASSERT_EQ(back.size(), traj.size());
    ASSERT_TRUE(back.HasOrientation());
    for (std::size_t i = 0; i < traj.size(); ++i) {
        EXPECT_NEAR(back.t_s[i], traj.t_s[i], 1e-6);
        EXPECT_LT((back.p_frame[i] - traj.p_frame[i]).norm(), 1e-6);
        EXPECT_NEAR(std::abs(back.q_frame_body[i].dot(traj.q_frame_body[i])), 1.0, 1e-9);
    }
    const std::string text = ReadText(path);
    EXPECT_EQ(text.substr(0, text.find('\n')).substr(0, 46),
              "1606391913.755000 0.000000 -0.000000 0.000000 ");
}

TEST(TrajectoryIo, WriteTumWithoutOrientationWritesIdentity) {
    const fs::path dir = TestDir();
    Trajectory traj;
    traj.t_s = {0.0, 0.1};
    traj.p_frame = {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(4, 5, 6)};
    const std::string path = (dir / "traj.tum").string();
    WriteTum(path, traj);
    EXPECT_EQ(
        ReadText(path),
        "0.000000 1.000000 2.000000 3.000000 0.000000000 0.000000000 0.000000000 1.000000000\n"
        "0.100000 4.000000 5.000000 6.000000 0.000000000 0.000000000 0.000000000 1.000000000\n");
}

TEST(TrajectoryIo, WriteTumRejectsInconsistentTrajectoryAndWritesNothing) {
    const fs::path dir = TestDir();
    Trajectory traj = SmallTrajectory();
    traj.p_frame.pop_back();
    const fs::path path = dir / "traj.tum";
    EXPECT_THROW(WriteTum(path.string(), traj), std::invalid_argument);
    EXPECT_FALSE(fs::exists(path));
}

TEST(TrajectoryIo, TumSkipsCommentsAndBlankLinesAndNormalises) {
    const fs::path dir = TestDir();
    const std::string path = WriteText(dir / "t.tum",
                                       "# t x y z qx qy qz qw\n\n"
                                       "0 1 2 3 0 0 0 2\r\n"
                                       "  \t\n"
                                       "0.5\t1 2 3 0 0 2 0\n"
                                       "+1.0 -1e-3 2.5E+1 3 0 0 0 1");  // no final newline
    const Trajectory traj = ReadTum(path);
    ASSERT_EQ(traj.size(), 3u);
    EXPECT_DOUBLE_EQ(traj.t_s[2], 1.0);
    EXPECT_DOUBLE_EQ(traj.p_frame[2].x(), -1e-3);
    EXPECT_DOUBLE_EQ(traj.p_frame[2].y(), 25.0);
    EXPECT_DOUBLE_EQ(traj.q_frame_body[0].w(), 1.0);
    EXPECT_DOUBLE_EQ(traj.q_frame_body[1].z(), 1.0);
}

/// One row of the KITTI fixture: rotation about the camera's y axis by `yaw`, position (x, 0, z).
std::string KittiLine(double yaw, double x, double z) {
    const double c = std::cos(yaw), s = std::sin(yaw);
    char buf[256];
    std::snprintf(buf, sizeof(buf), "%.9f 0 %.9f %.3f 0 1 0 0 %.9f 0 %.9f %.3f\n", c, s, x, -s, c,
                  z);
    return buf;
}

std::string KittiFixture() {
    return KittiLine(0.0, 0.0, 0.0) + KittiLine(0.1, 0.5, 1.0) + KittiLine(0.2, 1.0, 2.0) +
           KittiLine(0.3, 1.5, 3.0);
}

TEST(TrajectoryIo, KittiWithRate) {
    const fs::path dir = TestDir();
    const std::string path = WriteText(dir / "k.txt", KittiFixture());
    const Trajectory traj = ReadKitti(path, std::nullopt, 10.0);
    ASSERT_EQ(traj.size(), 4u);
    ASSERT_TRUE(traj.HasOrientation());
    for (std::size_t i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(traj.t_s[i], i / 10.0);
    EXPECT_LT((traj.p_frame[2] - Eigen::Vector3d(1.0, 0.0, 2.0)).norm(), 1e-12);
    const Eigen::Quaterniond expected(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()));
    EXPECT_NEAR(std::abs(traj.q_frame_body[3].dot(expected)), 1.0, 1e-9);
    EXPECT_NEAR(traj.q_frame_body[3].norm(), 1.0, 1e-12);
}

TEST(TrajectoryIo, KittiWithTimes) {
    const fs::path dir = TestDir();
    const std::string path = WriteText(dir / "k.txt", KittiFixture());
    const std::string times = WriteText(dir / "times.txt", "0.0\n1.037359e-01\n0.25\n3.5e-01\n");
    TrajectorySource source;
    source.path = path;
    source.format = TrajectoryFormat::kKitti;
    source.rate_hz = 10.0;  // the times file wins
    source.times_path = times;
    const Trajectory traj = LoadTrajectory(source);
    ASSERT_EQ(traj.size(), 4u);
    EXPECT_DOUBLE_EQ(traj.t_s[1], 0.1037359);
    EXPECT_DOUBLE_EQ(traj.t_s[3], 0.35);
}

// Lines that start with a frame index: the frames a tracker had no pose for are gaps, not poses;
// the times come from the index (times file or rate).
TEST(TrajectoryIo, KittiWithFrameIndices) {
    const fs::path dir = TestDir();
    std::istringstream in(KittiFixture());
    std::string indexed;
    const int frames[] = {0, 3, 4, 9};
    int k = 0;
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        indexed += std::to_string(frames[k++]) + " " + line + "\n";
    }
    ASSERT_EQ(k, 4);
    const std::string path = WriteText(dir / "k_indexed.txt", indexed);
    const Trajectory by_rate = ReadKitti(path, std::nullopt, 10.0);
    ASSERT_EQ(by_rate.size(), 4u);
    for (int i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(by_rate.t_s[i], frames[i] / 10.0);
    EXPECT_LT((by_rate.p_frame[2] - Eigen::Vector3d(1.0, 0.0, 2.0)).norm(), 1e-12);
    std::string times;
    for (int f = 0; f < 10; ++f) times += std::to_string(0.5 * f) + "\n";
    const Trajectory by_times = ReadKitti(path, WriteText(dir / "t10.txt", times), std::nullopt);
    ASSERT_EQ(by_times.size(), 4u);
    EXPECT_DOUBLE_EQ(by_times.t_s[3], 4.5);
    ExpectInputError(
        [&] { ReadKitti(path, WriteText(dir / "t5.txt", "0\n1\n2\n3\n4\n"), std::nullopt); },
        {"has 5 timestamps but", "names frame 9"});
    std::string backwards = indexed;
    backwards.replace(backwards.rfind("\n9 ") + 1, 1, "2");
    const std::string back = WriteText(dir / "k_back.txt", backwards);
    ExpectInputError([&] { ReadKitti(back, std::nullopt, 10.0); },
                     {":4:", "frame index", "above the previous line's"});
}

/// A broken trajectory file and what its error must name.
struct BadTrajectoryCase {
    std::string label;
    TrajectoryFormat format;
    std::string content;
    std::string line_fragment;  ///< e.g. ":3:" (file:line:)
};

std::ostream& operator<<(std::ostream& os, const BadTrajectoryCase& c) { return os << c.label; }

class BadTrajectory : public ::testing::TestWithParam<BadTrajectoryCase> {};

TEST_P(BadTrajectory, ThrowsInputErrorNamingFileAndLine) {
    const BadTrajectoryCase& c = GetParam();
    const fs::path dir = TestDir();
    const std::string path = WriteText(dir / ("bad_" + c.label + ".txt"), c.content);
    ExpectInputError(
        [&] {
            if (c.format == TrajectoryFormat::kTum) {
                ReadTum(path);
            } else {
                ReadKitti(path, std::nullopt, 10.0);
            }
        },
        {path + c.line_fragment});
}

const std::string kTumOk = "0 0 0 0 0 0 0 1\n";
const std::string kKittiOk = "1 0 0 0 0 1 0 0 0 0 1 0\n";

INSTANTIATE_TEST_SUITE_P(
    Io, BadTrajectory,
    ::testing::Values(
        BadTrajectoryCase{"tum_too_few_fields", TrajectoryFormat::kTum,
                          kTumOk + "1 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n", ":2: expected 8 numbers"},
        BadTrajectoryCase{"tum_too_many_fields", TrajectoryFormat::kTum,
                          kTumOk + "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1 9\n", ":3: expected 8"},
        BadTrajectoryCase{"tum_trailing_garbage", TrajectoryFormat::kTum,
                          kTumOk + "1.0abc 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n", ":2: field 1"},
        BadTrajectoryCase{"tum_comma_separated", TrajectoryFormat::kTum,
                          kTumOk + "1,0,0,0,0,0,0,1\n2 0 0 0 0 0 0 1\n", ":2:"},
        BadTrajectoryCase{"tum_nan", TrajectoryFormat::kTum,
                          kTumOk + "1 nan 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n", ":2: field 2"},
        BadTrajectoryCase{"tum_inf", TrajectoryFormat::kTum,
                          kTumOk + "1 0 0 -inf 0 0 0 1\n2 0 0 0 0 0 0 1\n", ":2: field 4"},
        BadTrajectoryCase{"tum_repeated_time", TrajectoryFormat::kTum,
                          kTumOk + "1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", ":3: timestamp"},
        BadTrajectoryCase{"tum_backwards_time", TrajectoryFormat::kTum,
                          kTumOk + "# comment\n2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", ":4:"},
        BadTrajectoryCase{"tum_zero_quaternion", TrajectoryFormat::kTum,
                          kTumOk + "1 0 0 0 0 0 0 0\n2 0 0 0 0 0 0 1\n", ":2: quaternion"},
        BadTrajectoryCase{"tum_too_few_poses", TrajectoryFormat::kTum, kTumOk + "1 0 0 0 0 0 0 1\n",
                          ": has 2 poses, need at least 3"},
        BadTrajectoryCase{"tum_empty", TrajectoryFormat::kTum, "", ": has 0 poses"},
        BadTrajectoryCase{"kitti_too_few_fields", TrajectoryFormat::kKitti,
                          kKittiOk + kKittiOk + "1 0 0 0 0 1 0 0 0 0 1\n", ":3: expected 12"},
        BadTrajectoryCase{"kitti_trailing_garbage", TrajectoryFormat::kKitti,
                          kKittiOk + "1 0 0 0 0 1 0 0 0 0 1 0x\n" + kKittiOk, ":2: field 12"},
        BadTrajectoryCase{"kitti_nan", TrajectoryFormat::kKitti,
                          kKittiOk + kKittiOk + "1 0 0 NaN 0 1 0 0 0 0 1 0\n", ":3: field 4"},
        BadTrajectoryCase{"kitti_not_rotation", TrajectoryFormat::kKitti,
                          kKittiOk + "2 0 0 0 0 2 0 0 0 0 2 0\n" + kKittiOk, ":2: rotation"},
        BadTrajectoryCase{"kitti_reflection", TrajectoryFormat::kKitti,
                          kKittiOk + kKittiOk + "-1 0 0 0 0 1 0 0 0 0 1 0\n", ":3: rotation"},
        BadTrajectoryCase{"kitti_too_few_poses", TrajectoryFormat::kKitti, kKittiOk,
                          ": has 1 poses"}),
    [](const ::testing::TestParamInfo<BadTrajectoryCase>& p) { return p.param.label; });

TEST(TrajectoryIo, MissingFileNamesIt) {
    const std::string path = (TestDir() / "does_not_exist.tum").string();
    ExpectInputError([&] { ReadTum(path); }, {path, "cannot open"});
}

TEST(TrajectoryIo, KittiNeedsRateOrTimes) {
    const std::string path = WriteText(TestDir() / "k.txt", KittiFixture());
    ExpectInputError([&] { ReadKitti(path, std::nullopt, std::nullopt); }, {path, "rate_hz"});
    ExpectInputError([&] { ReadKitti(path, std::nullopt, 0.0); }, {path, "rate_hz"});
    ExpectInputError([&] { ReadKitti(path, std::nullopt, -10.0); }, {path, "rate_hz"});
}

TEST(TrajectoryIo, KittiTimesCountMismatch) {
    const fs::path dir = TestDir();
    const std::string path = WriteText(dir / "k.txt", KittiFixture());
    const std::string times = WriteText(dir / "times.txt", "0\n0.1\n0.2\n");
    ExpectInputError([&] { ReadKitti(path, times, std::nullopt); },
                     {times, "3 timestamps", "4 poses"});
}

TEST(TrajectoryIo, KittiTimesNotIncreasing) {
    const fs::path dir = TestDir();
    const std::string path = WriteText(dir / "k.txt", KittiFixture());
    const std::string times = WriteText(dir / "times.txt", "0\n0.1\n0.1\n0.3\n");
    ExpectInputError([&] { ReadKitti(path, times, std::nullopt); }, {times + ":3:", "increase"});
}

TEST(TrajectoryIo, KittiTimesGarbage) {
    const fs::path dir = TestDir();
    const std::string path = WriteText(dir / "k.txt", KittiFixture());
    const std::string times = WriteText(dir / "times.txt", "0\n0.1\n0.2 0.3\n0.4\n");
    ExpectInputError([&] { ReadKitti(path, times, std::nullopt); }, {times + ":3:", "expected 1"});
    const std::string times2 = WriteText(dir / "times2.txt", "0\n0.1s\n0.2\n0.4\n");
    ExpectInputError([&] { ReadKitti(path, times2, std::nullopt); }, {times2 + ":2:", "0.1s"});
}

// ---------------------------------------------------------------------------------------------
// Scenario files

const char* const kGoodScenario = R"(name: tiny
mode: road2d
estimate:
  path: est.txt
  format: kitti
  rate_hz: 10.0
  times: sub/times.txt
ground_truth:
  path: /abs/gt.tum
  format: tum
frame: kitti_camera
anchor:
  lat_deg: 48.98
  lon_deg: 8.39
  yaw_deg: -30.5
map:
  - path: map.osm
  - {path: floors.PCD, role: floorplan, floor_z_m: 3.5}
  - {path: a.bt, lifts: [[50, 17.5, 52, 19.5], [-1, 0, 1.5, 2]]}
  - {path: b.ot, format: octomap}
  - {path: c.json, role: walkways}
  - {path: d.ply}
future_key: {anything: [1, 2]}
)";

TEST(Scenario, LoadsFolderWithDefaultsAndResolvedPaths) {
    const fs::path dir = TestDir() / "my_scenario";
    fs::create_directories(dir);
    WriteText(dir / "scenario.yaml", kGoodScenario);
    const Scenario s = LoadScenario(dir.string());
    const fs::path abs_dir = fs::absolute(dir).lexically_normal();
    EXPECT_EQ(s.name, "tiny");
    EXPECT_EQ(fs::path(s.dir), abs_dir);
    EXPECT_EQ(s.mode, ScenarioMode::kRoad2d);
    EXPECT_EQ(s.estimate.path, (abs_dir / "est.txt").string());
    EXPECT_EQ(s.estimate.format, TrajectoryFormat::kKitti);
    EXPECT_EQ(s.estimate.rate_hz, 10.0);
    EXPECT_EQ(s.estimate.times_path, (abs_dir / "sub" / "times.txt").string());
    ASSERT_TRUE(s.ground_truth.has_value());
    EXPECT_EQ(s.ground_truth->path, "/abs/gt.tum");
    EXPECT_EQ(s.ground_truth->format, TrajectoryFormat::kTum);
    EXPECT_EQ(s.frame, FrameAxes::kKittiCamera);
    EXPECT_TRUE(s.anchor.IsGeographic());
    EXPECT_EQ(s.anchor.alt_m, 0.0);
    EXPECT_DOUBLE_EQ(*s.anchor.yaw_deg, -30.5);
    EXPECT_EQ(s.anchor.z_m, 0.0);
    ASSERT_EQ(s.map.size(), 6u);
    EXPECT_EQ(s.map[0].format, MapFormat::kOsm);
    EXPECT_EQ(s.map[0].role, LayerRole::kNone);
    EXPECT_FALSE(s.map[0].floor_z_m.has_value());
    EXPECT_EQ(s.map[1].format, MapFormat::kPcd);
    EXPECT_EQ(s.map[1].role, LayerRole::kFloorplan);
    EXPECT_EQ(s.map[1].floor_z_m, 3.5);
    EXPECT_EQ(s.map[2].format, MapFormat::kOctomap);
    ASSERT_EQ(s.map[2].lifts.size(), 2u);
    EXPECT_EQ(s.map[2].lifts[0].x0, 50.0);
    EXPECT_EQ(s.map[2].lifts[0].y0, 17.5);
    EXPECT_EQ(s.map[2].lifts[0].x1, 52.0);
    EXPECT_EQ(s.map[2].lifts[0].y1, 19.5);
    EXPECT_EQ(s.map[2].lifts[1].x0, -1.0);
    EXPECT_EQ(s.map[2].lifts[1].y1, 2.0);
    EXPECT_TRUE(s.map[3].lifts.empty());
    EXPECT_EQ(s.map[3].format, MapFormat::kOctomap);
    EXPECT_EQ(s.map[4].format, MapFormat::kGeoJson);
    EXPECT_EQ(s.map[4].role, LayerRole::kWalkways);
    EXPECT_EQ(s.map[5].format, MapFormat::kPly);
    EXPECT_EQ(ToString(s.mode), "road2d");
    EXPECT_EQ(ToString(s.map[2].format), "octomap");
}

TEST(Scenario, LoadsYamlFileAndDefaultsNameToFolder) {
    const fs::path dir = TestDir() / "crs_case";
    fs::create_directories(dir);
    const std::string yaml = WriteText(dir / "other.yml", R"(mode: indoor3d
estimate: {path: e.tum, format: tum}
frame: enu
anchor: {crs: "urn:ogc:def:crs:EPSG::32632", easting_m: 566578.7, northing_m: 5932830.4, z_m: 19.6, yaw_deg: 0}
map: [{path: r.geojson, format: geojson, role: walkways, floor_z_m: 19.6}]
)");
    const Scenario s = LoadScenario(yaml);
    EXPECT_EQ(s.yaml_path, yaml);
    EXPECT_EQ(s.name, "crs_case");
    EXPECT_EQ(s.mode, ScenarioMode::kIndoor3d);
    EXPECT_FALSE(s.ground_truth.has_value());
    EXPECT_EQ(s.frame, FrameAxes::kEnu);
    EXPECT_FALSE(s.anchor.IsGeographic());
    EXPECT_EQ(s.anchor.crs, "urn:ogc:def:crs:EPSG::32632");
    EXPECT_EQ(s.anchor.easting_m, 566578.7);
    EXPECT_EQ(s.anchor.northing_m, 5932830.4);
    EXPECT_EQ(s.anchor.z_m, 19.6);
    EXPECT_EQ(s.anchor.yaw_deg, 0.0);
}

TEST(Scenario, MissingOrWrongPath) {
    const fs::path dir = TestDir();
    ExpectInputError([&] { LoadScenario(dir.string()); }, {"scenario.yaml", "no scenario.yaml"});
    const std::string txt = WriteText(dir / "scenario.txt", "mode: road2d\n");
    ExpectInputError([&] { LoadScenario(txt); }, {txt, ".yaml"});
    const std::string missing = (dir / "nope.yaml").string();
    ExpectInputError([&] { LoadScenario(missing); }, {missing, "no such file"});
    const std::string missing_dir = (dir / "no_folder").string();
    ExpectInputError([&] { LoadScenario(missing_dir); }, {missing_dir, "no such file or folder"});
}

/// Replaces the first occurrence of `from` in `text` (which must be there).
std::string Replace(std::string text, const std::string& from, const std::string& to) {
    const std::size_t pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    if (pos != std::string::npos) text.replace(pos, from.size(), to);
    return text;
}

TEST(Scenario, YawAutoAndPositionSearch) {
    const fs::path dir = TestDir() / "auto_scenario";
    fs::create_directories(dir);
    WriteText(dir / "scenario.yaml", Replace(kGoodScenario, "  yaw_deg: -30.5\n",
                                             "  yaw_deg: AUTO\n  position_search_m: 25\n"));
    const Scenario s = LoadScenario(dir.string());
    EXPECT_FALSE(s.anchor.yaw_deg.has_value());
    EXPECT_EQ(s.anchor.position_search_m, 25.0);
    WriteText(dir / "scenario.yaml", kGoodScenario);
    EXPECT_EQ(LoadScenario(dir.string()).anchor.position_search_m, 0.0);
}

// `scale`: auto, or a number the estimate's positions are multiplied by; absent: metric.
TEST(Scenario, AnchorScale) {
    const fs::path dir = TestDir() / "scale_scenario";
    fs::create_directories(dir);
    WriteText(dir / "scenario.yaml",
              Replace(kGoodScenario, "  yaw_deg: -30.5\n", "  yaw_deg: -30.5\n  scale: Auto\n"));
    Scenario s = LoadScenario(dir.string());
    EXPECT_TRUE(s.anchor.scale_auto);
    EXPECT_TRUE(s.anchor.scale_given);
    WriteText(dir / "scenario.yaml",
              Replace(kGoodScenario, "  yaw_deg: -30.5\n", "  yaw_deg: -30.5\n  scale: 12.5\n"));
    s = LoadScenario(dir.string());
    EXPECT_FALSE(s.anchor.scale_auto);
    EXPECT_TRUE(s.anchor.scale_given);
    EXPECT_EQ(s.anchor.scale, 12.5);
    WriteText(dir / "scenario.yaml", kGoodScenario);
    s = LoadScenario(dir.string());
    EXPECT_FALSE(s.anchor.scale_given || s.anchor.scale_auto);
    EXPECT_EQ(s.anchor.scale, 1.0);
}

// The anchor's ranges, one check for scenario.yaml, --anchor and the Python dict: the first value
// outside its range by its key, a NaN too; nothing for an anchor within every range.
TEST(Scenario, AnchorRangesAreCheckedInOnePlace) {
    AnchorSpec a;
    a.lat_deg = 48.98;
    a.lon_deg = 8.39;
    EXPECT_FALSE(FindAnchorProblem(a).has_value());
    const auto key = [](const AnchorSpec& spec) {
        const std::optional<AnchorProblem> p = FindAnchorProblem(spec);
        return p ? p->key : std::string("none");
    };
    AnchorSpec b = a;
    b.lat_deg = -90.5;
    EXPECT_EQ(key(b), "lat_deg");
    b.lat_deg = std::nan("");
    EXPECT_EQ(key(b), "lat_deg");
    b = a;
    b.lon_deg = 180.01;
    EXPECT_EQ(key(b), "lon_deg");
    b = a;
    b.position_search_m = 1000.5;
    EXPECT_EQ(key(b), "position_search_m");
    AnchorSpec grid;
    grid.crs = "EPSG:32632";
    grid.easting_m = 1.0;
    grid.northing_m = 2.0;
    EXPECT_EQ(key(grid), "none");
    grid.crs = "EPSG:banana";
    EXPECT_EQ(key(grid), "crs");
    EXPECT_NE(FindAnchorProblem(grid)->rule.find("EPSG:banana"), std::string::npos);
}

// A folder where the scenario file should be is bad input naming the path, not a read error.
TEST(Scenario, FolderNamedLikeTheScenarioFileIsAnInputError) {
    const fs::path dir = TestDir() / "folder_yaml";
    fs::create_directories(dir / "scenario.yaml");
    const std::string yaml = (dir / "scenario.yaml").string();
    ExpectInputError([&] { LoadScenario(dir.string()); }, {yaml + ": is a folder, not a file"});
    // Named directly, the folder is taken as a scenario folder, and it has no scenario.yaml.
    ExpectInputError([&] { LoadScenario(yaml); }, {yaml, "has no scenario.yaml"});
}

/// A broken scenario: kGoodScenario with one edit, and what the error must name.
struct BadScenarioCase {
    std::string label;
    std::string from, to;      ///< the edit
    std::string key_fragment;  ///< e.g. ":13: anchor.lat_deg" or ": map" (file:line: key)
};

std::ostream& operator<<(std::ostream& os, const BadScenarioCase& c) { return os << c.label; }

class BadScenario : public ::testing::TestWithParam<BadScenarioCase> {};

TEST_P(BadScenario, ThrowsInputErrorNamingFileLineAndKey) {
    const BadScenarioCase& c = GetParam();
    const fs::path dir = TestDir();
    const std::string yaml = WriteText(dir / "scenario.yaml", Replace(kGoodScenario, c.from, c.to));
    ExpectInputError([&] { LoadScenario(dir.string()); }, {yaml + c.key_fragment});
}

// Line numbers refer to kGoodScenario (line 1: "name: tiny", 13: lat_deg, 17: "  - path: map.osm").
INSTANTIATE_TEST_SUITE_P(
    Io, BadScenario,
    ::testing::Values(
        BadScenarioCase{"missing_mode", "mode: road2d\n", "", ":1: mode: missing"},
        BadScenarioCase{"duplicate_key", "frame: kitti_camera", "frame: enu\nframe: kitti_camera",
                        ":12: frame: key given twice"},
        BadScenarioCase{"misspelled_mode", "mode: road2d", "mdoe: road2d", ":1: mode: missing"},
        BadScenarioCase{"unknown_mode", "road2d", "road3d", ":2: mode: unknown value 'road3d'"},
        BadScenarioCase{"missing_estimate", "estimate:", "estimat:", ":1: estimate: missing"},
        BadScenarioCase{"estimate_not_mapping",
                        "estimate:\n  path: est.txt\n  format: kitti\n"
                        "  rate_hz: 10.0\n  times: sub/times.txt\n",
                        "estimate: est.txt\n", ":3: estimate: must be a mapping"},
        BadScenarioCase{"missing_estimate_path", "  path: est.txt\n", "",
                        ":4: estimate.path: missing"},
        BadScenarioCase{"unknown_estimate_format", "format: kitti", "format: kiti",
                        ":5: estimate.format: unknown value"},
        BadScenarioCase{"kitti_without_rate_or_times", "  rate_hz: 10.0\n  times: sub/times.txt\n",
                        "", ":4: estimate: a kitti trajectory needs rate_hz or times"},
        BadScenarioCase{"rate_not_positive", "rate_hz: 10.0", "rate_hz: -1",
                        ":6: estimate.rate_hz: must be positive"},
        BadScenarioCase{"rate_not_number", "rate_hz: 10.0", "rate_hz: ten",
                        ":6: estimate.rate_hz: 'ten' is not a number"},
        BadScenarioCase{"rate_with_tum", "format: tum", "format: tum\n  rate_hz: 5",
                        ":11: ground_truth.rate_hz: only valid"},
        BadScenarioCase{"gt_kitti_without_rate", "format: tum", "format: kitti",
                        ":9: ground_truth: a kitti trajectory needs"},
        BadScenarioCase{"missing_frame", "frame: kitti_camera\n", "", ":1: frame: missing"},
        BadScenarioCase{"unknown_frame", "kitti_camera", "camera", ":11: frame: unknown value"},
        BadScenarioCase{"missing_anchor", "anchor:", "anchr:", ":1: anchor: missing"},
        BadScenarioCase{"anchor_both_kinds", "  yaw_deg: -30.5\n",
                        "  crs: EPSG:32632\n  easting_m: 1\n  northing_m: 2\n",
                        ":13: anchor: give either"},
        BadScenarioCase{"anchor_neither", "  lat_deg: 48.98\n  lon_deg: 8.39\n", "",
                        ":13: anchor: needs lat_deg"},
        BadScenarioCase{"anchor_lat_without_lon", "  lon_deg: 8.39\n", "",
                        ":13: anchor.lon_deg: missing"},
        BadScenarioCase{"lat_not_number", "48.98", "48.98abc",
                        ":13: anchor.lat_deg: '48.98abc' is not a number"},
        BadScenarioCase{"lat_nan", "48.98", ".nan", ":13: anchor.lat_deg: '.nan' is not a finite"},
        BadScenarioCase{"lat_nan_word", "48.98", "nan",
                        ":13: anchor.lat_deg: 'nan' is not a finite"},
        BadScenarioCase{"lon_inf", "8.39", "inf", ":14: anchor.lon_deg: 'inf' is not a finite"},
        BadScenarioCase{"lat_out_of_range", "48.98", "98.4", ":13: anchor.lat_deg: must be within"},
        BadScenarioCase{"lat_is_list", "48.98", "[1, 2]", ":13: anchor.lat_deg: must be a single"},
        BadScenarioCase{"yaw_garbage", "-30.5", "-30.5deg", ":15: anchor.yaw_deg"},
        BadScenarioCase{"yaw_missing", "  yaw_deg: -30.5\n", "",
                        ":13: anchor.yaw_deg: missing required key"},
        BadScenarioCase{"yaw_null", "  yaw_deg: -30.5\n", "  yaw_deg:\n",
                        ":13: anchor.yaw_deg: missing required key"},
        BadScenarioCase{"indoor_without_z", "mode: road2d", "mode: indoor3d",
                        ":13: anchor.z_m: missing required key in indoor3d mode"},
        BadScenarioCase{"position_search_negative", "  yaw_deg: -30.5\n",
                        "  yaw_deg: -30.5\n  position_search_m: -5\n",
                        ":16: anchor.position_search_m: must be within"},
        BadScenarioCase{"scale_zero", "  yaw_deg: -30.5\n", "  yaw_deg: -30.5\n  scale: 0\n",
                        ":16: anchor.scale: must be auto or a number in (0, 1e6)"},
        BadScenarioCase{"scale_word", "  yaw_deg: -30.5\n", "  yaw_deg: -30.5\n  scale: mono\n",
                        ":16: anchor.scale: must be auto or a number"},
        BadScenarioCase{"bad_crs", "  lat_deg: 48.98\n  lon_deg: 8.39\n",
                        "  crs: WGS84\n  easting_m: 1\n  northing_m: 2\n",
                        ":13: anchor.crs: unknown CRS"},
        BadScenarioCase{"missing_map", "map:", "maps:", ":1: map: missing"},
        BadScenarioCase{"empty_map", "map:", "map: []\nold_map:", ":16: map: must list at least"},
        BadScenarioCase{"map_not_list",
                        "map:", "map: map.osm\nold_map:", ":16: map: must be a list"},
        BadScenarioCase{"map_unknown_format", "{path: b.ot, format: octomap}",
                        "{path: b.ot, format: voxels}",
                        ":20: map[3].format: unknown value 'voxels'"},
        BadScenarioCase{"map_format_not_inferable", "{path: a.bt,", "{path: a.xyz,",
                        ":19: map[2].format: missing, and the extension"},
        BadScenarioCase{"map_missing_path", "{path: a.bt,", "{format: bt,", ":19: map[2].path"},
        BadScenarioCase{"lifts_on_a_plan", "role: walkways",
                        "role: walkways, lifts: [[0, 0, 1, 1]]",
                        ":21: map[4].lifts: only valid on a point-cloud or OctoMap layer"},
        BadScenarioCase{"lifts_not_a_list", "lifts: [[50, 17.5, 52, 19.5], [-1, 0, 1.5, 2]]",
                        "lifts: 5", ":19: map[2].lifts: must be a list of lists of 4 numbers"},
        BadScenarioCase{"lift_of_three_numbers", "[-1, 0, 1.5, 2]", "[-1, 0, 1.5]",
                        ":19: map[2].lifts: must be a list of lists of 4 numbers (lifts[1])"},
        BadScenarioCase{"lift_not_a_number", "[-1, 0, 1.5, 2]", "[-1, 0, 1.5, high]",
                        ":19: map[2].lifts[1]: 'high' is not a number"},
        BadScenarioCase{"lift_inf", "[-1, 0, 1.5, 2]", "[-1, 0, .inf, 2]",
                        ":19: map[2].lifts[1]: '.inf' is not a finite number"},
        BadScenarioCase{"lift_empty_footprint", "[-1, 0, 1.5, 2]", "[1.5, 0, -1, 2]",
                        ":19: map[2].lifts: a shaft [x0, y0, x1, y1] needs x1 > x0"},
        BadScenarioCase{"map_unknown_role", "role: walkways", "role: walls",
                        ":21: map[4].role: unknown value"},
        BadScenarioCase{"map_floor_not_number", "floor_z_m: 3.5", "floor_z_m: high",
                        ":18: map[1].floor_z_m"},
        BadScenarioCase{"map_entry_not_mapping", "  - {path: d.ply}", "  - d.ply",
                        ":22: map[5]: must be a mapping"},
        BadScenarioCase{"yaml_syntax_error", "  yaw_deg: -30.5", "  yaw_deg: [-30.5",
                        ":16: YAML error"}),
    [](const ::testing::TestParamInfo<BadScenarioCase>& p) { return p.param.label; });

TEST(Scenario, EmptyOrScalarDocument) {
    const fs::path dir = TestDir();
    const std::string yaml = WriteText(dir / "scenario.yaml", "");
    ExpectInputError([&] { LoadScenario(yaml); }, {yaml, "must be a mapping"});
    WriteText(dir / "scenario.yaml", "just a string\n");
    ExpectInputError([&] { LoadScenario(yaml); }, {yaml + ":1:", "must be a mapping"});
}

// ---------------------------------------------------------------------------------------------
// The real scenarios of ../shared/datasets

struct RealScenarioCase {
    std::string folder;
    std::size_t poses;
};

std::ostream& operator<<(std::ostream& os, const RealScenarioCase& c) { return os << c.folder; }

class RealScenario : public ::testing::TestWithParam<RealScenarioCase> {};

TEST_P(RealScenario, LoadsEstimateAndGroundTruth) {
    const RealScenarioCase& c = GetParam();
    const fs::path dir = fs::path(DRIFTCORR_SHARED_DATASETS) / c.folder;
    if (!fs::exists(dir / "scenario.yaml")) {
        GTEST_SKIP() << "real data set not available: " << dir;
    }
    const Scenario s = LoadScenario(dir.string());
    EXPECT_FALSE(s.name.empty());
    ASSERT_FALSE(s.map.empty());
    for (const MapLayerSpec& layer : s.map) EXPECT_TRUE(fs::exists(layer.path)) << layer.path;
    const Trajectory estimate = LoadTrajectory(s.estimate);
    ASSERT_TRUE(s.ground_truth.has_value());
    const Trajectory truth = LoadTrajectory(*s.ground_truth);
    EXPECT_EQ(estimate.size(), c.poses);
    EXPECT_EQ(truth.size(), c.poses);
    EXPECT_TRUE(estimate.HasOrientation());
    ASSERT_EQ(estimate.size(), truth.size());
    for (std::size_t i = 0; i < estimate.size(); ++i) {
        ASSERT_NEAR(estimate.t_s[i], truth.t_s[i], 1e-3) << "pose " << i;
    }
}

INSTANTIATE_TEST_SUITE_P(Io, RealScenario,
                         ::testing::Values(RealScenarioCase{"kitti00_cvo_stereo_geometric", 4541},
                                           RealScenarioCase{"kitti00_gicp_frame2frame", 4541},
                                           RealScenarioCase{"kitti00_orb2_longruidong", 4541},
                                           RealScenarioCase{"kitti05_cvo_stereo_geometric", 2761},
                                           RealScenarioCase{"kitti05_gicp_frame2frame", 2761},
                                           RealScenarioCase{"kitti07_cvo_stereo_geometric", 1101},
                                           RealScenarioCase{"kitti07_gicp_frame2frame", 1101},
                                           RealScenarioCase{"hcu_eight", 220}),
                         [](const ::testing::TestParamInfo<RealScenarioCase>& p) {
                             return p.param.folder;
                         });

TEST(RealScenarioDetails, Kitti00UsesTimesFileAndHcuUsesCrsAnchor) {
    const fs::path root(DRIFTCORR_SHARED_DATASETS);
    if (!fs::exists(root / "kitti00_cvo_stereo_geometric") || !fs::exists(root / "hcu_eight")) {
        GTEST_SKIP() << "real data sets not available under " << root;
    }
    const Scenario kitti = LoadScenario((root / "kitti00_cvo_stereo_geometric").string());
    ASSERT_TRUE(kitti.estimate.times_path.has_value());
    const Trajectory est = LoadTrajectory(kitti.estimate);
    EXPECT_DOUBLE_EQ(est.t_s[1], 0.1037359);
    EXPECT_EQ(kitti.frame, FrameAxes::kKittiCamera);
    EXPECT_NEAR(*kitti.anchor.lat_deg, 48.9825452359, 1e-12);
    const Scenario hcu = LoadScenario((root / "hcu_eight").string());
    EXPECT_EQ(hcu.mode, ScenarioMode::kIndoor3d);
    EXPECT_EQ(hcu.anchor.crs, "EPSG:32632");
    EXPECT_EQ(hcu.anchor.z_m, 19.6);
    ASSERT_EQ(hcu.map.size(), 6u);
    EXPECT_EQ(hcu.map[1].role, LayerRole::kFloorplan);
    EXPECT_EQ(hcu.map[5].floor_z_m, 19.6);
}

// ---------------------------------------------------------------------------------------------
// Bounded text files

TEST(TextFile, SecondYamlDocumentIsFoundWithItsLine) {
    EXPECT_EQ(SecondYamlDocumentLine("a: 1\nb: 2\n"), std::nullopt);
    EXPECT_EQ(SecondYamlDocumentLine("---\na: 1\n...\n"), std::nullopt);
    EXPECT_EQ(SecondYamlDocumentLine("# c\n---\na: 1\n"), std::nullopt);
    EXPECT_EQ(SecondYamlDocumentLine("a: 1\n---\nb: 2\n"), 2);
    EXPECT_EQ(SecondYamlDocumentLine("---\na: 1\n--- \nb: 2\n"), 3);
    EXPECT_EQ(SecondYamlDocumentLine("a: 1\n...\nb: 2\n"), 3);
    EXPECT_EQ(SecondYamlDocumentLine("a: \"---\"\nb: ---x\n"), std::nullopt);
}

TEST(TextFile, ReadsWithinItsBoundsAndNamesTheLineBeyond) {
    const fs::path dir = TestDir();
    WriteText(dir / "ok.txt", "one\ntwo\n");
    EXPECT_EQ(ReadTextFile((dir / "ok.txt").string(), {100, 10, "a test file"}), "one\ntwo\n");
    WriteText(dir / "long.txt", "one\n" + std::string(11, 'x') + "\n");
    try {
        ReadTextFile((dir / "long.txt").string(), {100, 10, "a test file"});
        ADD_FAILURE() << "no exception";
    } catch (const InputError& e) {
        EXPECT_EQ(e.line(), 2);
    }
    EXPECT_THROW(ReadTextFile((dir / "ok.txt").string(), {5, 10, "a test file"}), InputError);
    EXPECT_THROW(ReadTextFile(dir.string(), {100, 10, "a test file"}), InputError);
}

// ---------------------------------------------------------------------------------------------
// AtomicFile

std::size_t CountFiles(const fs::path& dir) {
    std::size_t n = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
    return n;
}

TEST(AtomicFile, LeavesNothingWhenNotCommitted) {
    const fs::path dir = TestDir();
    const fs::path path = dir / "out.txt";
    {
        AtomicFile file(path.string());
        file.stream() << "partial";
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_EQ(CountFiles(dir), 0u);
}

TEST(AtomicFile, DoesNotClobberExistingFileUntilCommit) {
    const fs::path dir = TestDir();
    const fs::path path = dir / "out.txt";
    WriteText(path, "old");
    {
        AtomicFile file(path.string());
        file.stream() << "new";
        EXPECT_EQ(ReadText(path), "old");
    }
    EXPECT_EQ(ReadText(path), "old");
    EXPECT_EQ(CountFiles(dir), 1u);
    {
        AtomicFile file(path.string());
        file.stream() << "new";
        file.Commit();
    }
    EXPECT_EQ(ReadText(path), "new");
    EXPECT_EQ(CountFiles(dir), 1u);
}

TEST(AtomicFile, FollowsASymbolicLinkAndKeepsIt) {
    const fs::path dir = TestDir();
    WriteText(dir / "target.txt", "old");
    fs::create_symlink(dir / "target.txt", dir / "link.txt");
    WriteFileAtomically((dir / "link.txt").string(), "new");
    EXPECT_TRUE(fs::is_symlink(dir / "link.txt"));
    EXPECT_EQ(ReadText(dir / "target.txt"), "new");
    EXPECT_EQ(CountFiles(dir), 2u);
}

TEST(AtomicFile, ResolvesWhatMustNotBeReplaced) {
    const fs::path dir = TestDir();
    EXPECT_EQ(ResolveOutput("/dev/null").kind, OutputTarget::Kind::kInPlace);
    EXPECT_EQ(ResolveOutput("-").kind, OutputTarget::Kind::kDescriptor);
    EXPECT_EQ(ResolveOutput((dir / "new.txt").string()).kind, OutputTarget::Kind::kFile);
    EXPECT_THROW(ResolveOutput(dir.string()), OutputError);  // a folder
    fs::create_symlink(dir / "missing.txt", dir / "dangling.txt");
    EXPECT_THROW(ResolveOutput((dir / "dangling.txt").string()), OutputError);
    WriteFileAtomically("/dev/null", "into the device, in place");
    struct stat st {};
    ASSERT_EQ(::stat("/dev/null", &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
}

TEST(AtomicFile, UnwritableFolderThrowsNamingPath) {
    const std::string path = (TestDir() / "no_such_folder" / "out.tum").string();
    try {
        WriteTum(path, SmallTrajectory());
        ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
}

// ---------------------------------------------------------------------------------------------
// GeoJSON

TEST(GeoJson, WritesFeatureCollectionThatParsesBack) {
    const fs::path dir = TestDir();
    const std::string path = (dir / "tracks.geojson").string();
    const std::vector<GeoTrack> tracks = {
        {"estimate", {{48.9825452359, 8.39036610, 116.0}, {48.98260000, 8.39040000, 116.0}}, {}},
        {"corr\"ected\\", {{-33.5, -70.25, 0.0}, {-33.6, -70.35, 0.0}, {-33.7, -70.45, 0.0}}, {}},
        {"single", {{1.0, 2.0, 0.0}}, {}},
    };
    WriteGeoJsonTracks(path, tracks);
    const std::string text = ReadText(path);
    EXPECT_EQ(text.rfind("{\"type\":\"FeatureCollection\",\"features\":[", 0), 0u);
    EXPECT_NE(text.find("\"properties\":{\"name\":\"estimate\"}"), std::string::npos);
    EXPECT_NE(text.find("\"name\":\"corr\\\"ected\\\\\""), std::string::npos);
    EXPECT_NE(text.find("\"coordinates\":[[8.39036610,48.98254524],[8.39040000,48.98260000]]"),
              std::string::npos);
    EXPECT_NE(text.find("[-70.45000000,-33.70000000]]"), std::string::npos);
    EXPECT_NE(text.find("{\"type\":\"Point\",\"coordinates\":[2.00000000,1.00000000]}"),
              std::string::npos);
#ifdef DRIFTCORR_TEST_HAS_JSON
    const nlohmann::json json = nlohmann::json::parse(text);
    ASSERT_EQ(json["features"].size(), 3u);
    EXPECT_EQ(json["features"][1]["properties"]["name"], "corr\"ected\\");
    EXPECT_EQ(json["features"][1]["geometry"]["type"], "LineString");
    EXPECT_DOUBLE_EQ(json["features"][1]["geometry"]["coordinates"][2][0].get<double>(), -70.45);
#endif
}

TEST(GeoJson, NonFiniteCoordinateWritesNothing) {
    const fs::path dir = TestDir();
    const fs::path path = dir / "tracks.geojson";
    const std::vector<GeoTrack> tracks = {{"bad", {{1.0, 2.0, 0.0}, {NAN, 2.0, 0.0}}, {}}};
    EXPECT_THROW(WriteGeoJsonTracks(path.string(), tracks), std::runtime_error);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_EQ(CountFiles(dir), 0u);
}

}  // namespace
}  // namespace driftcorr::io

namespace {

// A misspelt optional key is not fatal (docs/FORMAT.md allows extensions) but must be reported.
TEST(ScenarioWarnings, UnknownKeysAreReportedWithLine) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / ("warn_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "scenario.yaml") << "mode: road2d\n"
                                            "estimate: {path: e.tum, format: tum}\n"
                                            "frame: enu\n"
                                            "anchor:\n"
                                            "  lat_deg: 48.9\n"
                                            "  lon_deg: 8.3\n"
                                            "  alt_n: 116\n"
                                            "  yaw_deg: 30\n"
                                            "map:\n"
                                            "  - {path: map.osm, format: osm, widht: 3}\n"
                                            "colour: blue\n";
    const driftcorr::io::Scenario s = driftcorr::io::LoadScenario(dir.string());
    ASSERT_EQ(s.warnings.size(), 3u);
    EXPECT_NE(s.warnings[0].find("scenario.yaml:11: colour: unknown key"), std::string::npos)
        << s.warnings[0];
    EXPECT_NE(s.warnings[1].find("scenario.yaml:7: anchor.alt_n: unknown key"), std::string::npos)
        << s.warnings[1];
    EXPECT_NE(s.warnings[2].find("map[0].widht: unknown key"), std::string::npos) << s.warnings[2];
    fs::remove_all(dir);
}

}  // namespace

namespace driftcorr::io {
namespace {

// ---------------------------------------------------------------------------------------------
// Positions-only TUM, CSV and EuRoC / ASL

TEST(TrajectoryFormats, TumWithPositionsOnlyHasNoOrientation) {
    const fs::path dir = TestDir();
    const std::string path =
        WriteText(dir / "p.tum", "# t x y z\n0 0 0 0\n0.1 1 0 0\n0.2 2 0.5 0\n");
    const Trajectory traj = ReadTum(path);
    ASSERT_EQ(traj.size(), 3u);
    EXPECT_FALSE(traj.HasOrientation());
    EXPECT_EQ(traj.p_frame[2], Eigen::Vector3d(2, 0.5, 0));
    // The first data line decides: a later 8-field line is an error naming its line.
    const std::string mixed = WriteText(dir / "m.tum", "0 0 0 0\n0.1 1 0 0 0 0 0 1\n0.2 2 0 0\n");
    ExpectInputError([&] { ReadTum(mixed); }, {mixed + ":2: expected 4 numbers, found 8"});
}

TEST(TrajectoryFormats, EurocStateGroundtruthLayout) {
    const fs::path dir = TestDir();
    // The layout of EuRoC's state_groundtruth_estimate0/data.csv (velocities and biases ignored).
    const std::string path = WriteText(
        dir / "data.csv",
        "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
        "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad "
        "s^-1]\n"
        "1403636579763555584,4.688319,-1.786938,0.783338,0.534108,-0.153029,-0.827383,-0.082152,"
        "-0.027876,0.033207,0.800006,-0.003172\n"
        "1403636579768555520,4.688177,-1.786770,0.787350,0.534640,-0.152990,-0.826976,-0.082863,"
        "-0.029272,0.033992,0.804771,-0.003172\n"
        "1403636579773555456,4.688028,-1.786598,0.791382,0.535178,-0.152945,-0.826562,-0.083605,"
        "-0.030043,0.035215,0.808962,-0.003172\n");
    EXPECT_EQ(DetectTrajectoryFormat(path), TrajectoryFormat::kEuroc);
    const Trajectory traj = ReadCsv(path, true);
    ASSERT_EQ(traj.size(), 3u);
    ASSERT_TRUE(traj.HasOrientation());
    // Nanoseconds to seconds without losing the sub-microsecond digits to a 19-digit double.
    EXPECT_DOUBLE_EQ(traj.t_s[0], 1403636579.0 + 0.763555584);
    EXPECT_NEAR(traj.t_s[1] - traj.t_s[0], 0.004999936, 1e-6);  // a double of ~1.4e9 s
    EXPECT_EQ(traj.p_frame[0], Eigen::Vector3d(4.688319, -1.786938, 0.783338));
    const Eigen::Quaterniond q0 = traj.q_frame_body[0];  // file order w x y z
    EXPECT_NEAR(q0.w(), 0.534108, 1e-5);
    EXPECT_NEAR(q0.x(), -0.153029, 1e-5);
    EXPECT_NEAR(q0.z(), -0.082152, 1e-5);
}

TEST(TrajectoryFormats, EurocPositionsOnlyAndPlainCsv) {
    const fs::path dir = TestDir();
    const std::string leica = WriteText(dir / "leica.csv",
                                        "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m]\n"
                                        "1000000000,0,0,0\n1100000000,1,0,0\n1200000000,2,0,0\n");
    const Trajectory l = ReadCsv(leica, false);
    EXPECT_FALSE(l.HasOrientation());
    EXPECT_DOUBLE_EQ(l.t_s[2], 1.2);
    // Plain CSV: any column order, units in brackets, extra columns ignored.
    const std::string plain =
        WriteText(dir / "plain.csv",
                  "x [m], y [m], z [m], speed, t [s], qx, qy, qz, qw\n"
                  "0,0,0,1,0.0,0,0,0,2\n1,0,0,1,0.5,0,0,0,1\n2,1,0,1,1.0,0,0,1,1\n");
    EXPECT_EQ(DetectTrajectoryFormat(plain), TrajectoryFormat::kCsv);
    const Trajectory p = ReadCsv(plain, false);
    ASSERT_EQ(p.size(), 3u);
    EXPECT_DOUBLE_EQ(p.t_s[1], 0.5);
    EXPECT_EQ(p.p_frame[2], Eigen::Vector3d(2, 1, 0));
    EXPECT_NEAR(p.q_frame_body[0].w(), 1.0, 1e-12);  // normalised
    const std::string ns =
        WriteText(dir / "ns.csv", "timestamp_ns,tx,ty,tz\n5,0,0,0\n10,1,0,0\n15,2,0,0\n");
    EXPECT_DOUBLE_EQ(ReadCsv(ns, false).t_s[2], 15e-9);
}

TEST(TrajectoryFormats, BadCsvNamesFileLineAndColumn) {
    const fs::path dir = TestDir();
    const auto bad = [&](const std::string& name, const std::string& text, bool euroc,
                         const std::string& fragment) {
        const std::string path = WriteText(dir / name, text);
        ExpectInputError([&] { ReadCsv(path, euroc); }, {path + fragment});
    };
    bad("no_time.csv", "x,y,z\n1,2,3\n", false, ":1: header has no time column");
    bad("no_z.csv", "t,x,y\n1,2,3\n", false, ":1: header has no position column 'z'");
    bad("half_q.csv", "t,x,y,z,qw\n0,0,0,0,1\n", false, ":1: header names some quaternion");
    bad("not_euroc.csv", "t,x,y,z\n0,0,0,0\n", true, ":1: is not an EuRoC / ASL file");
    bad("short_line.csv", "t,x,y,z\n0,0,0,0\n1,1,0\n2,2,0,0\n", false,
        ":3: expected 4 comma-separated fields");
    bad("not_number.csv", "t,x,y,z\n0,0,0,0\n1,1,abc,0\n2,2,0,0\n", false, ":3: field 3 'abc'");
    bad("decreasing.csv", "t,x,y,z\n0,0,0,0\n2,1,0,0\n1,2,0,0\n", false, ":4: timestamp 1");
    bad("bad_unit.csv", "t [ms],x,y,z\n0,0,0,0\n", false, ":1: t: time unit 'ms'");
    bad("empty.csv", "\n\n", false, ": empty file");
    bad("header_only.csv", "t,x,y,z\n", false, ": has 0 poses");
}

TEST(TrajectoryFormats, ScenarioKeysForFormatsAndHeading) {
    const fs::path dir = TestDir();
    const std::string yaml = WriteText(dir / "scenario.yaml", R"(mode: road2d
estimate: {path: traj.csv, format: euroc, heading: motion}
frame: enu
anchor: {lat_deg: 48.98, lon_deg: 8.39, yaw_deg: 0}
map: [{path: map.osm.pbf}]
)");
    const Scenario s = LoadScenario(yaml);
    EXPECT_EQ(s.estimate.format, TrajectoryFormat::kEuroc);
    EXPECT_TRUE(s.estimate.heading_from_motion);
    EXPECT_EQ(s.map.front().format, MapFormat::kOsm);  // .pbf: OSM, read by content
    WriteText(dir / "scenario.yaml", R"(mode: road2d
estimate: {path: traj.csv, format: csv, heading: sideways}
frame: enu
anchor: {lat_deg: 48.98, lon_deg: 8.39, yaw_deg: 0}
map: [{path: map.osm}]
)");
    ExpectInputError([&] { LoadScenario(yaml); },
                     {yaml + ":2: estimate.heading: unknown value 'sideways'"});
}

}  // namespace
}  // namespace driftcorr::io
