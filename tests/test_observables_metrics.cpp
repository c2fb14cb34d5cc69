// Tests of the step observations (core/src/observables.cpp), the accuracy metrics
// (core/src/metrics.cpp) and the frame conventions (core/src/frames.cpp), all on hand-built
// trajectories whose answers can be worked out on paper.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"
#include "driftcorr/core/frames.h"
#include "driftcorr/core/metrics.h"
#include "driftcorr/core/observables.h"

namespace driftcorr {
namespace {

constexpr double kTol = 1e-12;

PlanarTrajectory MakePlanar(const std::vector<Eigen::Vector2d>& p, std::vector<double> yaw = {},
                            std::vector<double> up = {}) {
    PlanarTrajectory t;
    for (std::size_t i = 0; i < p.size(); ++i) t.t_s.push_back(0.5 * double(i));
    t.p_en = p;
    t.up_m = up.empty() ? std::vector<double>(p.size(), 0.0) : up;
    t.yaw_rad = std::move(yaw);
    return t;
}

// ---- Observations ----------------------------------------------------------------------------

// A broken invariant is an exception naming the file, the line, the condition and the message (no
// output from core); a kept one costs nothing.
TEST(Check, ABrokenInvariantThrowsWithFileLineAndCondition) {
    EXPECT_NO_THROW(DRIFTCORR_CHECK(1 + 1 == 2, "arithmetic"));
    try {
        DRIFTCORR_CHECK(1 + 1 == 3, "arithmetic");
        FAIL() << "no exception";
    } catch (const InvariantError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("test_observables_metrics.cpp:"), std::string::npos) << what;
        EXPECT_NE(what.find("1 + 1 == 3: arithmetic"), std::string::npos) << what;
    }
}

// A level walk at 1 Hz with +-0.15 m of barometer ripple, a 6 m climb from t = 30 to 42, level
// again. A pose is level when its +-10 s hold at most 0.9 m of height change: the level span
// ends at t = 21 (its +-10 s reach 0.35 m up the climb) and starts again at t = 51 (they reach
// back to 5.35 m); the arrays' ends cut the spans short.
TEST(Observables, LevelSpansEndAWindowHalfBeforeAClimbAndStartOneAfter) {
    std::vector<double> t, up;
    for (int k = 0; k <= 80; ++k) {
        t.push_back(k);
        const double ripple = (k % 2 == 0) ? 0.15 : -0.15;
        up.push_back(ripple + (k <= 30 ? 0.0 : k >= 42 ? 6.0 : 0.5 * (k - 30)));
    }
    const std::vector<std::uint8_t> level = LevelSpans(t, up, 20.0, 0.9);
    ASSERT_EQ(level.size(), t.size());
    for (int k = 0; k <= 21; ++k) EXPECT_TRUE(level[k]) << k;
    for (int k = 22; k <= 50; ++k) EXPECT_FALSE(level[k]) << k;
    for (int k = 51; k <= 80; ++k) EXPECT_TRUE(level[k]) << k;
    // A profile of one sample is level; an empty one has no poses.
    EXPECT_TRUE(LevelSpans({0.0}, {3.0}, 20.0, 1.0)[0]);
    EXPECT_TRUE(LevelSpans({}, {}, 20.0, 1.0).empty());
}

// Appends a step observation (dt, length, height change; stationary when it does not move) and
// returns the pose it leads into.
std::size_t AddStep(std::vector<StepObservation>& obs, double dt, double length, double dup) {
    StepObservation o;
    o.dt_s = dt, o.length_m = length, o.dup_m = dup, o.stationary = length < 1e-3;
    obs.push_back(o);
    return obs.size() - 1;
}

// Steps of 0.6 m every 0.5 s, and in between: a 10 s wait (one step of 10 s, level), a lift ride
// (a step into the cabin, 12 s standing, 8 s standing while the barometer reads 10 m, the last
// 2 m of it 1 s after the ride: its lag), a 2 s stop while the height jumps 3 m (too short for a
// ride), and a stair climb (walking steps of 0.2 m up each). Only the ride's poses are rides.
TEST(Observables, RideSpansFindTheLiftRideNotAWaitAStopOrAClimb) {
    std::vector<StepObservation> obs(1);
    auto add = [&obs](double dt, double length, double dup) {
        return AddStep(obs, dt, length, dup);
    };
    auto walk = [&](int steps, double dup) {
        for (int k = 0; k < steps; ++k) add(0.5, 0.6, dup);
    };
    walk(5, 0.0);
    add(10.0, 0.4, 0.0);  // the wait
    walk(5, 0.0);
    const std::size_t cabin = add(0.5, 0.6, 0.0);  // into the cabin
    add(12.0, 0.0, 0.0);
    const std::size_t out = add(8.0, 0.0, 8.0);
    add(1.0, 0.6, 2.0);  // out of the cabin, the barometer catching up
    walk(5, 0.0);
    add(2.0, 0.0, 3.0);  // the short stop
    walk(5, 0.0);
    walk(20, 0.2);  // the stairs
    walk(5, 0.0);
    const std::vector<std::uint8_t> ride = RideSpans(obs, 5.0, 2.0, 3.0, 5.0);
    ASSERT_EQ(ride.size(), obs.size());
    for (std::size_t i = 0; i < obs.size(); ++i) {
        EXPECT_EQ(ride[i], i >= cabin && i <= out ? 1 : 0) << "pose " << i;
    }
    // Read without the lag, the ride changes height by 8 m, still a ride; asked for 9 m it is not.
    EXPECT_EQ(RideSpans(obs, 5.0, 9.0, 3.0, 0.0)[cabin], 0);
    EXPECT_EQ(RideSpans(obs, 5.0, 9.0, 3.0, 5.0)[cabin], 1);
}

// Steps of 0.7 m every 0.6 s: a level walk, a stair climb of 24 risers (0.17 m a step, read
// 0.8x by the barometer), a level walk, a lift ride (standing 15 s while the barometer reads 12 m,
// the last 1.5 m on the first two steps out: its lag, which MoveRideLag moves into the ride
// first, as the correction does) and a level walk with a pressure jump of 0.5 m over two steps.
// The climb's steps become treads of 0.45 m (its first and last two may not: the window around
// them climbs for part of its span); the ride, the steps out of it, the jump and the level walk
// do not.
TEST(Observables, StepsAmidAStairClimbAreTreads) {
    std::vector<StepObservation> obs(1);
    auto walk = [&obs](int steps, double dup) {
        std::size_t last = 0;
        for (int k = 0; k < steps; ++k) last = AddStep(obs, 0.6, 0.7, dup);
        return last;
    };
    walk(20, 0.0);
    const std::size_t climb_first = obs.size();
    const std::size_t climb_last = walk(24, 0.8 * 0.17);
    walk(20, 0.0);
    AddStep(obs, 15.0, 0.0, 10.5);  // the ride
    const std::size_t out = walk(2, 0.75);
    walk(20, 0.0);
    const std::size_t jump = walk(2, 0.25);
    walk(20, 0.0);
    std::vector<StepObservation> unmoved = obs;
    EXPECT_EQ(MoveRideLag(obs, 5.0, 2.0, 3.0, 5.0), 1u);
    const std::vector<StepObservation> before = obs;
    const std::size_t treads = MarkStairTreads(obs, 0.45, 4.0, 0.15, 3.0);
    EXPECT_GE(treads, 20u);
    EXPECT_LE(treads, 28u);
    for (std::size_t i = 1; i < obs.size(); ++i) {
        if (i >= climb_first + 2 && i + 2 <= climb_last) EXPECT_TRUE(obs[i].tread) << "pose " << i;
        if (i + 2 < climb_first || i > climb_last + 2) EXPECT_FALSE(obs[i].tread) << "pose " << i;
        EXPECT_EQ(obs[i].length_m, obs[i].tread ? 0.45 : before[i].length_m) << "pose " << i;
        EXPECT_EQ(obs[i].observed_length_m, obs[i].tread ? 0.7 : 0.0) << "pose " << i;
        EXPECT_EQ(obs[i].dup_m, before[i].dup_m);
        EXPECT_EQ(obs[i].dt_s, before[i].dt_s);
    }
    EXPECT_FALSE(obs[out].tread);
    EXPECT_FALSE(obs[jump].tread);
    // Marked once: a second pass finds nothing new. A threshold above the climb's rate finds none.
    EXPECT_EQ(MarkStairTreads(obs, 0.45, 4.0, 0.15, 3.0), 0u);
    std::vector<StepObservation> slow = before;
    EXPECT_EQ(MarkStairTreads(slow, 0.45, 4.0, 0.3, 3.0), 0u);
    // Left in the steps out, the ride's lag reads as a climb there (1.5 m over 1.2 s of walking).
    EXPECT_GT(MarkStairTreads(unmoved, 0.45, 4.0, 0.15, 3.0), treads);
    EXPECT_TRUE(unmoved[out].tread);
    // The run of a tread is its own: scaled, a level step moves scale x length, a tread its run.
    EXPECT_DOUBLE_EQ(ScaledLength(obs[climb_first + 5], 1.4), 0.45);
    EXPECT_DOUBLE_EQ(ScaledLength(obs[1], 1.4), 1.4 * 0.7);
}

// A lift ride read with lag: 1 m while waiting at the door, 9 m during the ride, 1.5 m during
// the 2 s standing after it, then 0.8, 0.4 and 0.2 m over the first steps out (0.5 s each), and a
// stair climb 10 s later. What comes after the ride's step (2.9 m) moves into it, the walk after
// it is level, the door's reading and the climb keep theirs; total height change and every other
// observation unchanged. A source that reports in the cabin at a fixed rate keeps its ramp.
TEST(Observables, MoveRideLagPutsTheLaggedReadingIntoTheRide) {
    std::vector<StepObservation> obs(1);
    auto add = [&obs](double dt, double length, double dup) {
        return AddStep(obs, dt, length, dup);
    };
    for (int k = 0; k < 5; ++k) add(0.5, 0.6, 0.0);
    add(0.5, 0.6, 0.0);  // into the cabin
    add(8.0, 0.0, 1.0);  // the door closes
    const std::size_t ride = add(10.0, 0.0, 9.0);
    const std::size_t stand = add(2.0, 0.0, 1.5);
    const std::size_t out = add(0.5, 0.6, 0.8);
    add(0.5, 0.6, 0.4);
    add(0.5, 0.6, 0.2);
    for (int k = 0; k < 20; ++k) add(0.5, 0.6, 0.0);
    const std::size_t climb = add(0.5, 0.6, 0.2);
    for (int k = 0; k < 5; ++k) add(0.5, 0.6, 0.2);
    const std::vector<StepObservation> before = obs;
    EXPECT_EQ(MoveRideLag(obs, 5.0, 2.0, 3.0, 5.0), 1u);
    double total_before = 0.0, total_after = 0.0;
    for (std::size_t i = 1; i < obs.size(); ++i) {
        total_before += before[i].dup_m, total_after += obs[i].dup_m;
        EXPECT_EQ(obs[i].dt_s, before[i].dt_s);
        EXPECT_EQ(obs[i].length_m, before[i].length_m);
        if (i == ride) {
            EXPECT_NEAR(obs[i].dup_m, 11.9, 1e-12);
        } else if (i == ride - 1) {
            EXPECT_EQ(obs[i].dup_m, 1.0);
        } else if (i >= climb) {
            EXPECT_EQ(obs[i].dup_m, 0.2) << i;
        } else {
            EXPECT_EQ(obs[i].dup_m, 0.0) << i;
        }
    }
    EXPECT_NEAR(total_after, total_before, 1e-12);
    EXPECT_GT(before[stand].dup_m + before[out].dup_m, 0.0);
    // Read without lag, the steps out keep their reading; a walk without a ride is left alone.
    std::vector<StepObservation> no_lag = before;
    EXPECT_EQ(MoveRideLag(no_lag, 5.0, 2.0, 3.0, 0.0), 1u);
    EXPECT_NEAR(no_lag[ride].dup_m, 10.5, 1e-12);
    EXPECT_EQ(no_lag[out].dup_m, 0.8);
    // Cabin poses every 0.5 s, 0.5 m each, then 0.2 and 0.1 m of lag standing: the ramp stays.
    std::vector<StepObservation> cabin(1);
    auto step = [&cabin](double dt, double length, double dup) { AddStep(cabin, dt, length, dup); };
    for (int k = 0; k < 5; ++k) step(0.5, 0.6, 0.0);
    for (int k = 0; k < 12; ++k) step(0.5, 0.0, 0.5);
    step(0.5, 0.0, 0.2);
    step(0.5, 0.0, 0.1);
    for (int k = 0; k < 5; ++k) step(0.5, 0.6, 0.0);
    EXPECT_EQ(MoveRideLag(cabin, 5.0, 2.0, 3.0, 5.0), 1u);
    for (int k = 6; k <= 16; ++k) EXPECT_EQ(cabin[k].dup_m, 0.5) << k;
    EXPECT_NEAR(cabin[17].dup_m, 0.8, 1e-12);
    EXPECT_EQ(cabin[18].dup_m, 0.0);
    EXPECT_EQ(cabin[19].dup_m, 0.0);
    std::vector<StepObservation> stairs(before.begin() + climb - 1, before.end());
    const std::vector<StepObservation> stairs_before = stairs;
    EXPECT_EQ(MoveRideLag(stairs, 5.0, 2.0, 3.0, 5.0), 0u);
    for (std::size_t i = 1; i < stairs.size(); ++i) {
        EXPECT_EQ(stairs[i].dup_m, stairs_before[i].dup_m);
    }
}

TEST(Observables, SquareWithYawHasKnownLengthsTurnsAndUnwrappedHeadings) {
    // A 10 m square driven counter-clockwise, facing along each side; the yaw of pose 3 is given
    // wrapped (-pi/2), the unwrapped headings climb to 2 pi.
    const PlanarTrajectory t = MakePlanar({{0, 0}, {10, 0}, {10, 10}, {0, 10}, {0, 0}},
                                          {0.0, kPi / 2, kPi, -kPi / 2, 0.0}, {0, 0, 1, 1, 0});
    const std::vector<double> yaw = UnwrappedHeadings(t);
    ASSERT_EQ(yaw.size(), 5u);
    for (int i = 0; i < 5; ++i) EXPECT_NEAR(yaw[i], i * kPi / 2, kTol) << "pose " << i;

    const std::vector<StepObservation> obs = ComputeObservations(t);
    ASSERT_EQ(obs.size(), 5u);
    EXPECT_EQ(obs[0].length_m, 0.0);
    EXPECT_EQ(obs[0].dheading_rad, 0.0);
    for (int i = 1; i < 5; ++i) {
        EXPECT_NEAR(obs[i].dt_s, 0.5, kTol);
        EXPECT_NEAR(obs[i].length_m, 10.0, kTol) << "step " << i;
        EXPECT_NEAR(obs[i].direction_rad, 0.0, 1e-9) << "step " << i;
        EXPECT_NEAR(obs[i].dheading_rad, kPi / 2, kTol) << "step " << i;
        EXPECT_FALSE(obs[i].stationary);
    }
    EXPECT_NEAR(obs[1].dup_m, 0.0, kTol);
    EXPECT_NEAR(obs[2].dup_m, 1.0, kTol);
    EXPECT_NEAR(obs[4].dup_m, -1.0, kTol);
}

TEST(Observables, DirectionIsRelativeToThePreviousHeading) {
    // Facing East throughout while moving North then North-West: a crab walk.
    const PlanarTrajectory t = MakePlanar({{0, 0}, {0, 2}, {-3, 5}}, {0.0, 0.0, 0.0});
    const std::vector<StepObservation> obs = ComputeObservations(t);
    EXPECT_NEAR(obs[1].direction_rad, kPi / 2, kTol);
    EXPECT_NEAR(obs[1].length_m, 2.0, kTol);
    EXPECT_NEAR(obs[2].direction_rad, 3 * kPi / 4, kTol);
    EXPECT_NEAR(obs[2].length_m, 3.0 * std::sqrt(2.0), kTol);
    EXPECT_NEAR(obs[2].dheading_rad, 0.0, kTol);
}

TEST(Observables, WithoutYawHeadingsFollowStepDirections) {
    // The square again, no orientation: pose i looks along step i -> i+1; the last pose keeps
    // the last step's direction. Every step then has direction 0; the turns land on the corners.
    const PlanarTrajectory t =
        MakePlanar({{0, 0}, {5, 0}, {10, 0}, {10, 5}, {10, 10}, {5, 10}, {0, 10}});
    const std::vector<double> yaw = UnwrappedHeadings(t);
    const std::vector<double> expected = {0, 0, kPi / 2, kPi / 2, kPi, kPi, kPi};
    ASSERT_EQ(yaw.size(), expected.size());
    for (std::size_t i = 0; i < yaw.size(); ++i) EXPECT_NEAR(yaw[i], expected[i], kTol) << i;
    const std::vector<StepObservation> obs = ComputeObservations(t);
    for (std::size_t i = 1; i < obs.size(); ++i) {
        EXPECT_NEAR(obs[i].length_m, 5.0, kTol) << "step " << i;
        EXPECT_NEAR(obs[i].direction_rad, 0.0, kTol) << "step " << i;
        EXPECT_NEAR(obs[i].dheading_rad, expected[i] - expected[i - 1], kTol) << "step " << i;
    }
}

TEST(Observables, StopIsStationaryAndHeadingIsCarriedAcrossIt) {
    // East 2 m, stop for two steps (one exact repeat, one 0.5 mm jitter), then North.
    const PlanarTrajectory t =
        MakePlanar({{0, 0}, {1, 0}, {2, 0}, {2, 0}, {2.0005, 0}, {2.0005, 1}, {2.0005, 2}});
    const std::vector<double> yaw = UnwrappedHeadings(t);
    // Poses 2..4 look along the next moving step (North), across the stop.
    const std::vector<double> expected = {0, 0, kPi / 2, kPi / 2, kPi / 2, kPi / 2, kPi / 2};
    for (std::size_t i = 0; i < yaw.size(); ++i) EXPECT_NEAR(yaw[i], expected[i], kTol) << i;

    const std::vector<StepObservation> obs = ComputeObservations(t, 1e-3);
    for (int i : {3, 4}) {
        EXPECT_TRUE(obs[i].stationary) << "step " << i;
        EXPECT_EQ(obs[i].length_m, 0.0) << "step " << i;
        EXPECT_EQ(obs[i].direction_rad, 0.0) << "step " << i;
        EXPECT_NEAR(obs[i].dheading_rad, 0.0, kTol) << "step " << i;
    }
    for (int i : {1, 2, 5, 6}) EXPECT_FALSE(obs[i].stationary) << "step " << i;
    EXPECT_NEAR(obs[2].dheading_rad, kPi / 2, kTol);  // the turn lands before the stop
    EXPECT_NEAR(obs[5].direction_rad, 0.0, kTol);     // carried heading matches the departure
    // Total turn across the whole trajectory is preserved.
    double total = 0.0;
    for (const auto& o : obs) total += o.dheading_rad;
    EXPECT_NEAR(total, kPi / 2, kTol);
}

TEST(Observables, StopWithYawKeepsTheGivenHeadings) {
    const PlanarTrajectory t =
        MakePlanar({{0, 0}, {1, 0}, {1, 0}, {1, 0}, {2, 0}}, {0.1, 0.1, 0.3, 0.3, 0.3});
    const std::vector<StepObservation> obs = ComputeObservations(t);
    EXPECT_TRUE(obs[2].stationary);
    EXPECT_TRUE(obs[3].stationary);
    EXPECT_NEAR(obs[2].dheading_rad, 0.2, kTol);  // turning on the spot is still observed
    EXPECT_NEAR(obs[3].dheading_rad, 0.0, kTol);
    EXPECT_NEAR(obs[4].direction_rad, -0.3, kTol);
    EXPECT_NEAR(obs[1].direction_rad, -0.1, kTol);
}

TEST(Observables, HeadingsUnwrapAcrossPlusMinusPi) {
    const PlanarTrajectory t =
        MakePlanar({{0, 0}, {-1, 0}, {-2, 0}, {-3, 0}}, {3.0, -3.0, 3.1, -3.1});
    const std::vector<double> yaw = UnwrappedHeadings(t);
    EXPECT_NEAR(yaw[0], 3.0, kTol);
    EXPECT_NEAR(yaw[1], 2 * kPi - 3.0, 1e-12);
    EXPECT_NEAR(yaw[2], 3.1, 1e-12);
    EXPECT_NEAR(yaw[3], 2 * kPi - 3.1, 1e-12);
    const std::vector<StepObservation> obs = ComputeObservations(t);
    EXPECT_NEAR(obs[1].dheading_rad, 2 * kPi - 6.0, 1e-12);
    EXPECT_NEAR(obs[2].dheading_rad, 6.1 - 2 * kPi, 1e-12);
    // Moving West (atan2 = pi) while facing 3.0 rad: direction pi - 3.0, wrapped small.
    EXPECT_NEAR(obs[1].direction_rad, kPi - 3.0, 1e-12);
    EXPECT_NEAR(obs[2].direction_rad, kPi - (2 * kPi - 3.0), 1e-12);
}

TEST(Observables, WithoutYawUnwrapsWestboundZigZag) {
    // Steps heading just above and just below West alternate between +pi and -pi directions.
    const PlanarTrajectory t = MakePlanar({{0, 0}, {-1, 0.01}, {-2, 0}, {-3, 0.01}, {-4, 0}});
    const std::vector<double> yaw = UnwrappedHeadings(t);
    for (std::size_t i = 1; i < yaw.size(); ++i) {
        EXPECT_LT(std::abs(yaw[i] - yaw[i - 1]), 0.1) << "jump at pose " << i;
    }
}

// ---- Metrics ---------------------------------------------------------------------------------

/// Steps of a straight drive at 10 Hz whose speed [m/s] per step is speed(i).
template <typename F>
std::vector<StepObservation> Steps(std::size_t n, F speed) {
    std::vector<StepObservation> obs(n);
    for (std::size_t i = 1; i < n; ++i) {
        obs[i].dt_s = 0.1;
        obs[i].length_m = 0.1 * speed(i);
    }
    return obs;
}

TEST(RepairSpeedEpisodes, DroppedEpisodeIsObservedAtTheSpeedAroundIt) {
    // 10 m/s; steps 100..119 (2 s) report 40 % of their motion.
    auto obs = Steps(300, [](std::size_t i) { return i >= 100 && i < 120 ? 4.0 : 10.0; });
    EXPECT_EQ(RepairSpeedEpisodes(obs, 10.0, 0.3, 10.0, 0.25), 1u);
    for (std::size_t i = 1; i < obs.size(); ++i) {
        const bool dropped = i >= 100 && i < 120;
        EXPECT_EQ(obs[i].repaired, dropped) << "step " << i;
        EXPECT_NEAR(obs[i].length_m, 1.0, 1e-9) << "step " << i;
        if (dropped) EXPECT_NEAR(obs[i].observed_length_m, 0.4, 1e-12);
    }
}

TEST(RepairSpeedEpisodes, PhysicalSpeedChangesAreKept) {
    // Braking at 8 m/s^2 from 20 m/s to a stop, waiting, accelerating at 3 m/s^2.
    auto speed = [](std::size_t i) {
        const double t = 0.1 * double(i);
        if (t < 5.0) return 20.0;
        if (t < 7.5) return 20.0 - 8.0 * (t - 5.0);
        if (t < 12.0) return 0.0;
        return std::min(15.0, 3.0 * (t - 12.0));
    };
    auto obs = Steps(300, speed);
    const auto before = obs;
    EXPECT_EQ(RepairSpeedEpisodes(obs, 10.0, 0.3, 10.0, 0.25), 0u);
    for (std::size_t i = 1; i < obs.size(); ++i) {
        EXPECT_FALSE(obs[i].repaired) << "step " << i;
        EXPECT_EQ(obs[i].length_m, before[i].length_m);
    }
}

TEST(RepairSpeedEpisodes, LoneEdgesAndDoubledEpisodesAreNotRepaired) {
    // A speed that drops and stays (nothing tells which side is wrong), and a rise that comes
    // back down (doubled steps are left to the step terms).
    auto lone = Steps(300, [](std::size_t i) { return i < 150 ? 10.0 : 4.0; });
    EXPECT_EQ(RepairSpeedEpisodes(lone, 10.0, 0.3, 10.0, 0.25), 0u);
    auto doubled = Steps(300, [](std::size_t i) { return i >= 100 && i < 120 ? 20.0 : 10.0; });
    EXPECT_EQ(RepairSpeedEpisodes(doubled, 10.0, 0.3, 10.0, 0.25), 0u);
    // A drop that recovers only after max_episode_s is not an episode either.
    auto long_drop = Steps(400, [](std::size_t i) { return i >= 100 && i < 250 ? 4.0 : 10.0; });
    EXPECT_EQ(RepairSpeedEpisodes(long_drop, 10.0, 0.3, 10.0, 0.25), 0u);
    for (const auto& o : long_drop) EXPECT_FALSE(o.repaired);
}

// Steps of 0.5 s: lengths 0.5, 0.6, ..., 0.9 m, a stop, a tread, a repaired step and a jump.
TEST(ReadAtGait, MovingStepsAreReadAboutTheirMedianTheRestAsRead) {
    std::vector<StepObservation> obs(10);
    const double lengths[] = {0.0, 0.5, 0.6, 0.7, 0.8, 0.9, 0.0, 0.3, 0.4, 20.0};
    for (std::size_t i = 1; i < obs.size(); ++i) {
        obs[i].dt_s = 0.5;
        obs[i].length_m = lengths[i];
    }
    obs[6].stationary = true;
    obs[7].tread = true;
    obs[8].repaired = true;
    const double max_speed_mps = 10.0;  // step 9 (40 m/s) is a jump
    for (std::size_t i = 1; i < obs.size(); ++i) {
        EXPECT_EQ(GaitStep(obs[i], max_speed_mps), i <= 5) << "step " << i;
    }
    const double median_m = MedianGaitStep(obs, max_speed_mps);
    EXPECT_DOUBLE_EQ(median_m, 0.7);
    const auto before = obs;
    for (StepObservation& o : obs) ReadAtGait(o, median_m, 0.25, max_speed_mps);
    for (std::size_t i = 1; i < obs.size(); ++i) {
        if (i > 5) {
            EXPECT_EQ(obs[i].length_m, before[i].length_m) << "step " << i;
            continue;
        }
        // The log length moves three quarters of the way to the median's, and no further.
        EXPECT_NEAR(std::log(obs[i].length_m / median_m),
                    0.25 * std::log(before[i].length_m / median_m), 1e-12)
            << "step " << i;
        EXPECT_EQ(obs[i].observed_length_m, before[i].length_m);
    }
    auto as_read = before;
    for (StepObservation& o : as_read) ReadAtGait(o, median_m, 1.0, max_speed_mps);
    for (std::size_t i = 0; i < obs.size(); ++i) EXPECT_EQ(as_read[i].length_m, lengths[i]);
    std::vector<StepObservation> stops(3);  // no moving step: no median, nothing read anew
    EXPECT_EQ(MedianGaitStep(stops, max_speed_mps), 0.0);
}

// After every value, the running median is the element at index size / 2 of the values sorted
// (ties and an even count included), as MedianGaitStep takes it.
TEST(RunningMedian, IsTheUpperMedianOfTheValuesSoFar) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> pick(0, 20);  // small range: many ties
    RunningMedian running;
    std::vector<double> values;
    for (int k = 0; k < 500; ++k) {
        const double v = 0.05 * pick(rng);
        running.Add(v);
        values.push_back(v);
        std::vector<double> sorted = values;
        std::sort(sorted.begin(), sorted.end());
        ASSERT_EQ(running.Median(), sorted[sorted.size() / 2]) << "after " << values.size();
    }
}

