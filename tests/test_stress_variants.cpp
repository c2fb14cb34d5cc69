// Tests of the stress generator (datasets/stress, driftcorr_make_stress_variants) on the real
// KITTI 07 scenario: every variant is a complete scenario; clean is a faithful copy; the anchor
// faults keep the ground truth where it truly is in the world (through the io library and
// ToPlanar, to 1e-6 m); drop_steps shortens exactly the documented episodes; heading_bias turns
// the heading at the bias rate; road_removed removes exactly the way the ground truth drives
// along the longest. The generator is run as a program; it must be built before this test
// (add_dependencies(test_stress_variants driftcorr_make_stress_variants)).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/frames.h"
#include "driftcorr/io/scenario.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/mapping/geodesy.h"
#include "driftcorr/mapping/osm_reader.h"
#include "test_support.h"

namespace {

namespace fs = std::filesystem;
using namespace driftcorr;

const std::string kGenerator = DRIFTCORR_BINARY_DIR "/datasets/driftcorr_make_stress_variants";
const fs::path kInput = fs::path(DRIFTCORR_SHARED_DATASETS) / "kitti07_cvo_stereo_geometric";
const fs::path kIndoorInput = fs::path(DRIFTCORR_SHARED_DATASETS) / "hcu_eight";

const std::vector<std::string> kVariants = {
    "clean",      "drop_steps", "heading_bias_0.1", "heading_bias_0.3", "heading_bias_0.5",
    "yaw_off_10", "yaw_off_20", "yaw_off_30",       "anchor_off_20m",   "road_removed"};

// The ground truth placed with the variant's anchor must land on the input's ground truth placed
// with the input's anchor: KITTI files are written with 13 significant digits, so 1e-6 m is far
// above the rounding (~1e-10 m) and far below any real error.
constexpr double kInPlaceTolerance_m = 1e-6;
constexpr double kStepTolerance_m = 1e-6;
constexpr double kRotationTolerance_rad = 1e-9;
constexpr double kRoadRadius_m = 5.0;  // documented in datasets/README.md

/// Runs the generator; stdout and stderr go to `log`. Returns the exit code (-1: no normal exit).
int RunGenerator(const std::string& args, const fs::path& log) {
    const std::string command =
        "\"" + kGenerator + "\" " + args + " > \"" + log.string() + "\" 2>&1";
    const int status = std::system(command.c_str());
    return (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
}

std::string Quote(const fs::path& p) { return "\"" + p.string() + "\""; }

std::string ReadBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// The header comment lines of a scenario.yaml that start with `prefix` (after "# ").
std::vector<std::string> HeaderLines(const fs::path& yaml, const std::string& prefix) {
    std::ifstream in(yaml);
    std::vector<std::string> found;
    for (std::string line; std::getline(in, line) && !line.empty() && line[0] == '#';) {
        if (line.rfind("# " + prefix, 0) == 0) found.push_back(line.substr(2 + prefix.size()));
    }
    return found;
}

struct Loaded {
    io::Scenario scenario;
    Trajectory estimate;
    Trajectory ground_truth;
    PlanarAnchor anchor;
};

Loaded Load(const fs::path& dir) {
    Loaded l;
    l.scenario = io::LoadScenario(dir.string());
    l.estimate = io::LoadTrajectory(l.scenario.estimate);
    l.ground_truth = io::LoadTrajectory(*l.scenario.ground_truth);
    l.anchor.yaw_rad = DegToRad(l.scenario.anchor.yaw_deg.value());
    return l;
}

GeoPoint AnchorOrigin(const io::AnchorSpec& a) {
    return {*a.lat_deg, *a.lon_deg, a.alt_m.value_or(0.0)};
}

/// `traj` (a trajectory of `l`) placed with l's anchor, in the East-North plane of `reference`'s
/// anchor (both lat/lon anchors): through WGS84, as the anchors differ.
std::vector<Eigen::Vector2d> InPlaneOf(const Trajectory& traj, const Loaded& l,
                                       const Loaded& reference) {
    const PlanarTrajectory planar = ToPlanar(traj, l.scenario.frame, l.anchor);
    const LocalTangentPlane own(AnchorOrigin(l.scenario.anchor));
    const LocalTangentPlane ref(AnchorOrigin(reference.scenario.anchor));
    std::vector<Eigen::Vector2d> en;
    for (std::size_t i = 0; i < planar.size(); ++i) {
        const Eigen::Vector3d enu(planar.p_en[i].x(), planar.p_en[i].y(), planar.up_m[i]);
        en.push_back(ref.ToEnu(own.ToGeo(enu)).head<2>());
    }
    return en;
}

double MaxDistance(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
    EXPECT_EQ(a.size(), b.size());
    double max_m = 0.0;
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
        max_m = std::max(max_m, (a[i] - b[i]).norm());
    }
    return max_m;
}

class StressVariantsTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        root_ = test::FreshProcessDir("stress_variants");
        exit_ = RunGenerator(Quote(kInput) + " " + Quote(root_ / "k07"), root_ / "k07.log");
    }
    static void TearDownTestSuite() { fs::remove_all(root_); }

    void SetUp() override {
        ASSERT_TRUE(fs::exists(kGenerator)) << kGenerator << " is not built";
        ASSERT_TRUE(fs::exists(kInput / "scenario.yaml")) << kInput << " is missing";
        ASSERT_EQ(exit_, 0) << ReadBytes(root_ / "k07.log");
    }

    static fs::path Variant(const std::string& name) { return root_ / "k07" / name; }

    static inline fs::path root_;
    static inline int exit_ = -1;
};

