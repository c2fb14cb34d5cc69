// The verdict's indoor checks on hand-made trajectories in buildings of two or three floors: a
// corrected floor change that the estimate's heights deny, level walking between floors, a floor
// that another floor explains as well, and the plausible scale the model declares; online, causal
// outputs a floor or a branch away from the smoothed trajectory. On roads: the drive's size where
// the map fits another size as well (FitSizes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "driftcorr/mapping/indoor_field.h"
#include "driftcorr/mapping/road_network.h"
#include "driftcorr/optim/anchor_fit.h"
#include "driftcorr/optim/verdict.h"

namespace driftcorr {
namespace {

FloorPolygon Rect(double x0, double y0, double x1, double y1) {
    return {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, {}};
}

// Floors 4 m apart, floor f spanning x 0..extent_x_m[f] and y 0..10, joined by a lift at x 2..4.
TraversableField Floors(const std::vector<double>& extent_x_m) {
    std::vector<IndoorFloor> floors(extent_x_m.size());
    for (std::size_t f = 0; f < floors.size(); ++f) {
        floors[f].floor_z_m = 4.0 * double(f);
        floors[f].walkable.push_back(Rect(0, 0, extent_x_m[f], 10));
        floors[f].lifts.push_back(Rect(2, 4, 4, 6));
    }
    IndoorFieldConfig c;
    c.resolution_z_m = 0.25;
    c.vertical_tolerance_m = 0.25;
    return BuildIndoorField(floors, c);
}

// Two 40 m x 10 m floors.
TraversableField TwoFloors() { return Floors({40.0, 40.0}); }

// A 200 s walk along y = 5 at 0.15 m/s, one pose a second, at height up_m(t).
template <class Up>
PlanarTrajectory Walk(Up up_m, double speed_mps = 0.15) {
    PlanarTrajectory t;
    for (int k = 0; k <= 200; ++k) {
        t.t_s.push_back(k);
        t.p_en.emplace_back(5.0 + speed_mps * k, 5.0);
        t.up_m.push_back(up_m(k));
        t.yaw_rad.push_back(0.0);
    }
    return t;
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

TEST(VerdictIndoor, ACorrectedFloorChangeTheEstimateDeniesIsNotOk) {
    const TraversableField field = TwoFloors();
    const PlanarTrajectory level = Walk([](int) { return 0.0; });
    const PlanarTrajectory climbs = Walk([](int k) { return k < 150 ? 0.0 : 4.0; });
    const ModelConfig model;
    const VerdictConfig config;
    // The estimate stays on the ground floor; a correction that stays too is fine...
    const Verdict same =
        JudgeCorrection(level, &field, model, Result(level), nullptr, false, false, config);
    EXPECT_EQ(same.level, VerdictLevel::kOk);
    // ...one that moves the last quarter of the walk to the upper floor is not: 4 m against 0 m
    // of height change is beyond 1.5 m + 35 % of the estimate's. Flagged: the poses of every
    // 60 s that holds the change.
    const Verdict up =
        JudgeCorrection(level, &field, model, Result(climbs), nullptr, false, false, config);
    EXPECT_NE(up.level, VerdictLevel::kOk);
    EXPECT_TRUE(HasReason(up, "height changes disagree")) << up.reasons.front();
    EXPECT_TRUE(up.pose_flags[120] & kPoseHeightDisagrees);
    EXPECT_TRUE(up.pose_flags[170] & kPoseHeightDisagrees);
    EXPECT_FALSE(up.pose_flags[80] & kPoseHeightDisagrees);
    // An estimate that reads the same climb 0.8x (a barometer's gain error) supports it.
    const PlanarTrajectory reads = Walk([](int k) { return k < 150 ? 0.0 : 3.2; });
    const Verdict gain =
        JudgeCorrection(reads, &field, model, Result(climbs), nullptr, false, false, config);
    EXPECT_FALSE(HasReason(gain, "height changes disagree")) << gain.reasons.front();
}

// A barometer over-reads a floor change by 12 % at most, so a correction whose change falls
// short of the reading by more than 1.5 m + 20 % of it changed floor less than the walk did: an
// estimate that climbs 8 m does not support a correction that climbs 4 m (the floor below the
// one it reached), though 4 m is within 1.5 m + 35 % of 8 m. One that reads the 4 m 1.1x does.
TEST(VerdictIndoor, ACorrectedFloorChangeShortOfTheReadingIsNotOk) {
    const TraversableField field = TwoFloors();
    const PlanarTrajectory climbs = Walk([](int k) { return k < 150 ? 0.0 : 4.0; });
    const ModelConfig model;
    const VerdictConfig config;
    const PlanarTrajectory twice = Walk([](int k) { return k < 150 ? 0.0 : 8.0; });
    const Verdict short_of =
        JudgeCorrection(twice, &field, model, Result(climbs), nullptr, false, false, config);
    EXPECT_TRUE(HasReason(short_of, "height changes disagree"));
    const PlanarTrajectory over = Walk([](int k) { return k < 150 ? 0.0 : 4.4; });
    const Verdict gain =
        JudgeCorrection(over, &field, model, Result(climbs), nullptr, false, false, config);
    EXPECT_FALSE(HasReason(gain, "height changes disagree")) << gain.reasons.front();
}

TEST(VerdictIndoor, LevelWalkingBetweenFloorsIsNotOk) {
    TraversableField field = TwoFloors();
    // The estimate: level, with a barometer's 0.3 m of wobble.
    const PlanarTrajectory level = Walk([](int k) { return 0.3 * std::sin(0.7 * k); });
    // The correction holds the last 100 s at 2 m: between the floors (0 and 4 m), level.
    const PlanarTrajectory between = Walk([](int k) { return k < 100 ? 0.0 : 2.0; });
    const ModelConfig model;
    VerdictConfig config;
    config.height_disagree_m = 10.0;  // this test is about the other check
    const Verdict unknown =
        JudgeCorrection(level, &field, model, Result(between), nullptr, false, false, config);
    EXPECT_FALSE(HasReason(unknown, "walk level")) << "no floor heights: no check";
    field.set_floor_heights_m({0.0, 4.0});
    const Verdict v =
        JudgeCorrection(level, &field, model, Result(between), nullptr, false, false, config);
    EXPECT_TRUE(HasReason(v, "walk level up to 2.0 m from every floor")) << v.reasons.front();
    EXPECT_EQ(v.level, VerdictLevel::kFailed);  // half of the poses
    EXPECT_TRUE(v.pose_flags[150] & kPoseHeightDisagrees);
    EXPECT_FALSE(v.pose_flags[50] & kPoseHeightDisagrees);
    // On a floor, or changing height (a stair climb), it is fine.
    const Verdict on_floor =
        JudgeCorrection(level, &field, model, Result(level), nullptr, false, false, config);
    EXPECT_FALSE(HasReason(on_floor, "walk level"));
    // Stairs: 4 m in 20 s (0.2 m/s), then the upper floor.
    const PlanarTrajectory climb = Walk([](int k) {
        return k < 100 ? 0.0 : k < 120 ? 0.2 * (k - 100) : 4.0;
    });
    const Verdict stairs =
        JudgeCorrection(climb, &field, model, Result(climb), nullptr, false, false, config);
    EXPECT_FALSE(HasReason(stairs, "walk level"));
}

// A lift ride from the ground floor to the top one (8 m over 60-80 s), then 120 s on the top
// floor. A barometer that reads the ride 0.8x (6.4 m) reads the middle floor (4 m) as well: the
// verdict says the floor is not determined, unless the map tells the floors apart.
TEST(VerdictIndoor, AFloorThatAnotherFloorExplainsAsWellIsNotOk) {
    auto ride = [](double gain) {
        return Walk([gain](int k) { return gain * std::clamp(0.4 * (k - 60), 0.0, 8.0); });
    };
    const PlanarTrajectory corrected = ride(1.0);
    ModelConfig model;
    model.map_giveup_m = 3.0;  // the pedestrian model's reach
    const VerdictConfig config;
    std::vector<double> floors = {0.0, 4.0, 8.0};
    auto judge = [&](TraversableField field, const PlanarTrajectory& estimate) {
        field.set_floor_heights_m(floors);
        return JudgeCorrection(estimate, &field, model, Result(corrected), nullptr, false, false,
                               config);
    };
    const TraversableField same_floors = Floors({40.0, 40.0, 40.0});
    const Verdict short_reading = judge(same_floors, ride(0.8));
    EXPECT_EQ(short_reading.level, VerdictLevel::kDegraded);
    EXPECT_TRUE(HasReason(short_reading, "the floor is not determined over 61 % of the walk"))
        << (short_reading.reasons.empty() ? "no reason" : short_reading.reasons.front());
    EXPECT_TRUE(HasReason(short_reading, "read the floor at 4.0 m as well"));
    EXPECT_TRUE(short_reading.pose_flags[150] & kPoseFloorAmbiguous);
    EXPECT_FALSE(short_reading.pose_flags[30] & kPoseFloorAmbiguous);
    // Read 1.0x, the ride is too long for the middle floor (4 m short of 8 m is beyond
    // 1.5 m + 20 %).
    const Verdict exact = judge(same_floors, ride(1.0));
    EXPECT_EQ(exact.level, VerdictLevel::kOk) << exact.reasons.front();
    EXPECT_FALSE(exact.pose_flags[150] & kPoseFloorAmbiguous);
    // The middle floor ends at x 10, and the walk stays at x 17-35 there: the map tells them
    // apart.
    const Verdict apart = judge(Floors({40.0, 10.0, 40.0}), ride(0.8));
    EXPECT_EQ(apart.level, VerdictLevel::kOk) << apart.reasons.front();
    // Without the floors' heights there is no check.
    floors.clear();
    EXPECT_EQ(judge(same_floors, ride(0.8)).level, VerdictLevel::kOk);
}

TEST(VerdictIndoor, TheModelsPlausibleScaleRangeIsTheVerdicts) {
    const TraversableField field = TwoFloors();
    const PlanarTrajectory estimate = Walk([](int) { return 0.0; }, 0.1);
    const PlanarTrajectory stretched = Walk([](int) { return 0.0; }, 0.14);  // 1.4x the path
    // 0.85x the path: a walk squeezed into a corridor beside its own.
    const PlanarTrajectory squeezed = Walk([](int) { return 0.0; }, 0.085);
    ModelConfig road;  // plausible 0.8..1.25
    road.scale_segment_m = 10.0;
    ModelConfig pedestrian = road;
    pedestrian.scale_range_min = 0.9;
    pedestrian.scale_range_max = 1.5;
    ModelConfig no_prior = pedestrian;  // without a range prior the verdict's own range holds
    no_prior.scale_range_sigma = 0.0;
    auto judge = [&](const ModelConfig& model, const PlanarTrajectory& corrected) {
        return JudgeCorrection(estimate, &field, model, Result(corrected), nullptr, false, true,
                               VerdictConfig{});
    };
    EXPECT_TRUE(HasReason(judge(road, stretched), "beyond the plausible scale"));
    const Verdict b = judge(pedestrian, stretched);
    EXPECT_FALSE(HasReason(b, "plausible scale"));
    EXPECT_EQ(b.level, VerdictLevel::kOk);
    EXPECT_FALSE(HasReason(judge(road, squeezed), "plausible scale"));
    const Verdict d = judge(pedestrian, squeezed);
    EXPECT_TRUE(HasReason(d, "beyond the plausible scale"));
    EXPECT_EQ(d.level, VerdictLevel::kDegraded);
    EXPECT_FALSE(HasReason(judge(no_prior, squeezed), "plausible scale"));
}

// A stair flight's treads run shorter than the odometry's level steps, and the model does not
// scale them (MarkStairTreads): poses 60-119 (a climb of 60 s) move 0.04 m a second where the
// estimate's steps read 0.1, the rest as read. Counted as scaled steps, the climb reads as a walk
// squeezed below 0.6x (failed); without the treads, the scale is 1.
TEST(VerdictIndoor, StairTreadsAreNotASqueezedWalk) {
    const TraversableField field = TwoFloors();
    const PlanarTrajectory estimate = Walk([](int) { return 0.0; }, 0.1);
    PlanarTrajectory corrected = estimate;
    double x = corrected.p_en[0].x();
    for (std::size_t k = 1; k < corrected.size(); ++k) {
        x += k >= 60 && k < 120 ? 0.04 : 0.1;
        corrected.p_en[k].x() = x;
    }
    ModelConfig pedestrian;
    pedestrian.scale_segment_m = 3.0;
    pedestrian.scale_range_min = 0.9;
    pedestrian.scale_range_max = 1.5;
    CorrectionResult result = Result(corrected);
    result.step_length_m.assign(estimate.size(), 0.1);
    result.step_length_m[0] = 0.0;
    auto judge = [&](const CorrectionResult& r) {
        return JudgeCorrection(estimate, &field, pedestrian, r, nullptr, false, true,
                               VerdictConfig{});
    };
    const Verdict squeezed = judge(result);
    EXPECT_EQ(squeezed.level, VerdictLevel::kFailed);
    EXPECT_TRUE(HasReason(squeezed, "stretches or squeezes the drive"));
    EXPECT_LT(squeezed.scale_min, 0.6);
    result.tread_steps.assign(estimate.size(), 0);
    std::fill(result.tread_steps.begin() + 60, result.tread_steps.begin() + 120, 1);
    const Verdict v = judge(result);
    EXPECT_EQ(v.level, VerdictLevel::kOk) << (v.reasons.empty() ? "" : v.reasons.front());
    EXPECT_NEAR(v.scale_min, 1.0, 1e-9);
    EXPECT_NEAR(v.scale_max, 1.0, 1e-9);
}

// Online (JudgeOnline): the causal outputs against the smoothed trajectory. The smoothed
// trajectory rides a lift from the ground floor to the top one (8 m over 60-80 s) and stays
// there, as the barometer reads; the causal chain ends its ride on the middle floor (4 m) and
// stays there `stay_s` seconds before it follows. An online output lags a floor change by a few
// seconds; a level window (20 s) or more a floor apart is a wrong floor on one side.
TEST(VerdictOnline, CausalOutputsAFloorApartAreNotOk) {
    TraversableField field = Floors({40.0, 40.0, 40.0});
    field.set_floor_heights_m({0.0, 4.0, 8.0});
    const PlanarTrajectory smoothed =
        Walk([](int k) { return std::clamp(0.4 * (k - 60), 0.0, 8.0); });
    auto causal_staying = [&](int stay_s) {
        PlanarTrajectory causal = smoothed;
        for (int k = 80; k < 80 + stay_s; ++k) causal.up_m[k] = 4.0;
        return causal;
    };
    const ModelConfig model;
    VerdictConfig config;
    auto judge = [&](const PlanarTrajectory& causal) {
        return JudgeOnline(smoothed, causal, &field, model, Result(smoothed), config);
    };
    const OnlineVerdict same = judge(smoothed);
    EXPECT_EQ(same.verdict.level, VerdictLevel::kOk)
        << (same.verdict.reasons.empty() ? "" : same.verdict.reasons.front());
    EXPECT_EQ(same.check.floor_apart_share, 0.0);
    const OnlineVerdict lag = judge(causal_staying(15));  // 14 s from first to last pose
    EXPECT_EQ(lag.verdict.level, VerdictLevel::kOk);
    EXPECT_EQ(lag.check.floor_apart_share, 0.0);
    const OnlineVerdict stay = judge(causal_staying(40));
    EXPECT_EQ(stay.verdict.level, VerdictLevel::kDegraded);
    EXPECT_NEAR(stay.check.floor_apart_share, 40.0 / 201.0, 1e-12);
    EXPECT_NEAR(stay.check.floor_apart_longest_s, 39.0, 1e-12);
    EXPECT_NEAR(stay.check.floor_apart_max_m, 4.0, 1e-12);
    EXPECT_TRUE(HasReason(stay.verdict,
                          "20 % of the causal outputs stood up to 4.0 m above or "
                          "below the smoothed trajectory (39 s in a row)"))
        << (stay.verdict.reasons.empty() ? "no reason" : stay.verdict.reasons.front());
    // Beyond off_map_failed_share (30 %) of the poses: failed.
    const OnlineVerdict rest = judge(causal_staying(100));
    EXPECT_EQ(rest.verdict.level, VerdictLevel::kFailed);
    EXPECT_FALSE(rest.check.disagree);  // horizontally they agree
    // A longer window lets the same stay pass.
    config.level_window_s = 60.0;
    EXPECT_EQ(judge(causal_staying(40)).verdict.level, VerdictLevel::kOk);
    // In 2D (no height thresholds: the heights are not corrected) there is no height check.
    EXPECT_EQ(CheckCausalOutput(smoothed, causal_staying(100), smoothed).floor_apart_share, 0.0);
    EXPECT_GT(CheckCausalOutput(smoothed, causal_staying(100), smoothed, &config).floor_apart_share,
              0.0);
}

// Horizontally: causal outputs farther from the smoothed trajectory (RMS) than the input lies
// from it followed a wrong branch on one side. The input lies 3 m beside the smoothed
// trajectory; causal outputs 2 m beside it agree, 4 m beside it do not.
TEST(VerdictOnline, CausalOutputsFartherThanTheInputFail) {
    const TraversableField field = TwoFloors();
    const PlanarTrajectory smoothed = Walk([](int) { return 0.0; });
    auto beside = [&](double dy_m) {
        PlanarTrajectory t = smoothed;
        for (Eigen::Vector2d& p : t.p_en) p.y() += dy_m;
        return t;
    };
    const ModelConfig model;
    const VerdictConfig config;
    const PlanarTrajectory input = beside(3.0);
    const OnlineVerdict near =
        JudgeOnline(input, beside(2.0), &field, model, Result(smoothed), config);
    EXPECT_FALSE(near.check.disagree);
    EXPECT_FALSE(HasReason(near.verdict, "wrong branch"));
    const OnlineVerdict far =
        JudgeOnline(input, beside(4.0), &field, model, Result(smoothed), config);
    EXPECT_TRUE(far.check.disagree);
    EXPECT_NEAR(far.check.causal_rms_m, 4.0, 1e-9);
    EXPECT_NEAR(far.check.input_rms_m, 3.0, 1e-9);
    EXPECT_EQ(far.verdict.level, VerdictLevel::kFailed);
    EXPECT_TRUE(HasReason(far.verdict, "followed a wrong branch of the map"));
    // A smoothed result that is the input kept (the map cannot tell it wrong): the causal outputs
    // moved it, and the reason says so rather than blaming a branch.
    CorrectionResult kept = Result(input);
    kept.input_kept = true;
    const OnlineVerdict moved = JudgeOnline(input, beside(4.0), &field, model, kept, config);
    EXPECT_TRUE(moved.check.disagree);
    EXPECT_EQ(moved.verdict.level, VerdictLevel::kFailed);
    EXPECT_TRUE(HasReason(moved.verdict, "which is the input itself"));
    EXPECT_FALSE(HasReason(moved.verdict, "wrong branch"));
    // Outputs composed from the input itself (the odometry from the known start, before the
    // first solve), equal to it but for rounding, leave a kept input as it was.
    PlanarTrajectory composed = input;
    for (Eigen::Vector2d& p : composed.p_en) p.x() += 1e-9;
    const OnlineVerdict same = JudgeOnline(input, composed, &field, model, kept, config);
    EXPECT_FALSE(same.check.disagree);
    EXPECT_NE(same.verdict.level, VerdictLevel::kFailed);
}

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

// A 2 km drive east with small heading changes of its own (the odometry's), one pose every 2 m;
// a correction of it (`corrected`) turns by up to 0.001 rad a step more or less everywhere, and
// with `detour` bends the stretch from 1000 to 1200 m: 20 steps turning 0.05 rad left, 40 right,
// 20 left, as a correction that put the drive on another road than the estimate drove.
PlanarTrajectory Weaving(bool corrected, bool detour = false) {
    PlanarTrajectory t;
    Eigen::Vector2d p(0.0, 0.0);
    double heading = 0.0;
    for (int i = 0; i <= 1000; ++i) {
        if (i > 0) {
            heading += 0.002 * std::sin(0.37 * i) + 0.001 * std::cos(1.3 * i);
            if (corrected) heading += 0.001 * std::sin(2.1 * i);
            if (detour && i > 500 && i <= 580) heading += (i <= 520 || i > 560) ? 0.05 : -0.05;
            p += 2.0 * Eigen::Vector2d(std::cos(heading), std::sin(heading));
        }
        t.t_s.push_back(0.2 * i);
        t.p_en.push_back(p);
        t.up_m.push_back(0.0);
        t.yaw_rad.push_back(heading);
    }
    return t;
}

// The correction turns where the estimate does not: degraded, and the poses of that window are
// flagged; the correction without the detour, turned as a whole and scaled, is not.
TEST(VerdictRoads, TurnsTheEstimateDoesNotMakeAreNotOk) {
    const TraversableField field = Streets({1000.0});
    ModelConfig road;
    road.map_giveup_m = 1000.0;  // every pose within the map term's reach: no off-map finding
    road.scale_range_min = 0.5, road.scale_range_max = 2.0;
    const PlanarTrajectory estimate = Weaving(false);
    const PlanarTrajectory correction = Weaving(true);
    const std::string finding = "turns where the estimate does not";
    const Verdict bent = JudgeCorrection(estimate, &field, road, Result(Weaving(true, true)),
                                         nullptr, false, false, VerdictConfig{});
    EXPECT_EQ(bent.level, VerdictLevel::kDegraded);
    EXPECT_TRUE(HasReason(bent, finding));
    EXPECT_TRUE(bent.pose_flags[540] & kPoseTurnUnsupported);
    EXPECT_FALSE(bent.pose_flags[300] & kPoseTurnUnsupported);
    EXPECT_FALSE(bent.pose_flags[800] & kPoseTurnUnsupported);
    const PlanarTrajectory turned =
        ApplyPlacement(ScaleAbout(correction, Eigen::Vector2d::Zero(), 0.0, 1.05),
                       Eigen::Vector2d::Zero(), AnchorPlacement{0.3, Eigen::Vector2d(5.0, -3.0)});
    const Verdict same = JudgeCorrection(estimate, &field, road, Result(turned), nullptr, false,
                                         false, VerdictConfig{});
    EXPECT_FALSE(HasReason(same, finding));
    for (std::uint8_t flags : same.pose_flags) EXPECT_FALSE(flags & kPoseTurnUnsupported);
}

// An input with a gap in its times (a tracker lost for 2.2 s: ten poses missing from the
// estimate and so from its correction) whose correction placed the drive after the gap 4 m to
// the side: the step over the gap is a 20 m chord, whose direction the correction turned by
// 0.2 rad with its end. That is not a turn the correction made where the estimate did not.
TEST(VerdictRoads, AStepOverAGapInTheInputIsNotATurn) {
    const TraversableField field = Streets({1000.0});
    ModelConfig road;
    road.map_giveup_m = 1000.0;
    road.scale_range_min = 0.5, road.scale_range_max = 2.0;
    const auto without_gap = [](const PlanarTrajectory& t, const Eigen::Vector2d& shift) {
        PlanarTrajectory out;
        for (std::size_t i = 0; i < t.size(); ++i) {
            if (i > 300 && i <= 310) continue;
            out.t_s.push_back(t.t_s[i]);
            out.p_en.push_back(t.p_en[i] + (i > 310 ? shift : Eigen::Vector2d::Zero()));
            out.up_m.push_back(t.up_m[i]);
            out.yaw_rad.push_back(t.yaw_rad[i]);
        }
        return out;
    };
    const PlanarTrajectory estimate = without_gap(Weaving(false), Eigen::Vector2d::Zero());
    const PlanarTrajectory corrected = without_gap(Weaving(true), Eigen::Vector2d(0.0, 4.0));
    const Verdict v = JudgeCorrection(estimate, &field, road, Result(corrected), nullptr, false,
                                      false, VerdictConfig{});
    EXPECT_FALSE(HasReason(v, "turns where the estimate does not"));
    for (std::uint8_t flags : v.pose_flags) EXPECT_FALSE(flags & kPoseTurnUnsupported);
}

}  // namespace
}  // namespace driftcorr