TEST(Metrics, TenPoseExampleWithKnownErrors) {
    // Ground truth along East every 10 m; the estimate is off by e_i metres in the direction
    // (0.6, 0.8), and its height is off by 2 m on poses 2, 5 and 7 (1.5 m on pose 9: on floor).
    const std::vector<double> e = {1, 0, 3, 2, 5, 4, 9, 6, 8, 7};
    std::vector<Eigen::Vector2d> p_gt, p;
    std::vector<double> up_gt(10, 3.0), up(10, 3.0);
    for (int i = 0; i < 10; ++i) {
        p_gt.emplace_back(10.0 * i, 0.0);
        p.push_back(p_gt.back() + e[i] * Eigen::Vector2d(0.6, 0.8));
    }
    up[2] += 2.0, up[5] -= 2.0, up[7] += 2.0, up[9] += 1.5;
    const PlanarTrajectory gt = MakePlanar(p_gt, {}, up_gt), est = MakePlanar(p, {}, up);

    const std::vector<double> errs = HorizontalErrors(est, gt);
    for (int i = 0; i < 10; ++i) EXPECT_NEAR(errs[i], e[i], 1e-12);

    const ErrorMetrics m = ComputeMetrics(est, gt);
    EXPECT_EQ(m.poses, 10u);
    EXPECT_NEAR(m.ate_m, std::sqrt(285.0 / 10.0), 1e-12);  // sum of 0..9 squared = 285
    EXPECT_NEAR(m.mean_m, 4.5, 1e-12);
    EXPECT_NEAR(m.final_m, 7.0, 1e-12);
    EXPECT_NEAR(m.max_m, 9.0, 1e-12);
    EXPECT_NEAR(m.p90_m, 8.0, 1e-12);  // 9th of 10 sorted errors
    EXPECT_NEAR(m.floor_accuracy, 0.7, 1e-12);
    EXPECT_NEAR(m.path_length_m, 90.0, 1e-12);
    EXPECT_EQ(m.drift_pct, 0.0);  // path shorter than the shortest 100 m segment
}

