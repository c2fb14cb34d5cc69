// The start of a trajectory fitted to the map: headings and positions recovered on a hand-made
// road network, ambiguity reported, and the pipeline's `yaw_deg: auto` on a real drive.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "driftcorr/core/angles.h"
#include "driftcorr/mapping/road_network.h"
#include "driftcorr/optim/anchor_fit.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr {
namespace {

// An L of two streets: east from the origin for 200 m, then north for 200 m, and a side street
// going north from x = 80 m, so that a straight start alone is not unique.
RoadNetwork LStreets() {
    RoadNetwork net;
    net.roads.push_back(RoadPolyline{1, "residential", 4.0, {{0.0, 0.0}, {200.0, 0.0}}});
    net.roads.push_back(RoadPolyline{2, "residential", 4.0, {{200.0, 0.0}, {200.0, 200.0}}});
    net.roads.push_back(RoadPolyline{3, "residential", 4.0, {{80.0, 0.0}, {80.0, 150.0}}});
    return net;
}

TraversableField LField() {
    RoadFieldConfig c;
    c.resolution_m = 0.5;
    c.margin_m = 60.0;
    return RasteriseRoads(
        LStreets(), Eigen::AlignedBox2d(Eigen::Vector2d(-250, -250), Eigen::Vector2d(450, 450)), c);
}

// The drive along the L, one pose a metre, heading along the street.
PlanarTrajectory DriveAlongL() {
    PlanarTrajectory t;
    for (int i = 0; i <= 400; ++i) {
        const bool first_leg = i <= 200;
        t.t_s.push_back(0.1 * i);
        t.p_en.emplace_back(first_leg ? i : 200.0, first_leg ? 0.0 : i - 200.0);
        t.up_m.push_back(0.0);
        t.yaw_rad.push_back(first_leg ? 0.0 : kPi / 2);
    }
    return t;
}

TEST(AnchorFit, RecoversAHeadingFromTheWholeCircle) {
    const TraversableField field = LField();
    const PlanarTrajectory truth = DriveAlongL();
    for (double wrong_deg : {-150.0, -30.0, 10.0, 95.0}) {
        AnchorPlacement turn;
        turn.dyaw_rad = DegToRad(wrong_deg);
        const PlanarTrajectory placed = ApplyPlacement(truth, Eigen::Vector2d::Zero(), turn);
        const AnchorFitResult fit =
            FitAnchor(placed, Eigen::Vector2d::Zero(), field, true, 0.0, AnchorFitConfig{});
        EXPECT_NEAR(RadToDeg(WrapAngle(fit.best.dyaw_rad + turn.dyaw_rad)), 0.0, 0.3) << wrong_deg;
        EXPECT_LT(fit.best.rms_m, 0.3) << wrong_deg;
        EXPECT_GT(fit.given.rms_m, 3.0) << wrong_deg;
        EXPECT_EQ(fit.best.off_share, 0.0) << wrong_deg;
        ASSERT_TRUE(fit.runner_up.has_value()) << wrong_deg;
        EXPECT_GT(fit.runner_up->rms_m, 2.0 * fit.best.rms_m + 1.0) << wrong_deg;
    }
}

// A monocular tracker's drive along the L: the right shape at a tenth of the size. Scaled by 10
// it fits the L; scaled by 4 it fits as well, turning into the side street at x = 80 m (80 m
// east, 80 m north): the leading path alone cannot tell the two, so both are candidates, and
// other scales fit worse.
TEST(AnchorFit, FindsTheGlobalScalesThatFitAShrunkenDrive) {
    const TraversableField field = LField();
    const PlanarTrajectory small = ScaleAbout(DriveAlongL(), Eigen::Vector2d::Zero(), 0.0, 0.1);
    for (bool search_yaw : {false, true}) {
        const ScaleFitResult fit = FitScale(small, Eigen::Vector2d::Zero(), 0.0, field, search_yaw,
                                            2.0, 40.0, 1.02, 3, AnchorFitConfig{});
        ASSERT_GE(fit.candidates.size(), 2u) << search_yaw;
        const auto found = [&](double scale) {
            return std::any_of(
                fit.candidates.begin(), fit.candidates.begin() + 2, [&](const ScaleCandidate& c) {
                    return std::abs(c.scale - scale) < 0.02 * scale && c.placement.rms_m < 0.3;
                });
        };
        EXPECT_TRUE(found(10.0)) << search_yaw;
        EXPECT_TRUE(found(4.0)) << search_yaw;
        EXPECT_EQ(fit.scales.size(), fit.rms_m.size());
        EXPECT_NEAR(fit.scales.front(), 2.0, 1e-12);
        EXPECT_GE(fit.scales.back(), 40.0);
        // Away from both, the fit is worse (the turn falls beside every corner); below 3 the
        // whole drive stays on the first street, which fits any such scale.
        for (std::size_t k = 0; k < fit.scales.size(); ++k) {
            const double s = fit.scales[k];
            if (std::abs(std::log(s / 10.0)) > 0.1 && std::abs(std::log(s / 4.0)) > 0.1 &&
                s > 3.0) {
                EXPECT_GT(fit.rms_m[k], 1.0) << s;
            }
        }
    }
}

TEST(AnchorFit, RecoversAPositionWithinTheSearchRadius) {
    const TraversableField field = LField();
    AnchorPlacement wrong;
    wrong.dyaw_rad = DegToRad(12.0);
    wrong.offset_en = Eigen::Vector2d(-9.0, 14.0);
    const PlanarTrajectory placed = ApplyPlacement(DriveAlongL(), Eigen::Vector2d::Zero(), wrong);
    const AnchorFitResult fit =
        FitAnchor(placed, wrong.offset_en, field, true, 25.0, AnchorFitConfig{});
    const PlanarTrajectory back = ApplyPlacement(placed, wrong.offset_en, fit.best);
    double worst_m = 0.0;
    for (std::size_t i = 0; i < back.size(); ++i) {
        worst_m = std::max(worst_m, (back.p_en[i] - DriveAlongL().p_en[i]).norm());
    }
    EXPECT_LT(worst_m, 1.0);
    // Without a position search, only the heading can move: the fit stays off the roads.
    const AnchorFitResult heading_only =
        FitAnchor(placed, wrong.offset_en, field, true, 0.0, AnchorFitConfig{});
    EXPECT_GT(heading_only.best.rms_m, 3.0 * fit.best.rms_m);
}

// A lone straight street fits both ways round: the runner-up is as good as the best.
TEST(AnchorFit, AStraightStartIsReportedAsAmbiguous) {
    RoadNetwork net;
    net.roads.push_back(RoadPolyline{1, "residential", 4.0, {{-300.0, 0.0}, {300.0, 0.0}}});
    RoadFieldConfig c;
    c.resolution_m = 0.5;
    const TraversableField field = RasteriseRoads(
        net, Eigen::AlignedBox2d(Eigen::Vector2d(-320, -320), Eigen::Vector2d(320, 320)), c);
    PlanarTrajectory t = DriveAlongL();
    t.p_en.resize(201), t.t_s.resize(201), t.up_m.resize(201), t.yaw_rad.resize(201);
    const AnchorFitResult fit =
        FitAnchor(t, Eigen::Vector2d::Zero(), field, true, 0.0, AnchorFitConfig{});
    ASSERT_TRUE(fit.runner_up.has_value());
    EXPECT_NEAR(std::abs(RadToDeg(WrapAngle(fit.runner_up->dyaw_rad - fit.best.dyaw_rad))), 180.0,
                0.5);
    EXPECT_NEAR(fit.runner_up->rms_m, fit.best.rms_m, 0.05);
}

// `yaw_deg: auto` on a real drive: the heading found from the map is within the few degrees the
// odometry's own heading drifts over the leading path.
TEST(AnchorFit, YawAutoOnARealDrive) {
    namespace fs = std::filesystem;
    const fs::path src = fs::path(DRIFTCORR_SHARED_DATASETS) / "kitti07_cvo_stereo_geometric";
    if (!fs::exists(src / "scenario.yaml")) GTEST_SKIP() << "real data not present: " << src;
    std::ifstream in(src / "scenario.yaml");
    std::stringstream text;
    text << in.rdbuf();
    std::string yaml = std::regex_replace(text.str(), std::regex("path: ([a-z_]+\\.[a-z]+)"),
                                          "path: " + src.string() + "/$1");
    const std::smatch given = [&] {
        std::smatch m;
        std::regex_search(yaml, m, std::regex("yaw_deg: (-?[0-9.]+)"));
        return m;
    }();
    ASSERT_FALSE(given.empty());
    const double given_deg = std::stod(given[1].str());
    yaml = std::regex_replace(yaml, std::regex("yaw_deg: -?[0-9.]+"), "yaw_deg: auto");
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "yaw_auto_kitti07";
    fs::create_directories(dir);
    std::ofstream(dir / "scenario.yaml") << yaml;
    const pipeline::PreparedScenario ps =
        pipeline::PrepareScenario(dir.string(), pipeline::PipelineConfig{});
    ASSERT_TRUE(ps.anchor_fit.has_value());
    EXPECT_NEAR(RadToDeg(ps.anchor.yaw_rad), given_deg, 5.0);
    EXPECT_LT(ps.anchor_fit->best.rms_m, 3.0);
    ASSERT_TRUE(ps.anchor_fit->runner_up.has_value());
    EXPECT_GT(ps.anchor_fit->runner_up->rms_m, 2.0 * ps.anchor_fit->best.rms_m);
}

}  // namespace
}  // namespace driftcorr
