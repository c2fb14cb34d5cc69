// A road drive's size against the map: FitSizes scores the corrected drive scaled about its start,
// and the verdict fails a correction that changed the drive's size where the map fits another
// size as well.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "driftcorr/mapping/road_network.h"
#include "driftcorr/optim/anchor_fit.h"
#include "driftcorr/optim/verdict.h"

namespace driftcorr {
namespace {

// A street east along y = 0 for 3 km, and `north_x` streets north from it, 1.5 km long.
TraversableField Streets(const std::vector<double>& north_x) {
    RoadNetwork net;
    net.roads.push_back(RoadPolyline{1, "residential", 4.5, {{0.0, 0.0}, {3000.0, 0.0}}});
    for (std::size_t k = 0; k < north_x.size(); ++k) {
        net.roads.push_back(RoadPolyline{
            std::int64_t(k + 2), "residential", 4.5, {{north_x[k], 0.0}, {north_x[k], 1500.0}}});
    }
    RoadFieldConfig c;
    c.resolution_m = 1.0;
    c.margin_m = 60.0;
    return RasteriseRoads(
        net, Eigen::AlignedBox2d(Eigen::Vector2d(-100, -100), Eigen::Vector2d(3100, 1600)), c);
}

// East along y = 0 to x = turn_x, then north for 1000 m: one pose every 2 m, 10 m/s.
PlanarTrajectory TurnAt(double turn_x) {
    PlanarTrajectory t;
    const int east = int(turn_x / 2.0);
    for (int i = 0; i <= east + 500; ++i) {
        t.t_s.push_back(0.2 * i);
        t.p_en.emplace_back(i <= east ? 2.0 * i : turn_x, i <= east ? 0.0 : 2.0 * (i - east));
        t.up_m.push_back(0.0);
        t.yaw_rad.push_back(i <= east ? 0.0 : 0.5 * M_PI);
    }
    return t;
}

AnchorFitConfig RoadFit() {
    AnchorFitConfig c;
    c.reach_m = 8.0;
    c.sample_spacing_m = 5.0;
    return c;
}

// One turn after 2 km onto one of a grid's streets: scaled by 0.925 the drive turns into the
// street at x = 1850 m and fits as well; the street at 2300 m (1.15) is beyond the range
// (1 / 1.1 .. 1.1).
TEST(SizeFit, ASingleTurnAfterALongStraightFitsAnotherSize) {
    const TraversableField field = Streets({1850.0, 2000.0, 2300.0});
    const SizeFit fit = FitSizes(TurnAt(2000.0), field, 0.1, RoadFit());
    EXPECT_LT(fit.rms_m, 0.5);
    EXPECT_NEAR(fit.farthest_m, std::hypot(2000.0, 1000.0), 1.0);
    ASSERT_TRUE(fit.other.has_value());
    EXPECT_NEAR(fit.other->scale, 0.925, 0.002);
    EXPECT_LT(fit.other->placement.rms_m, fit.rms_m + 0.2);
    // Without the street at 1850 m no other size fits.
    const SizeFit alone = FitSizes(TurnAt(2000.0), Streets({2000.0, 2300.0}), 0.1, RoadFit());
    EXPECT_LT(alone.rms_m, 0.5);
    EXPECT_TRUE(!alone.other || alone.other->placement.rms_m > 3.0);
}

CorrectionResult Result(PlanarTrajectory corrected) {
    CorrectionResult r;
    r.status = SolveStatus::kSuccess;
    r.corrected = std::move(corrected);
    return r;
}

bool HasReason(const Verdict& v, const std::string& text) {
    for (const auto& r : v.reasons) {
        if (r.find(text) != std::string::npos) return true;
    }
    return false;
}

// The correction turned into the street at 2000 m, stretching an input that turned at 1960 m
// (2 %): the street at 1850 m fits the corrected shape as well, so the choice was the
// correction's, not the map's: failed. The same correction of an input of its own size changed
// nothing the map could not tell (not this finding), and so does one on a map where no other
// street fits.
TEST(SizeFit, TheVerdictFailsASizeTheMapDoesNotTell) {
    const TraversableField grid = Streets({1850.0, 2000.0, 2300.0});
    const PlanarTrajectory corrected = TurnAt(2000.0);
    const PlanarTrajectory shorter = ScaleAbout(corrected, Eigen::Vector2d::Zero(), 0.0, 1 / 1.02);
    ModelConfig road;
    road.map_giveup_m = 8.0;
    road.scale_prior_sigma = 0.1;
    road.scale_segment_m = 150.0;
    const auto judge = [&](const PlanarTrajectory& estimate, const TraversableField& field) {
        return JudgeCorrection(estimate, &field, road, Result(corrected), nullptr, false, true,
                               VerdictConfig{});
    };
    const std::string finding = "the map does not tell the drive's size";
    const Verdict stretched = judge(shorter, grid);
    EXPECT_EQ(stretched.level, VerdictLevel::kFailed);
    EXPECT_TRUE(HasReason(stretched, finding));
    EXPECT_FALSE(HasReason(judge(corrected, grid), finding));
    EXPECT_FALSE(HasReason(judge(shorter, Streets({2000.0, 2300.0})), finding));
}

}  // namespace
}  // namespace driftcorr