TEST(Metrics, PerfectTrajectoryScoresZero) {
    std::vector<Eigen::Vector2d> p;
    for (int i = 0; i < 150; ++i) p.emplace_back(2.0 * i, 0.01 * i * i);
    const PlanarTrajectory gt = MakePlanar(p);
    const ErrorMetrics m = ComputeMetrics(gt, gt);
    EXPECT_EQ(m.ate_m, 0.0);
    EXPECT_EQ(m.max_m, 0.0);
    EXPECT_EQ(m.p90_m, 0.0);
    EXPECT_NEAR(m.drift_pct, 0.0, 1e-9);
    EXPECT_EQ(m.floor_accuracy, 1.0);
    EXPECT_GT(m.path_length_m, 100.0);
}

TEST(Metrics, DriftOfAUniformlyScaledStraightLine) {
    // Straight East at 1 m steps for 301 m; the estimate is 2% too long. Every 100..300 m
    // segment of ground truth is covered 2% too far: drift 2%.
    std::vector<Eigen::Vector2d> p_gt, p;
    for (int i = 0; i <= 300; ++i) {
        p_gt.emplace_back(double(i), 0.0);
        p.emplace_back(1.02 * i, 0.0);
    }
    const ErrorMetrics m = ComputeMetrics(MakePlanar(p), MakePlanar(p_gt));
    EXPECT_NEAR(m.drift_pct, 2.0, 1e-9);
    EXPECT_NEAR(m.final_m, 6.0, 1e-9);
    EXPECT_NEAR(m.path_length_m, 300.0, 1e-9);
}