TEST_F(StressVariantsTest, EveryVariantIsACompleteScenarioInItsFolder) {
    const Loaded input = Load(kInput);
    for (const std::string& name : kVariants) {
        SCOPED_TRACE(name);
        const fs::path dir = Variant(name);
        ASSERT_TRUE(fs::is_regular_file(dir / "scenario.yaml"));
        const Loaded v = Load(dir);
        EXPECT_EQ(v.scenario.name, input.scenario.name + "/" + name);
        EXPECT_TRUE(v.scenario.warnings.empty());
        std::vector<std::string> files = {v.scenario.estimate.path, v.scenario.ground_truth->path};
        for (const io::MapLayerSpec& layer : v.scenario.map) files.push_back(layer.path);
        for (const std::string& file : files) {
            EXPECT_EQ(fs::path(file).parent_path(), fs::absolute(dir).lexically_normal()) << file;
            EXPECT_TRUE(fs::is_regular_file(file)) << file;
        }
        EXPECT_EQ(v.estimate.size(), input.estimate.size());
        EXPECT_EQ(v.ground_truth.size(), input.ground_truth.size());
        EXPECT_EQ(v.estimate.t_s, input.estimate.t_s);
        const std::string first_line = ReadBytes(dir / "scenario.yaml").substr(0, 46);
        EXPECT_EQ(first_line, "# Generated by driftcorr_make_stress_variants ");
        ASSERT_EQ(HeaderLines(dir / "scenario.yaml", "variant: ").size(), 1u);
        EXPECT_EQ(HeaderLines(dir / "scenario.yaml", "variant: ")[0].rfind(name + ";", 0), 0u);
        ASSERT_EQ(HeaderLines(dir / "scenario.yaml", "input: ").size(), 1u);
        for (const auto& entry : fs::directory_iterator(dir)) {
            EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
        }
    }
}

TEST_F(StressVariantsTest, CleanIsAFaithfulCopy) {
    const Loaded input = Load(kInput);
    const Loaded clean = Load(Variant("clean"));
    for (const char* file : {"estimate.txt", "ground_truth.txt", "map.osm"}) {
        EXPECT_TRUE(ReadBytes(kInput / file) == ReadBytes(Variant("clean") / file)) << file;
    }
    const io::AnchorSpec &a = input.scenario.anchor, &b = clean.scenario.anchor;
    EXPECT_EQ(*a.lat_deg, *b.lat_deg);
    EXPECT_EQ(*a.lon_deg, *b.lon_deg);
    EXPECT_EQ(*a.alt_m, *b.alt_m);
    EXPECT_EQ(a.yaw_deg, b.yaw_deg);
    EXPECT_EQ(input.scenario.frame, clean.scenario.frame);
    EXPECT_EQ(input.scenario.mode, clean.scenario.mode);
    EXPECT_EQ(*input.scenario.estimate.rate_hz, *clean.scenario.estimate.rate_hz);
}