TEST(Metrics, DistanceTravelledAccumulatesHorizontalSteps) {
    const PlanarTrajectory gt = MakePlanar({{0, 0}, {3, 4}, {3, 4}, {3, 10}}, {}, {0, 5, 9, 0});
    const std::vector<double> s = DistanceTravelled(gt);
    ASSERT_EQ(s.size(), 4u);
    EXPECT_NEAR(s[0], 0.0, kTol);
    EXPECT_NEAR(s[1], 5.0, kTol);
    EXPECT_NEAR(s[2], 5.0, kTol);
    EXPECT_NEAR(s[3], 11.0, kTol);
}

TEST(Metrics, VerticalRmsIsTheHeightsError) {
    const PlanarTrajectory gt = MakePlanar({{0, 0}, {1, 0}, {2, 0}, {3, 0}}, {}, {0, 0, 0, 0});
    const PlanarTrajectory t = MakePlanar({{0, 0}, {1, 0}, {2, 0}, {3, 0}}, {}, {0, 3, -3, 0});
    EXPECT_NEAR(ComputeMetrics(t, gt).vertical_rms_m, std::sqrt(18.0 / 4.0), kTol);
    EXPECT_NEAR(ComputeMetrics(t, gt).ate_m, 0.0, kTol);
}

// A stretch steeper than the bound has its height change scaled down to it, the heights inside
// alike, and the later stretches follow on; gentler stretches keep theirs.
TEST(BoundGrades, OnlyStretchesSteeperThanTheBoundChange) {
    std::vector<Eigen::Vector2d> en;
    std::vector<double> up;
    for (int i = 0; i <= 100; ++i) {  // 1 m steps: 0-50 m climbs 30 %, 50-100 m climbs 5 %
        en.emplace_back(double(i), 0.0);
        up.push_back(i <= 50 ? 0.3 * i : 15.0 + 0.05 * (i - 50));
    }
    std::vector<double> bounded = up;
    const GradeBound b = BoundGrades(en, 25.0, 0.10, bounded);
    EXPECT_EQ(b.stretches, 4u);
    EXPECT_EQ(b.limited, 2u);
    EXPECT_NEAR(bounded[25], 2.5, 1e-12);
    EXPECT_NEAR(bounded[10], 1.0, 1e-12);  // inside the stretch: scaled alike
    EXPECT_NEAR(bounded[50], 5.0, 1e-12);
    EXPECT_NEAR(bounded[100], 5.0 + 2.5, 1e-12);  // the gentle half climbs as estimated
    EXPECT_NEAR(bounded[75] - bounded[50], up[75] - up[50], 1e-12);
    // Falling is bounded alike; no bound, or no stretch beyond it, changes nothing.
    std::vector<double> down = up;
    for (double& h : down) h = -h;
    EXPECT_EQ(BoundGrades(en, 25.0, 0.10, down).limited, 2u);
    EXPECT_NEAR(down[50], -5.0, 1e-12);
    std::vector<double> same = up;
    EXPECT_EQ(BoundGrades(en, 25.0, 0.0, same).limited, 0u);
    EXPECT_EQ(same, up);
    EXPECT_EQ(BoundGrades(en, 25.0, 0.35, same).limited, 0u);
    EXPECT_EQ(same, up);
}

// ---- Frames ----------------------------------------------------------------------------------

/// Random poses; bodies turned about the frame's Up axis by a random heading, tilted a little.
Trajectory RandomTrajectory(unsigned seed, int n, FrameAxes axes) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Trajectory t;
    for (int i = 0; i < n; ++i) {
        t.t_s.push_back(0.1 * i);
        t.p_frame.emplace_back(50.0 * u(rng), 5.0 * u(rng), 50.0 * u(rng));
        const Eigen::Quaterniond q(Eigen::AngleAxisd(kPi * u(rng), FrameUpAxis(axes)) *
                                   Eigen::AngleAxisd(0.2 * u(rng), Eigen::Vector3d::UnitX()) *
                                   Eigen::AngleAxisd(0.2 * u(rng), Eigen::Vector3d::UnitZ()));
        t.q_frame_body.push_back(q.normalized());
    }
    return t;
}

double AngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
    return a.angularDistance(b);
}

class FrameRoundTrip : public ::testing::TestWithParam<FrameAxes> {};

TEST_P(FrameRoundTrip, ToPlanarThenFromPlanarIsIdentity) {
    PlanarAnchor anchor;
    anchor.yaw_rad = 0.7;
    anchor.origin_en = Eigen::Vector2d(1250.0, -340.0);
    anchor.origin_up_m = 12.5;
    const Trajectory traj = RandomTrajectory(4242u, 40, GetParam());
    const PlanarTrajectory planar = ToPlanar(traj, GetParam(), anchor);
    ASSERT_TRUE(planar.HasYaw());
    const Trajectory back = FromPlanar(planar, planar, traj, GetParam(), anchor);
    ASSERT_EQ(back.size(), traj.size());
    ASSERT_TRUE(back.HasOrientation());
    for (std::size_t i = 0; i < traj.size(); ++i) {
        EXPECT_LT((back.p_frame[i] - traj.p_frame[i]).norm(), 1e-9) << "pose " << i;
        EXPECT_LT(AngleBetween(back.q_frame_body[i], traj.q_frame_body[i]), 1e-9) << "pose " << i;
        EXPECT_EQ(back.t_s[i], traj.t_s[i]);
    }
}