TEST_F(StressVariantsTest, YawOffsetKeepsTheGroundTruthInItsPlaceInTheWorld) {
    const Loaded input = Load(kInput);
    const PlanarTrajectory gt_world =
        ToPlanar(input.ground_truth, input.scenario.frame, input.anchor);
    const PlanarTrajectory est_world = ToPlanar(input.estimate, input.scenario.frame, input.anchor);
    for (const double offset_deg : {10.0, 20.0, 30.0}) {
        const std::string name = "yaw_off_" + std::to_string(static_cast<int>(offset_deg));
        SCOPED_TRACE(name);
        const Loaded v = Load(Variant(name));
        EXPECT_NEAR(v.scenario.anchor.yaw_deg.value(),
                    input.scenario.anchor.yaw_deg.value() + offset_deg, 1e-9);
        EXPECT_EQ(*v.scenario.anchor.lat_deg, *input.scenario.anchor.lat_deg);
        EXPECT_EQ(*v.scenario.anchor.lon_deg, *input.scenario.anchor.lon_deg);
        EXPECT_TRUE(ReadBytes(kInput / "estimate.txt") ==
                    ReadBytes(Variant(name) / "estimate.txt"));
        const PlanarTrajectory gt_v = ToPlanar(v.ground_truth, v.scenario.frame, v.anchor);
        EXPECT_LT(MaxDistance(gt_v.p_en, gt_world.p_en), kInPlaceTolerance_m);
        for (std::size_t i = 0; i < gt_v.size(); ++i) {
            ASSERT_NEAR(AngleDiff(gt_v.yaw_rad[i], gt_world.yaw_rad[i]), 0.0, 1e-9) << i;
        }
        // The estimate, unchanged, is placed with the wrong yaw: its last pose moves by
        // 2 |p| sin(D / 2).
        const PlanarTrajectory est_v = ToPlanar(v.estimate, v.scenario.frame, v.anchor);
        const double expected_m =
            2.0 * est_world.p_en.back().norm() * std::sin(DegToRad(offset_deg) / 2);
        EXPECT_NEAR((est_v.p_en.back() - est_world.p_en.back()).norm(), expected_m, 1e-6);
    }
}

TEST_F(StressVariantsTest, AnchorOffsetKeepsTheGroundTruthInItsPlaceInTheWorld) {
    const Loaded input = Load(kInput);
    const Loaded v = Load(Variant("anchor_off_20m"));
    // The new origin lies 20 m from the old one (in the old anchor's plane, at the anchor height).
    const LocalTangentPlane old_plane(AnchorOrigin(input.scenario.anchor));
    const Eigen::Vector3d moved = old_plane.ToEnu(AnchorOrigin(v.scenario.anchor));
    EXPECT_NEAR(moved.head<2>().norm(), 20.0, 1e-6);
    EXPECT_EQ(v.scenario.anchor.yaw_deg, input.scenario.anchor.yaw_deg);
    EXPECT_EQ(*v.scenario.anchor.alt_m, *input.scenario.anchor.alt_m);
    EXPECT_TRUE(ReadBytes(kInput / "estimate.txt") ==
                ReadBytes(Variant("anchor_off_20m") / "estimate.txt"));
    // Ground truth: in place to 1e-6 m; estimate: 20 m off everywhere (its anchor is wrong).
    const PlanarTrajectory gt_world =
        ToPlanar(input.ground_truth, input.scenario.frame, input.anchor);
    EXPECT_LT(MaxDistance(InPlaneOf(v.ground_truth, v, input), gt_world.p_en), kInPlaceTolerance_m);
    const PlanarTrajectory est_world = ToPlanar(input.estimate, input.scenario.frame, input.anchor);
    const std::vector<Eigen::Vector2d> est_v = InPlaneOf(v.estimate, v, input);
    for (std::size_t i = 0; i < est_v.size(); ++i) {
        ASSERT_NEAR((est_v[i] - est_world.p_en[i]).norm(), 20.0, 0.01) << "pose " << i;
    }
}

struct Episode {
    std::size_t first_step = 0, steps = 0;
    double ratio = 0.0;
};

std::vector<Episode> ParseEpisodes(const fs::path& yaml) {
    std::vector<Episode> episodes;
    for (const std::string& line : HeaderLines(yaml, "drop episode: ")) {
        Episode e;
        EXPECT_EQ(std::sscanf(line.c_str(), "first_step %zu, steps %zu, ratio %lf", &e.first_step,
                              &e.steps, &e.ratio),
                  3)
            << line;
        episodes.push_back(e);
    }
    return episodes;
}

TEST_F(StressVariantsTest, DropStepsShortensExactlyTheDocumentedEpisodes) {
    const Loaded input = Load(kInput);
    const Loaded v = Load(Variant("drop_steps"));
    const std::vector<Episode> episodes = ParseEpisodes(Variant("drop_steps") / "scenario.yaml");
    // 1100 steps: at most 20 % of them in episodes of up to 25 steps, so 5..8 episodes.
    EXPECT_GE(episodes.size(), 5u);
    EXPECT_LE(episodes.size(), 8u);
    std::vector<double> ratio(input.estimate.size(), 1.0);
    for (const Episode& e : episodes) {
        EXPECT_GE(e.steps, 15u);
        EXPECT_LE(e.steps, 25u);
        EXPECT_GE(e.ratio, 0.2);
        EXPECT_LT(e.ratio, 0.6);
        for (std::size_t i = e.first_step; i < e.first_step + e.steps; ++i) {
            ASSERT_EQ(ratio.at(i), 1.0) << "episodes overlap at step " << i;
            ratio.at(i) = e.ratio;
        }
    }
    const Trajectory &a = input.estimate, &b = v.estimate;
    std::size_t shortened = 0;
    for (std::size_t i = 1; i < a.size(); ++i) {
        const Eigen::Vector3d t_a =
            a.q_frame_body[i - 1].conjugate() * (a.p_frame[i] - a.p_frame[i - 1]);
        const Eigen::Vector3d t_b =
            b.q_frame_body[i - 1].conjugate() * (b.p_frame[i] - b.p_frame[i - 1]);
        ASSERT_LT((t_b - ratio[i] * t_a).norm(), kStepTolerance_m) << "step " << i;
        const Eigen::Quaterniond r_a = a.q_frame_body[i - 1].conjugate() * a.q_frame_body[i];
        const Eigen::Quaterniond r_b = b.q_frame_body[i - 1].conjugate() * b.q_frame_body[i];
        ASSERT_LT(r_a.angularDistance(r_b), kRotationTolerance_rad) << "step " << i;
        ASSERT_LT(a.q_frame_body[i].angularDistance(b.q_frame_body[i]), kRotationTolerance_rad);
        if (ratio[i] != 1.0 && t_a.norm() > 0.1) {
            ++shortened;
            EXPECT_NEAR(t_b.norm() / t_a.norm(), ratio[i], 1e-5) << "step " << i;
        }
    }
    EXPECT_GT(shortened, 5u * 15u / 2);  // most episode steps are driving, not standing
    // Re-integrated: everything after the first episode is shifted.
    EXPECT_GT((b.p_frame.back() - a.p_frame.back()).norm(), 5.0);
    EXPECT_TRUE(ReadBytes(kInput / "ground_truth.txt") ==
                ReadBytes(Variant("drop_steps") / "ground_truth.txt"));
}

TEST_F(StressVariantsTest, HeadingBiasTurnsTheHeadingLinearlyAtTheBiasRate) {
    const Loaded input = Load(kInput);
    const FrameAxes axes = input.scenario.frame;
    const PlanarTrajectory est_world = ToPlanar(input.estimate, axes, input.anchor);
    for (const double bias_deg_per_s : {0.1, 0.3, 0.5}) {
        std::ostringstream name;
        name << "heading_bias_" << bias_deg_per_s;
        SCOPED_TRACE(name.str());
        const Loaded v = Load(Variant(name.str()));
        const PlanarTrajectory biased = ToPlanar(v.estimate, axes, v.anchor);
        const Trajectory &a = input.estimate, &b = v.estimate;
        for (std::size_t i = 0; i < biased.size(); ++i) {
            const double expected_rad = DegToRad(bias_deg_per_s) * (a.t_s[i] - a.t_s[0]);
            ASSERT_NEAR(AngleDiff(biased.yaw_rad[i] - est_world.yaw_rad[i], expected_rad), 0.0,
                        1e-8)
                << "pose " << i;
            if (i == 0) continue;
            const Eigen::Vector3d t_a =
                a.q_frame_body[i - 1].conjugate() * (a.p_frame[i] - a.p_frame[i - 1]);
            const Eigen::Vector3d t_b =
                b.q_frame_body[i - 1].conjugate() * (b.p_frame[i] - b.p_frame[i - 1]);
            ASSERT_LT((t_b - t_a).norm(), kStepTolerance_m) << "step " << i;
        }
        const double duration_s = a.t_s.back() - a.t_s.front();
        EXPECT_NEAR(RadToDeg(AngleDiff(biased.yaw_rad.back(), est_world.yaw_rad.back())),
                    bias_deg_per_s * duration_s, 1e-6);
    }
}