TEST_P(FrameRoundTrip, HeadingCorrectionTurnsTheBodyByThatAngle) {
    // Correct every pose by a shift and a turn: placing the result again gives the corrected
    // positions and yaw (the turn is about Up, counter-clockwise in East-North).
    PlanarAnchor anchor;
    anchor.yaw_rad = -1.1;
    anchor.origin_en = Eigen::Vector2d(-20.0, 30.0);
    anchor.origin_up_m = -3.0;
    const Trajectory traj = RandomTrajectory(777u, 25, GetParam());
    const PlanarTrajectory reference = ToPlanar(traj, GetParam(), anchor);
    PlanarTrajectory corrected = reference;
    for (std::size_t i = 0; i < corrected.size(); ++i) {
        corrected.p_en[i] += Eigen::Vector2d(3.0, -1.0 + 0.1 * i);
        corrected.up_m[i] += 0.5;
        corrected.yaw_rad[i] += 0.3 - 0.02 * i;
    }
    const Trajectory out = FromPlanar(corrected, reference, traj, GetParam(), anchor);
    const PlanarTrajectory again = ToPlanar(out, GetParam(), anchor);
    for (std::size_t i = 0; i < corrected.size(); ++i) {
        EXPECT_LT((again.p_en[i] - corrected.p_en[i]).norm(), 1e-9) << "pose " << i;
        EXPECT_NEAR(again.up_m[i], corrected.up_m[i], 1e-9) << "pose " << i;
        EXPECT_NEAR(AngleDiff(again.yaw_rad[i], corrected.yaw_rad[i]), 0.0, 1e-9) << "pose " << i;
    }
}