/// Length of the ground truth (East-North) within radius_m of `way` (steps with both ends near).
double AlongWay_m(const std::vector<Eigen::Vector2d>& gt_en,
                  const std::vector<Eigen::Vector2d>& way) {
    const auto near = [&](const Eigen::Vector2d& p) {
        for (std::size_t k = 1; k < way.size(); ++k) {
            const Eigen::Vector2d d = way[k] - way[k - 1];
            const double s = d.squaredNorm() > 0
                                 ? std::clamp((p - way[k - 1]).dot(d) / d.squaredNorm(), 0.0, 1.0)
                                 : 0.0;
            if ((way[k - 1] + s * d - p).norm() <= kRoadRadius_m) return true;
        }
        return false;
    };
    double along_m = 0.0;
    for (std::size_t k = 1; k < gt_en.size(); ++k) {
        if (near(gt_en[k]) && near(gt_en[k - 1])) along_m += (gt_en[k] - gt_en[k - 1]).norm();
    }
    return along_m;
}

TEST_F(StressVariantsTest, RoadRemovedRemovesTheWayTheGroundTruthDrivesAlongTheLongest) {
    const Loaded input = Load(kInput);
    const fs::path yaml = Variant("road_removed") / "scenario.yaml";
    const std::vector<std::string> removed = HeaderLines(yaml, "variant road_removed: ");
    ASSERT_EQ(removed.size(), 1u);
    const std::size_t at = removed[0].find("removed way: ");
    ASSERT_NE(at, std::string::npos) << removed[0];
    const long long removed_id = std::stoll(removed[0].substr(at + 13));

    const OsmRoads before = ReadOsmRoads((kInput / "map.osm").string());
    const OsmRoads after = ReadOsmRoads((Variant("road_removed") / "map.osm").string());
    std::set<long long> ids_before, ids_after;
    for (const OsmWay& w : before.ways) ids_before.insert(w.id);
    for (const OsmWay& w : after.ways) ids_after.insert(w.id);
    ASSERT_TRUE(ids_before.count(removed_id));
    EXPECT_FALSE(ids_after.count(removed_id));
    ids_before.erase(removed_id);
    EXPECT_EQ(ids_before, ids_after);  // every other way remains
    EXPECT_EQ(before.report.ways_total, after.report.ways_total + 1);
    EXPECT_EQ(before.report.nodes_total, after.report.nodes_total);  // nodes stay

    // Independently: the removed way is the one with the longest ground truth within 5 m.
    const LocalTangentPlane plane(AnchorOrigin(input.scenario.anchor));
    const std::vector<Eigen::Vector2d> gt_en =
        ToPlanar(input.ground_truth, input.scenario.frame, input.anchor).p_en;
    std::map<long long, double> along;
    for (const OsmWay& w : before.ways) {
        std::vector<Eigen::Vector2d> way_en;
        for (const GeoPoint& g : w.nodes) way_en.push_back(plane.ToEnu(g).head<2>());
        along[w.id] = AlongWay_m(gt_en, way_en);
    }
    const auto longest =
        std::max_element(along.begin(), along.end(),
                         [](const auto& x, const auto& y) { return x.second < y.second; });
    EXPECT_EQ(longest->first, removed_id);
    EXPECT_GT(longest->second, 50.0);
    const std::vector<std::string> metres = HeaderLines(yaml, "ground truth along it: ");
    ASSERT_EQ(metres.size(), 1u);
    EXPECT_NEAR(std::stod(metres[0]), longest->second, 0.05);
    // The rest of the file is byte for byte the input's.
    EXPECT_LT(ReadBytes(Variant("road_removed") / "map.osm").size(),
              ReadBytes(kInput / "map.osm").size());
    EXPECT_TRUE(ReadBytes(kInput / "estimate.txt") ==
                ReadBytes(Variant("road_removed") / "estimate.txt"));
}