TEST_P(FrameRoundTrip, WithoutOrientationRoundTripsPositions) {
    PlanarAnchor anchor;
    anchor.yaw_rad = 2.5;
    anchor.origin_en = Eigen::Vector2d(7.0, 8.0);
    Trajectory traj = RandomTrajectory(99u, 10, GetParam());
    traj.q_frame_body.clear();
    const PlanarTrajectory planar = ToPlanar(traj, GetParam(), anchor);
    EXPECT_FALSE(planar.HasYaw());
    const Trajectory back = FromPlanar(planar, planar, traj, GetParam(), anchor);
    EXPECT_FALSE(back.HasOrientation());
    for (std::size_t i = 0; i < traj.size(); ++i) {
        EXPECT_LT((back.p_frame[i] - traj.p_frame[i]).norm(), 1e-9) << "pose " << i;
    }
}

// Positions only: the corrected heading becomes a rotation about Up alone whose forward axis has
// that heading (ToPlanar of the result gives it back), with no roll or pitch.
TEST_P(FrameRoundTrip, WithoutOrientationTheCorrectedHeadingBecomesTheOrientation) {
    PlanarAnchor anchor;
    anchor.yaw_rad = -1.2;
    Trajectory traj = RandomTrajectory(7u, 10, GetParam());
    traj.q_frame_body.clear();
    PlanarTrajectory corrected = ToPlanar(traj, GetParam(), anchor);
    for (std::size_t i = 0; i < corrected.size(); ++i) corrected.yaw_rad.push_back(0.4 * i - 2.0);
    const Trajectory back = FromPlanar(corrected, corrected, traj, GetParam(), anchor);
    ASSERT_TRUE(back.HasOrientation());
    const PlanarTrajectory again = ToPlanar(back, GetParam(), anchor);
    ASSERT_TRUE(again.HasYaw());
    for (std::size_t i = 0; i < traj.size(); ++i) {
        EXPECT_NEAR(std::remainder(again.yaw_rad[i] - corrected.yaw_rad[i], 2 * M_PI), 0.0, 1e-9)
            << "pose " << i;
        const Eigen::Vector3d up = FrameUpAxis(GetParam());
        EXPECT_NEAR((back.q_frame_body[i] * up - up).norm(), 0.0, 1e-12) << "pose " << i;
    }
}