TEST_F(StressVariantsTest, SameSeedSameBytesAndTheSeedChangesOnlySeededVariants) {
    ASSERT_EQ(RunGenerator(Quote(kInput) + " " + Quote(root_ / "again"), root_ / "again.log"), 0);
    ASSERT_EQ(RunGenerator(Quote(kInput) + " " + Quote(root_ / "seed2") + " --seed 2",
                           root_ / "seed2.log"),
              0);
    const std::set<std::string> seeded = {"drop_steps", "anchor_off_20m"};
    for (const std::string& name : kVariants) {
        for (const char* file : {"estimate.txt", "ground_truth.txt", "map.osm"}) {
            const std::string a = ReadBytes(Variant(name) / file);
            EXPECT_TRUE(a == ReadBytes(root_ / "again" / name / file)) << name << "/" << file;
        }
        const bool same_with_seed2 = ReadBytes(Variant(name) / "estimate.txt") ==
                                         ReadBytes(root_ / "seed2" / name / "estimate.txt") &&
                                     ReadBytes(Variant(name) / "ground_truth.txt") ==
                                         ReadBytes(root_ / "seed2" / name / "ground_truth.txt");
        EXPECT_EQ(same_with_seed2, seeded.count(name) == 0) << name;
    }
}

TEST_F(StressVariantsTest, IndoorScenarioSkipsRoadRemovedAndKeepsTheGroundTruthInPlace) {
    ASSERT_TRUE(fs::exists(kIndoorInput / "scenario.yaml")) << kIndoorInput << " is missing";
    const fs::path out = root_ / "hcu";
    ASSERT_EQ(RunGenerator(Quote(kIndoorInput) + " " + Quote(out), root_ / "hcu.log"), 0);
    EXPECT_NE(ReadBytes(root_ / "hcu.log").find("skipped road_removed"), std::string::npos);
    EXPECT_FALSE(fs::exists(out / "road_removed" / "scenario.yaml"));
    // A crs anchor: the East-North plane is the CRS grid, so the planes of both anchors differ
    // only by the origin.
    const Loaded input = Load(kIndoorInput);
    const PlanarTrajectory gt_world =
        ToPlanar(input.ground_truth, input.scenario.frame, input.anchor);
    for (const std::string name : {"yaw_off_20", "anchor_off_20m"}) {
        SCOPED_TRACE(name);
        const Loaded v = Load(out / name);
        std::vector<Eigen::Vector2d> gt_v =
            ToPlanar(v.ground_truth, v.scenario.frame, v.anchor).p_en;
        const Eigen::Vector2d origin_shift(
            *v.scenario.anchor.easting_m - *input.scenario.anchor.easting_m,
            *v.scenario.anchor.northing_m - *input.scenario.anchor.northing_m);
        for (Eigen::Vector2d& p : gt_v) p += origin_shift;
        // TUM files hold 9 decimals: 1e-6 m is well above the rounding.
        EXPECT_LT(MaxDistance(gt_v, gt_world.p_en), kInPlaceTolerance_m);
    }
}

TEST_F(StressVariantsTest, BadInputExitsWithTwoAndNamesTheFile) {
    const fs::path missing = root_ / "no_such_scenario";
    EXPECT_EQ(RunGenerator(Quote(missing) + " " + Quote(root_ / "bad"), root_ / "bad.log"), 2);
    EXPECT_NE(ReadBytes(root_ / "bad.log").find(missing.string()), std::string::npos);

    // A scenario.yaml naming an estimate file that does not exist: nothing is written.
    const fs::path broken = root_ / "broken";
    fs::create_directories(broken);
    std::string yaml = ReadBytes(kInput / "scenario.yaml");
    yaml.replace(yaml.find("path: estimate.txt"), 18, "path: " + (kInput / "missing.txt").string());
    std::ofstream(broken / "scenario.yaml") << yaml;
    EXPECT_EQ(RunGenerator(Quote(broken) + " " + Quote(root_ / "bad2"), root_ / "bad2.log"), 2);
    EXPECT_NE(ReadBytes(root_ / "bad2.log").find("missing.txt"), std::string::npos);
    EXPECT_FALSE(fs::exists(root_ / "bad2"));

    EXPECT_EQ(
        RunGenerator(Quote(kInput) + " " + Quote(root_ / "bad3") + " --seed x", root_ / "bad3.log"),
        2);
    EXPECT_EQ(RunGenerator(Quote(kInput), root_ / "bad4.log"), 2);
}

}  // namespace