INSTANTIATE_TEST_SUITE_P(BothAxes, FrameRoundTrip,
                         ::testing::Values(FrameAxes::kKittiCamera, FrameAxes::kEnu),
                         [](const ::testing::TestParamInfo<FrameAxes>& param_info) {
                             return ToString(param_info.param);
                         });

TEST(Frames, KittiCameraForwardZIsNorthAndForwardXIsEast) {
    const PlanarAnchor anchor;  // yaw 0, origin 0
    Trajectory t;
    t.t_s = {0.0, 1.0, 2.0};
    t.p_frame = {{0, 0, 0}, {0, -1.5, 5}, {0, 0, 10}};  // moving along camera +z; y down
    const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
    const Eigen::Quaterniond to_x(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitY()));
    ASSERT_LT((to_x * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm(), 1e-12);
    t.q_frame_body = {level, to_x, level};
    const PlanarTrajectory p = ToPlanar(t, FrameAxes::kKittiCamera, anchor);
    EXPECT_LT((p.p_en[1] - Eigen::Vector2d(0.0, 5.0)).norm(), 1e-12);  // +z -> North
    EXPECT_LT((p.p_en[2] - Eigen::Vector2d(0.0, 10.0)).norm(), 1e-12);
    EXPECT_NEAR(p.up_m[1], 1.5, 1e-12);         // y down -> Up = -y
    EXPECT_NEAR(p.yaw_rad[0], kPi / 2, 1e-12);  // looks along +z: North
    EXPECT_NEAR(p.yaw_rad[1], 0.0, 1e-12);      // forward +x: East
    // Moving along +z while facing +z: the step direction relative to the heading is 0.
    const std::vector<StepObservation> obs = ComputeObservations(p);
    EXPECT_NEAR(obs[1].direction_rad, 0.0, 1e-12);
}

TEST(Frames, EnuForwardXIsEastAndAnchorYawRotatesCounterClockwise) {
    PlanarAnchor anchor;
    anchor.yaw_rad = kPi / 2;
    anchor.origin_en = Eigen::Vector2d(100.0, 200.0);
    Trajectory t;
    t.t_s = {0.0};
    t.p_frame = {{1.0, 0.0, 2.0}};
    t.q_frame_body = {Eigen::Quaterniond::Identity()};
    const PlanarTrajectory p = ToPlanar(t, FrameAxes::kEnu, anchor);
    EXPECT_LT((p.p_en[0] - Eigen::Vector2d(100.0, 201.0)).norm(), 1e-12);  // +x turned to North
    EXPECT_NEAR(p.up_m[0], 2.0, 1e-12);
    EXPECT_NEAR(p.yaw_rad[0], kPi / 2, 1e-12);
}

TEST(Frames, ParseAndPrintAxes) {
    EXPECT_EQ(ParseFrameAxes("kitti_camera"), FrameAxes::kKittiCamera);
    EXPECT_EQ(ParseFrameAxes("enu"), FrameAxes::kEnu);
    EXPECT_FALSE(ParseFrameAxes("ned").has_value());
    EXPECT_EQ(ToString(FrameAxes::kKittiCamera), "kitti_camera");
    EXPECT_EQ(ToString(FrameAxes::kEnu), "enu");
    // The (u, v, h) split is right-handed for both: u x v = h.
    for (FrameAxes a : {FrameAxes::kKittiCamera, FrameAxes::kEnu}) {
        const Eigen::Matrix3d m = [&] {
            Eigen::Matrix3d r;
            for (int k = 0; k < 3; ++k) r.col(k) = FrameToUvh(a, Eigen::Vector3d::Unit(k));
            return r;
        }();
        EXPECT_NEAR(m.determinant(), 1.0, 1e-12) << ToString(a);
        EXPECT_LT(
            (UvhToFrame(a, FrameToUvh(a, Eigen::Vector3d(1, 2, 3))) - Eigen::Vector3d(1, 2, 3))
                .norm(),
            1e-15);
        EXPECT_LT((FrameToUvh(a, FrameUpAxis(a)) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
    }
}

}  // namespace
}  // namespace driftcorr
