// The online corrector: causal and smoothed quality against the batch corrector on a synthetic
// scenario, every kind of bad input, and `driftcorr stream` through a real pipe.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/io/tum_line.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/pipeline/online.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace driftcorr;

namespace {

std::string TmpDir(const std::string& name) {
    static const fs::path root = test::FreshProcessDir("online");
    return test::EmptySubdir(root, name);
}

// Runs the committed generator into a fresh folder; returns the folder.
std::string Generate(const std::string& name, const std::string& args) {
    const std::string dir = TmpDir(name);
    EXPECT_EQ(test::GenerateRoadScenario(dir, args), 0) << args;
    return dir;
}

PlanarPose At(const PlanarTrajectory& t, std::size_t i) {
    return PlanarPose{t.t_s[i], t.p_en[i], t.up_m[i], t.yaw_rad[i]};
}

// `t` turned about its first pose by `angle_rad` (positions and headings).
PlanarTrajectory TurnedAboutStart(PlanarTrajectory t, double angle_rad) {
    const Eigen::Rotation2Dd r(angle_rad);
    for (std::size_t i = 0; i < t.size(); ++i) {
        t.p_en[i] = t.p_en[0] + r * (t.p_en[i] - t.p_en[0]);
        t.yaw_rad[i] += angle_rad;
    }
    return t;
}

// The estimate re-integrated with step i's translation times keep(i).
template <typename Keep>
PlanarTrajectory WithStepsKept(const PlanarTrajectory& estimate, Keep keep) {
    PlanarTrajectory t = estimate;
    for (std::size_t i = 1; i < t.size(); ++i) {
        t.p_en[i] = t.p_en[i - 1] + keep(i) * (estimate.p_en[i] - estimate.p_en[i - 1]);
    }
    return t;
}

// The first n poses of `t` through a synchronous stream, with or without the covariance's
// calibration (OnlineConfig::calibrate_covariance); every push is accepted.
std::vector<PushResult> StreamCalibrated(const PlanarTrajectory& t, std::size_t n,
                                         const TraversableField& field, bool calibrate) {
    OnlineConfig cfg;
    cfg.synchronous = true;
    cfg.calibrate_covariance = calibrate;
    OnlineCorrector online(&field, cfg);
    std::vector<PushResult> out;
    for (std::size_t i = 0; i < n; ++i) {
        out.push_back(online.Push(At(t, i)));
        EXPECT_TRUE(out.back().Accepted()) << out.back().message;
    }
    return out;
}

struct OnlineOutcome {
    PlanarTrajectory causal;
    CorrectionResult smoothed;
};

OnlineOutcome RunOnline(const PlanarTrajectory& est, const TraversableField& field, bool sync,
                        double update_fraction = OnlineConfig{}.update_fraction) {
    OnlineConfig cfg;
    cfg.synchronous = sync;
    cfg.update_fraction = update_fraction;
    OnlineCorrector online(&field, cfg);
    OnlineOutcome out;
    for (std::size_t i = 0; i < est.size(); ++i) {
        const PushResult r = online.Push(At(est, i));
        EXPECT_TRUE(r.Accepted()) << r.message;
        out.causal.t_s.push_back(r.corrected.t_s);
        out.causal.p_en.push_back(r.corrected.p_en);
        out.causal.up_m.push_back(r.corrected.up_m);
    }
    out.smoothed = online.Finish();
    return out;
}

// One synthetic scenario shared by the tests below (generated once).
class OnlineSynthetic : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = new std::string(Generate("synthetic", "--seed 42"));
        run_ = new pipeline::CorrectionRun(pipeline::RunCorrection(*dir_, {}));
        setup_ = new pipeline::StreamSetup(pipeline::LoadStreamSetup(*dir_, {}));
    }
    static void TearDownTestSuite() {
        delete setup_;
        delete run_;
        delete dir_;
    }
    static std::string* dir_;
    static pipeline::CorrectionRun* run_;
    static pipeline::StreamSetup* setup_;
};
std::string* OnlineSynthetic::dir_ = nullptr;
pipeline::CorrectionRun* OnlineSynthetic::run_ = nullptr;
pipeline::StreamSetup* OnlineSynthetic::setup_ = nullptr;

// Tolerances: causal ATE <= 1.5 x batch ATE + 0.5 m (the filter estimate at the head of the
// window has no future information); smoothed ATE <= batch ATE x 1.05 + 0.05 m (same chunks,
// same refinement: measured equal to the batch ATE to the printed precision).
TEST_F(OnlineSynthetic, SynchronousMatchesBatch) {
    ASSERT_TRUE(Usable(run_->result.status) && run_->after && run_->ground_truth);
    const double batch = run_->after->ate_m;
    const OnlineOutcome o = RunOnline(run_->estimate, setup_->field, true);
    ASSERT_TRUE(Usable(o.smoothed.status)) << o.smoothed.message;
    const double causal = ComputeMetrics(o.causal, *run_->ground_truth).ate_m;
    const double smoothed = ComputeMetrics(o.smoothed.corrected, *run_->ground_truth).ate_m;
    std::printf("synthetic: batch ATE %.3f m, causal %.3f m, smoothed %.3f m\n", batch, causal,
                smoothed);
    EXPECT_LE(causal, 1.5 * batch + 0.5);
    EXPECT_LE(smoothed, 1.05 * batch + 0.05);
    EXPECT_EQ(o.smoothed.windows, run_->result.windows);
}

// Finish() judges the input against its correction as the batch does: the true trajectory given
// as the estimate lies inside the correction's 95 % region, and the smoothed result is the input,
// as the batch's is (the generator's truth drives 1.5 m off the centre line, so the correction
// itself is not the input).
TEST(Online, TheSmoothedResultKeepsAnInputTheMapCannotTellWrong) {
    const std::string dir = Generate("do_no_harm", "--seed 1 --duration-s 120");
    fs::copy_file(dir + "/ground_truth.tum", dir + "/estimate.tum",
                  fs::copy_options::overwrite_existing);
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, {});
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    ASSERT_TRUE(run.result.input_kept);
    const pipeline::StreamSetup setup = pipeline::LoadStreamSetup(dir, {});
    const OnlineOutcome o = RunOnline(run.estimate, setup.field, true);
    ASSERT_TRUE(Usable(o.smoothed.status)) << o.smoothed.message;
    EXPECT_TRUE(o.smoothed.input_kept);
    ASSERT_EQ(o.smoothed.corrected.size(), run.estimate.size());
    for (std::size_t i = 0; i < run.estimate.size(); ++i) {
        ASSERT_LT((o.smoothed.corrected.p_en[i] - run.estimate.p_en[i]).norm(), 1e-9) << i;
    }
}

// A drive whose odometry reads its steps 0.9 of the true ones turns about 10 m before its first
// junction. A window solved there leaves the turned poses off the road, and is restarted from
// the other scale hypotheses as a batch window is; without that, the chain's scale collapsed to
// hold them on the road they had left and never came back (716 m against 1.88 m for the batch).
// The bound: the causal output within max(2x, + 2 m) of the batch's ATE.
TEST(Online, AWindowInAWrongBasinIsRestartedAndTheChainKeepsTheRoad) {
    const std::string dir =
        Generate("wrong_basin", "--seed 1 --scale-error 0.9 --heading-bias-deg-per-sqrt-s 0.003");
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, {});
    ASSERT_TRUE(Usable(run.result.status) && run.after && run.ground_truth);
    const pipeline::StreamSetup setup = pipeline::LoadStreamSetup(dir, {});
    const OnlineOutcome o = RunOnline(run.estimate, setup.field, true);
    const double batch = run.after->ate_m;
    const double causal = ComputeMetrics(o.causal, *run.ground_truth).ate_m;
    std::printf("batch ATE %.2f m, causal %.2f m\n", batch, causal);
    EXPECT_LE(causal, std::max(2.0 * batch, batch + 2.0));
}

// The solves between chunk ends (update_fraction) only move the causal output: the smoothed
// result is the batch solve, the same with them and without them (same process, same solves:
// equal to rounding). They do move it (on this synthetic drive both are within the same bound of
// the batch result).
TEST_F(OnlineSynthetic, IntermediateSolvesMoveOnlyTheCausalOutput) {
    const OnlineOutcome with = RunOnline(run_->estimate, setup_->field, true, 0.125);
    const OnlineOutcome without = RunOnline(run_->estimate, setup_->field, true, 0.0);
    ASSERT_TRUE(Usable(with.smoothed.status) && Usable(without.smoothed.status));
    ASSERT_EQ(with.smoothed.corrected.size(), without.smoothed.corrected.size());
    for (std::size_t i = 0; i < with.smoothed.corrected.size(); ++i) {
        ASSERT_NEAR((with.smoothed.corrected.p_en[i] - without.smoothed.corrected.p_en[i]).norm(),
                    0.0, 1e-9)
            << i;
    }
    const double causal_with = ComputeMetrics(with.causal, *run_->ground_truth).ate_m;
    const double causal_without = ComputeMetrics(without.causal, *run_->ground_truth).ate_m;
    std::printf("synthetic causal ATE: %.3f m with intermediate solves, %.3f m without\n",
                causal_with, causal_without);
    double moved = 0.0;
    for (std::size_t i = 0; i < with.causal.size(); ++i) {
        moved = std::max(moved, (with.causal.p_en[i] - without.causal.p_en[i]).norm());
    }
    EXPECT_GT(moved, 0.05);
    EXPECT_LE(causal_with, 1.5 * run_->after->ate_m + 0.5);
}

// Finish() is the batch solve, whatever the worker did.
TEST_F(OnlineSynthetic, ThreadedSmoothedMatchesBatch) {
    const OnlineOutcome o = RunOnline(run_->estimate, setup_->field, false);
    ASSERT_TRUE(Usable(o.smoothed.status)) << o.smoothed.message;
    const double smoothed = ComputeMetrics(o.smoothed.corrected, *run_->ground_truth).ate_m;
    EXPECT_LE(smoothed, 1.05 * run_->after->ate_m + 0.05);
    EXPECT_EQ(o.smoothed.windows, run_->result.windows);
}

// A replay pushed as fast as possible, with back-pressure (max_lag_epochs 1): every output chains
// from the solve its schedule asked for (fresh), so the causal output is as good as the
// synchronous one (same bound), and ages stay within one request interval.
TEST_F(OnlineSynthetic, BackPressureKeepsEveryOutputFresh) {
    const PlanarTrajectory& est = run_->estimate;
    OnlineConfig cfg;
    cfg.max_lag_epochs = 1;
    OnlineCorrector online(&setup_->field, cfg);
    PlanarTrajectory causal;
    std::size_t max_age = 0;
    for (std::size_t i = 0; i < est.size(); ++i) {
        const PushResult r = online.Push(At(est, i));
        ASSERT_TRUE(r.Accepted()) << r.message;
        EXPECT_TRUE(r.fresh) << "pose " << i;
        EXPECT_LE(r.correction_age_epochs, i);
        max_age = std::max(max_age, r.correction_age_epochs);
        causal.t_s.push_back(r.corrected.t_s);
        causal.p_en.push_back(r.corrected.p_en);
        causal.up_m.push_back(r.corrected.up_m);
    }
    const OnlineStatistics st = online.Statistics();
    EXPECT_EQ(st.poses, est.size());
    EXPECT_EQ(st.stale_poses, 0u);
    EXPECT_GE(st.ahead_poses, est.size() - 2) << "a replay runs faster than real time";
    EXPECT_EQ(st.max_age_epochs, max_age);
    EXPECT_GT(st.solves, 10u);
    EXPECT_EQ(st.solve_s.size(), st.solves);
    EXPECT_GT(st.prior_solves, 0u) << "windows after the first carry a marginalised prior";
    const double ate = ComputeMetrics(causal, *run_->ground_truth).ate_m;
    std::printf(
        "synthetic, as fast as possible with max_lag_epochs 1: causal ATE %.3f m, "
        "%zu solves for %zu requests, %zu waits\n",
        ate, st.solves, st.requests, st.waits);
    EXPECT_LE(ate, 1.5 * run_->after->ate_m + 0.5);
    EXPECT_TRUE(Usable(online.Finish().status));
}

// A producer at its own real-time pace (stream time advancing as fast as the wall clock) is never
// held back, whatever the lag; the same poses pushed as fast as possible are (BackPressure...).
TEST_F(OnlineSynthetic, InputAtRealTimePaceIsNeverHeldBack) {
    const PlanarTrajectory& est = run_->estimate;
    OnlineConfig cfg;
    cfg.max_lag_epochs = 1;
    OnlineCorrector online(&setup_->field, cfg);
    constexpr double kStepS = 0.003;
    for (std::size_t i = 0; i < 400; ++i) {
        PlanarPose pose = At(est, i);
        pose.t_s = kStepS * double(i);  // the wall time between Pushes is at least kStepS
        std::this_thread::sleep_for(std::chrono::duration<double>(kStepS));
        const PushResult r = online.Push(pose);
        ASSERT_TRUE(r.Accepted()) << r.message;
        EXPECT_FALSE(r.ahead_of_real_time) << "pose " << i;
        EXPECT_EQ(r.waited_s, 0.0) << "pose " << i;
    }
    const OnlineStatistics st = online.Statistics();
    EXPECT_EQ(st.waits, 0u);
    EXPECT_EQ(st.ahead_poses, 0u);
    EXPECT_GT(st.requests, 0u);
}

// Without back-pressure (max_lag_epochs 0) a burst outruns the solver: the worker skips to the
// newest pose instead of solving every request in turn, and the outputs say how old their
// correction is.
TEST_F(OnlineSynthetic, BurstSkipsAheadAndReportsTheAge) {
    const PlanarTrajectory& est = run_->estimate;
    OnlineConfig cfg;
    cfg.max_lag_epochs = 0;
    OnlineCorrector online(&setup_->field, cfg);
    std::size_t stale = 0;
    for (std::size_t i = 0; i < est.size(); ++i) {
        const PushResult r = online.Push(At(est, i));
        ASSERT_TRUE(r.Accepted());
        stale += !r.fresh;
        EXPECT_NEAR(r.correction_age_s, est.t_s[i] - est.t_s[i - r.correction_age_epochs], 1e-9);
    }
    const OnlineStatistics st = online.Statistics();
    EXPECT_EQ(st.stale_poses, stale);
    std::printf(
        "synthetic burst: %zu solves for %zu requests, %zu of %zu poses stale, worst age "
        "%zu epochs\n",
        st.solves, st.requests, stale, est.size(), st.max_age_epochs);
    EXPECT_LT(st.solves, st.requests) << "a burst of " << est.size() << " poses queued no solves";
    EXPECT_GT(stale, 0u);
    const CorrectionResult smoothed = online.Finish();
    ASSERT_TRUE(Usable(smoothed.status));
    EXPECT_LE(ComputeMetrics(smoothed.corrected, *run_->ground_truth).ate_m,
              1.05 * run_->after->ate_m + 0.05);
}

// Synchronous: the pose that asks for a solve is composed onto it (age 0).
TEST_F(OnlineSynthetic, SynchronousRequestPosesHaveAgeZero) {
    const PlanarTrajectory& est = run_->estimate;
    OnlineConfig cfg;
    cfg.synchronous = true;
    OnlineCorrector online(&setup_->field, cfg);
    std::size_t zero_age = 0;
    for (std::size_t i = 0; i < 600; ++i) {
        const PushResult r = online.Push(At(est, i));
        ASSERT_TRUE(r.Accepted() && r.fresh);
        zero_age += i > 0 && r.correction_age_epochs == 0;
    }
    const OnlineStatistics st = online.Statistics();
    EXPECT_EQ(zero_age, st.requests);
    EXPECT_EQ(st.solves, st.requests);
    EXPECT_EQ(st.stale_poses, 0u);
}

// Without boundary_prior the online windows hold their boundary pose fixed (as the batch windows
// do); with it (the default) the boundary carries the marginalised past. Both follow the map: the
// causal ATE stays within the synchronous bound of the batch result.
TEST_F(OnlineSynthetic, FixedAndMarginalisedBoundariesBothCorrectTheOutput) {
    for (bool boundary_prior : {true, false}) {
        const PlanarTrajectory& est = run_->estimate;
        OnlineConfig cfg;
        cfg.synchronous = true;
        cfg.boundary_prior = boundary_prior;
        OnlineCorrector online(&setup_->field, cfg);
        PlanarTrajectory causal;
        for (std::size_t i = 0; i < est.size(); ++i) {
            const PushResult r = online.Push(At(est, i));
            ASSERT_TRUE(r.Accepted());
            causal.t_s.push_back(r.corrected.t_s);
            causal.p_en.push_back(r.corrected.p_en);
            causal.up_m.push_back(r.corrected.up_m);
        }
        const OnlineStatistics st = online.Statistics();
        if (boundary_prior) {
            EXPECT_GT(st.prior_solves, st.solves / 2);
        } else {
            EXPECT_EQ(st.prior_solves, 0u);
        }
        const double ate = ComputeMetrics(causal, *run_->ground_truth).ate_m;
        std::printf("synthetic, boundary prior %d: causal ATE %.3f m\n", int(boundary_prior), ate);
        EXPECT_LE(ate, 1.5 * run_->after->ate_m + 0.5);
    }
}

TEST_F(OnlineSynthetic, BadPosesAreSkippedAndTheStreamGoesOn) {
    const PlanarTrajectory& est = run_->estimate;
    OnlineConfig cfg;
    cfg.synchronous = true;
    OnlineCorrector online(&setup_->field, cfg);
    std::size_t accepted = 0;
    for (std::size_t i = 0; i < 200; ++i) {
        accepted += online.Push(At(est, i)).Accepted();
        if (i == 50) {  // repeated timestamp
            EXPECT_EQ(online.Push(At(est, i)).status, PushStatus::kRejectedTime);
        }
        if (i == 60) {  // out of order
            EXPECT_EQ(online.Push(At(est, i - 5)).status, PushStatus::kRejectedTime);
        }
        if (i == 70) {  // NaN position
            PlanarPose bad = At(est, i + 1);
            bad.p_en.x() = std::numeric_limits<double>::quiet_NaN();
            const PushResult r = online.Push(bad);
            EXPECT_EQ(r.status, PushStatus::kRejectedNonFinite);
            EXPECT_FALSE(r.message.empty());
        }
        if (i == 80) {  // no heading in a stream with headings
            PlanarPose bad = At(est, i + 1);
            bad.yaw_rad.reset();
            EXPECT_EQ(online.Push(bad).status, PushStatus::kRejectedHeading);
        }
    }
    EXPECT_EQ(accepted, 200u);
    EXPECT_EQ(online.size(), 200u);
    EXPECT_TRUE(Usable(online.Finish().status));
    EXPECT_EQ(online.Push(At(est, 200)).status, PushStatus::kRejectedFinished);
}

TEST_F(OnlineSynthetic, GapAndOutsideMapAreFlagged) {
    const PlanarTrajectory& est = run_->estimate;
    OnlineCorrector online(&setup_->field, OnlineConfig{});
    for (std::size_t i = 0; i < 10; ++i) EXPECT_FALSE(online.Push(At(est, i)).gap);
    PlanarPose late = At(est, 10);
    late.t_s += 30.0;
    const PushResult gap = online.Push(late);
    EXPECT_TRUE(gap.Accepted() && gap.gap);
    EXPECT_NE(gap.message.find("gap"), std::string::npos);
    PlanarPose far = At(est, 11);
    far.t_s = late.t_s + 0.1;
    far.p_en += Eigen::Vector2d(1e6, 0.0);  // a jump far off the map
    const PushResult off = online.Push(far);
    EXPECT_TRUE(off.Accepted() && off.outside_map);
    EXPECT_TRUE(off.corrected.p_en.allFinite());
    EXPECT_TRUE(off.doubt & kDoubtOffMap);
    EXPECT_FALSE(gap.doubt & kDoubtOffMap);
}

// A window that stays in a wrong basin after its restarts flags the outputs chained from it: the
// estimate turned by 90 degrees about the start leaves the map within metres, no scale hypothesis
// brings it back, and the lines say so as it happens (the batch verdict only at the end).
TEST_F(OnlineSynthetic, AChainInAWrongBasinFlagsItsOutputs) {
    const PlanarTrajectory turned = TurnedAboutStart(run_->estimate, M_PI / 2.0);
    OnlineConfig cfg;
    cfg.synchronous = true;
    OnlineCorrector online(&setup_->field, cfg);
    std::size_t poor = 0, solved = 0;
    for (std::size_t i = 0; i < 600; ++i) {
        const PushResult p = online.Push(At(turned, i));
        ASSERT_TRUE(p.Accepted()) << p.message;
        if (p.correction_age_epochs < i) ++solved;
        poor += (p.doubt & kDoubtPoorWindow) != 0;
    }
    EXPECT_GT(solved, 300u);
    EXPECT_GT(poor, solved / 2) << "of " << solved << " outputs after a solve";
    // The untouched drive: no output chains from a window in a wrong basin.
    OnlineCorrector clean(&setup_->field, cfg);
    for (std::size_t i = 0; i < 600; ++i) {
        EXPECT_FALSE(clean.Push(At(run_->estimate, i)).doubt & kDoubtPoorWindow) << i;
    }
}

// A chain in doubt has its prefix solved as a whole (OnlineConfig::relocalise_min_m) and
// continues from it when its own NLL is relocalise_nll_ratio times the prefix's: on the drive
// turned by 90 degrees every window is poor; a ratio near 0 takes every usable such correction (the
// first output after each flagged kDoubtRelocalised), a ratio no NLL reaches none, and
// relocalise_min_m 0 runs none.
TEST_F(OnlineSynthetic, AChainInDoubtIsRelocalisedFromItsPrefix) {
    const PlanarTrajectory turned = TurnedAboutStart(run_->estimate, M_PI / 2.0);
    auto run = [&](double min_m, double ratio) {
        OnlineConfig cfg;
        cfg.synchronous = true;
        cfg.relocalise_min_m = min_m;
        cfg.relocalise_nll_ratio = ratio;
        OnlineCorrector online(&setup_->field, cfg);
        std::size_t flagged = 0;
        for (std::size_t i = 0; i < 1000; ++i) {
            const PushResult p = online.Push(At(turned, i));
            EXPECT_TRUE(p.Accepted()) << p.message;
            flagged += (p.doubt & kDoubtRelocalised) != 0;
        }
        const OnlineStatistics st = online.Statistics();
        EXPECT_EQ(flagged, st.relocalised);
        return st;
    };
    // (A prefix whose correction is not usable is not taken.)
    const OnlineStatistics every = run(200.0, 1e-12);
    EXPECT_GE(every.relocalised, 2u);
    EXPECT_LE(every.relocalised, every.relocalisations);
    const OnlineStatistics none = run(200.0, 1e12);
    EXPECT_GE(none.relocalisations, 2u);
    EXPECT_EQ(none.relocalised, 0u);
    EXPECT_EQ(run(0.0, 1e-12).relocalisations, 0u);
}

// A solve that moves the chain's previous output outside the 95 % region that output claimed
// flags the outputs chained from it (kDoubtMoved) until a solve agrees again: the taken
// re-localisations of the drive turned by 90 degrees move the chain by tens of metres (not
// every one: one may land inside the region), and are flagged so; on the untouched drive
// successive solves agree on nearly every output.
TEST_F(OnlineSynthetic, ASolveThatMovesTheChainOutsideItsRegionIsFlagged) {
    const PlanarTrajectory turned = TurnedAboutStart(run_->estimate, M_PI / 2.0);
    OnlineConfig cfg;
    cfg.synchronous = true;
    cfg.relocalise_nll_ratio = 1e-12;  // every usable re-localisation taken
    OnlineCorrector online(&setup_->field, cfg);
    std::size_t relocalised = 0, moved_there = 0;
    for (std::size_t i = 0; i < 1000; ++i) {
        const PushResult p = online.Push(At(turned, i));
        ASSERT_TRUE(p.Accepted()) << p.message;
        if (p.doubt & kDoubtRelocalised) {
            ++relocalised;
            moved_there += (p.doubt & kDoubtMoved) != 0;
        }
    }
    EXPECT_GE(relocalised, 2u);
    EXPECT_GE(moved_there, 1u) << "of " << relocalised;
    OnlineCorrector clean(&setup_->field, cfg);
    std::size_t moved = 0, n = 0;
    for (std::size_t i = 0; i < 1000 && i < run_->estimate.size(); ++i, ++n) {
        moved += (clean.Push(At(run_->estimate, i)).doubt & kDoubtMoved) != 0;
    }
    EXPECT_LT(moved, n / 20) << "of " << n;
}

// A solve that moves the chain outside its region puts the chain in doubt for the
// re-localisation too (OnlineConfig::relocalise_when_moved): on the drive with its steps shortened
// to a third for 300 poses (odometry that drops motion), re-localised at every solve in doubt (no
// spacing), the moves add re-localisations to those of the windows in doubt.
TEST_F(OnlineSynthetic, ASolveThatMovesTheChainRunsARelocalisation) {
    PlanarTrajectory shortened = run_->estimate;
    for (std::size_t i = 301; i < shortened.size(); ++i) {
        const double keep = i <= 600 ? 1.0 / 3.0 : 1.0;
        shortened.p_en[i] =
            shortened.p_en[i - 1] + keep * (run_->estimate.p_en[i] - run_->estimate.p_en[i - 1]);
    }
    auto run = [&](bool when_moved) {
        OnlineConfig cfg;
        cfg.synchronous = true;
        cfg.relocalise_nll_ratio = 1e-12;
        cfg.relocalise_min_m = 1.0;  // at every solve in doubt
        cfg.relocalise_share = 0.0;
        cfg.relocalise_when_moved = when_moved;
        OnlineCorrector online(&setup_->field, cfg);
        std::size_t moved = 0;
        for (std::size_t i = 0; i < shortened.size() && i < 1500; ++i) {
            const PushResult p = online.Push(At(shortened, i));
            EXPECT_TRUE(p.Accepted()) << p.message;
            moved += (p.doubt & kDoubtMoved) != 0;
        }
        return std::make_pair(online.Statistics().relocalisations, moved);
    };
    const auto [off, moved_off] = run(false);
    const auto [on, moved_on] = run(true);
    EXPECT_GT(moved_off, 0u);
    EXPECT_GT(on, off) << "moved lines " << moved_on << " and " << moved_off;
}

// The outputs' covariance scaled by how well it held the chain's own final estimates
// (OnlineConfig::calibrate_covariance): on the drive whose steps are shortened to 0.7 for 150
// poses (odometry that loses motion), the model's covariance misses the true error on a third of
// the lines; scaled, it holds more of them (measured: 966 and 1077 of 1499). Positions and doubt
// bits are the same either way, and no output's covariance shrinks.
TEST_F(OnlineSynthetic, TheCovarianceIsScaledByHowItHeldTheFinalEstimates) {
    ASSERT_TRUE(run_->ground_truth);
    const PlanarTrajectory shortened = WithStepsKept(
        run_->estimate, [](std::size_t i) { return i >= 301 && i <= 450 ? 0.7 : 1.0; });
    const std::size_t n = std::min<std::size_t>(shortened.size(), 1500);
    const std::vector<PushResult> model = StreamCalibrated(shortened, n, setup_->field, false);
    const std::vector<PushResult> scaled = StreamCalibrated(shortened, n, setup_->field, true);
    const PlanarTrajectory& truth = *run_->ground_truth;
    std::size_t inside_model = 0, inside_scaled = 0, larger = 0, with = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const PushResult& a = model[i];
        const PushResult& b = scaled[i];
        EXPECT_EQ(a.corrected.p_en, b.corrected.p_en) << "pose " << i;
        EXPECT_EQ(a.doubt, b.doubt) << "pose " << i;
        ASSERT_EQ(a.covariance_ok, b.covariance_ok) << "pose " << i;
        if (!a.covariance_ok || !(a.covariance.xy_m2.determinant() > 0.0)) continue;
        ++with;
        EXPECT_GE(b.covariance.xy_m2.trace(), a.covariance.xy_m2.trace() * (1.0 - 1e-12));
        larger += b.covariance.xy_m2.trace() > 1.01 * a.covariance.xy_m2.trace();
        const Eigen::Vector2d e = a.corrected.p_en - truth.p_en[i];
        inside_model += InsideRegion95(e, a.covariance.xy_m2);
        inside_scaled += InsideRegion95(e, b.covariance.xy_m2);
    }
    std::printf(
        "shortened steps: %zu of %zu outputs inside the model's 95 %% region, %zu scaled; "
        "%zu scaled up\n",
        inside_model, with, inside_scaled, larger);
    EXPECT_GT(larger, 0u);
    EXPECT_GT(inside_scaled, inside_model);
}

// The outputs in doubt for the odometry (kDoubtOdometry) are scaled by how those outputs held
// their final estimates, where that is worse than all outputs did: on the synthetic drive with
// steps dropped to 0.3 of their length in 2 s episodes every 30 s, where the doubt ends, the last
// output in doubt is scaled by more than the next, which is not in doubt (one scale for every
// output would change by at most one bin of its quantile, 12 %, from one output to the next);
// the outputs' positions and flags are those of the uncalibrated stream.
TEST_F(OnlineSynthetic, OutputsInDoubtForTheOdometryAreCalibratedApart) {
    const PlanarTrajectory dropped = WithStepsKept(
        run_->estimate, [](std::size_t i) { return i >= 200 && i % 300 < 20 ? 0.3 : 1.0; });
    const std::size_t n = std::min<std::size_t>(dropped.size(), 2000);
    const std::vector<PushResult> model = StreamCalibrated(dropped, n, setup_->field, false);
    const std::vector<PushResult> scaled = StreamCalibrated(dropped, n, setup_->field, true);
    double largest_step = 0.0;  // factor of the last output in doubt over the next one's
    std::size_t ends = 0;
    double previous = 0.0;  // the previous output's factor, 0 when not in doubt or none
    for (std::size_t i = 0; i < n; ++i) {
        const PushResult& a = model[i];
        const PushResult& b = scaled[i];
        ASSERT_TRUE(a.Accepted() && b.Accepted()) << i;
        EXPECT_EQ(a.corrected.p_en, b.corrected.p_en) << "pose " << i;
        EXPECT_EQ(a.doubt, b.doubt) << "pose " << i;
        if (!a.covariance_ok || !(a.covariance.xy_m2.trace() > 0.0)) {
            previous = 0.0;
            continue;
        }
        const double factor = b.covariance.xy_m2.trace() / a.covariance.xy_m2.trace();
        const bool doubt = (a.doubt & kDoubtOdometry) != 0;
        if (!doubt && previous > 0.0) {
            largest_step = std::max(largest_step, previous / factor), ++ends;
        }
        previous = doubt ? factor : 0.0;
    }
    std::printf("dropped steps: %zu ends of the doubt, the largest factor's fall at one %.2f\n",
                ends, largest_step);
    EXPECT_GT(ends, 0u);
    EXPECT_GT(largest_step, 1.5);
}

// Before the first solve an output is the odometry from the start at the prior's step-length
// scale: its covariance holds that scale's uncertainty along the displacement so far (at least
// scale_prior_sigma of it, one sigma).
TEST_F(OnlineSynthetic, OutputsBeforeTheFirstSolveCarryThePriorScale) {
    OnlineConfig cfg;
    cfg.synchronous = true;
    OnlineCorrector online(&setup_->field, cfg);
    const double sd = cfg.corrector.model.scale_prior_sigma;
    std::size_t checked = 0;
    for (std::size_t i = 0; i < run_->estimate.size() && online.Statistics().solves == 0; ++i) {
        const PushResult p = online.Push(At(run_->estimate, i));
        ASSERT_TRUE(p.Accepted()) << p.message;
        if (online.Statistics().solves > 0 || !p.covariance_ok) break;
        const Eigen::Vector2d d = p.corrected.p_en - run_->estimate.p_en.front();
        if (d.norm() < 1.0) continue;
        const Eigen::Vector2d u = d.normalized();
        // (0.95: the output may have been moved into the corridor since.)
        EXPECT_GE(std::sqrt(u.dot(p.covariance.xy_m2 * u)), 0.95 * sd * d.norm()) << "pose " << i;
        ++checked;
    }
    EXPECT_GT(checked, 10u);
}

// With one start scale the first window is solved when the first chunk is complete: the outputs
// before it are the input itself (the odometry from the known start); with
// first_solve_at_chunk false, windows are solved within it and move them.
TEST_F(OnlineSynthetic, TheFirstWindowIsSolvedWithTheFirstChunk) {
    const PlanarTrajectory& est = run_->estimate;
    const double chunk_m = OnlineConfig{}.corrector.chunk_m;
    for (bool at_chunk : {true, false}) {
        SCOPED_TRACE(at_chunk ? "at the chunk" : "from the start");
        OnlineConfig cfg;
        cfg.synchronous = true;
        cfg.first_solve_at_chunk = at_chunk;
        OnlineCorrector online(&setup_->field, cfg);
        double path = 0.0, moved = 0.0;
        std::size_t solved = 0;
        for (std::size_t i = 0; path < chunk_m; ++i) {
            ASSERT_LT(i + 1, est.size());
            const PushResult p = online.Push(At(est, i));
            ASSERT_TRUE(p.Accepted()) << p.message;
            moved = std::max(moved, (p.corrected.p_en - est.p_en[i]).norm());
            solved += p.correction_age_epochs < i;
            path += (est.p_en[i + 1] - est.p_en[i]).norm();
        }
        if (at_chunk) {
            EXPECT_EQ(solved, 0u);
            EXPECT_LT(moved, 1e-9);
        } else {
            EXPECT_GT(solved, 0u);
            EXPECT_GT(moved, 0.01);
        }
    }
}

// A 3D field (20 m x 20 m x 4 m, 0.5 m cells) whose corridor distance is corridor(p) everywhere.
template <typename F>
TraversableField LinearCorridorField(F corridor) {
    GridSpec spec;
    spec.resolution_m = 0.5;
    spec.nx = spec.ny = 41;
    spec.nz = 9;
    std::vector<float> centre(spec.size(), 0.0f), values(spec.size());
    for (int k = 0; k < spec.nz; ++k) {
        for (int j = 0; j < spec.ny; ++j) {
            for (int i = 0; i < spec.nx; ++i) {
                values[spec.Index(i, j, k)] = static_cast<float>(corridor(spec.Position(i, j, k)));
            }
        }
    }
    return TraversableField(InterpolatedField(spec, centre), InterpolatedField(spec, values), 5.0);
}

// The causal output is moved into the corridor horizontally, but only where the corridor
// distance falls horizontally. Where it falls with height (between floors, on stairs) it is left
// where it is: a Newton step along a small horizontal slope took a pose on a real walk 165 m away.
TEST(Online, OutputIsProjectedOnlyAlongAHorizontalSlope) {
    const PlanarPose pose{0.0, {9.5, 10.0}, 1.0, 0.0};
    auto first_output = [&](const TraversableField& field) {
        OnlineConfig cfg;
        cfg.synchronous = true;
        OnlineCorrector online(&field, cfg);
        const PushResult r = online.Push(pose);
        EXPECT_TRUE(r.Accepted() && !r.outside_map) << r.message;
        return r.corrected;
    };
    // Outside by 1.5 m, slope 1 along x: moved onto the edge x = 8 (slack 0).
    const PlanarPose across =
        first_output(LinearCorridorField([](const Eigen::Vector3d& p) { return p.x() - 8.0; }));
    EXPECT_NEAR(across.p_en.x(), 8.0, 0.05);
    EXPECT_NEAR(across.p_en.y(), 10.0, 1e-6);
    // Outside by 0.89 m, falling with height (slope 1 in z, 0.02 along x): not moved.
    const PlanarPose below = first_output(LinearCorridorField(
        [](const Eigen::Vector3d& p) { return 2.0 - p.z() - 0.3 + 0.02 * p.x(); }));
    EXPECT_NEAR((below.p_en - pose.p_en).norm(), 0.0, 1e-9) << below.p_en.transpose();
    EXPECT_EQ(below.up_m, pose.up_m);
}

TEST(Online, TooFewPosesIsAStatusNotACrash) {
    OnlineCorrector online(nullptr, OnlineConfig{});
    online.Push(PlanarPose{0.0, {0.0, 0.0}, 0.0, 0.0});
    const CorrectionResult r = online.Finish();
    EXPECT_FALSE(Usable(r.status));
    EXPECT_NE(r.message.find("at least 3"), std::string::npos);
}

// Without headings the heading of a pose is the direction of the step into it (causal).
TEST(Online, WithoutHeadingsStraightLineIsKept) {
    OnlineConfig cfg;
    cfg.synchronous = true;
    OnlineCorrector online(nullptr, cfg);
    for (int i = 0; i < 300; ++i) {
        const PushResult r = online.Push(PlanarPose{0.1 * i, {1.0 * i, 2.0}, 0.0, std::nullopt});
        ASSERT_TRUE(r.Accepted());
        EXPECT_NEAR((r.corrected.p_en - Eigen::Vector2d(1.0 * i, 2.0)).norm(), 0.0, 0.5) << i;
    }
    EXPECT_TRUE(Usable(online.Finish().status));
}

// Dropped odometry steps put the outputs in doubt (kDoubtOdometry) from the speed jump until a
// solve has seen the estimate turn after the episode: on odometry alone, 10 m/s East with 2 s of
// steps shortened to 0.4 of their length at t = 20 s, straight on to t = 60 s, a left turn of
// 90 degrees over 3 s, then North. The lines of the straight after the episode are in doubt, 10 s
// after the jump as well; the lines well after the turn are not; the same drive without the
// episode has no line in doubt.
TEST(Online, DroppedStepsKeepTheOutputsInDoubtUntilATurnAfterThem) {
    auto drive = [](bool drop) {
        std::vector<PlanarPose> poses;
        Eigen::Vector2d p = Eigen::Vector2d::Zero();
        double yaw = 0.0;
        for (int i = 0; i <= 900; ++i) {
            const double t = 0.1 * i;
            if (i > 0) {
                if (t > 60.0 && t <= 63.0) yaw += (M_PI / 2.0) / 30.0;
                const double step = drop && t > 20.0 && t <= 22.0 ? 0.4 : 1.0;
                p += step * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
            }
            poses.push_back(PlanarPose{t, p, 0.0, yaw});
        }
        return poses;
    };
    OnlineConfig cfg;
    cfg.synchronous = true;
    for (const bool drop : {true, false}) {
        OnlineCorrector online(nullptr, cfg);
        std::size_t before = 0, straight = 0, late_straight = 0, late_lines = 0, after_turn = 0;
        for (const PlanarPose& pose : drive(drop)) {
            const PushResult r = online.Push(pose);
            ASSERT_TRUE(r.Accepted()) << r.message;
            const bool doubt = (r.doubt & kDoubtOdometry) != 0;
            if (pose.t_s < 19.0) before += doubt;
            if (pose.t_s > 22.0 && pose.t_s < 60.0) straight += !doubt;  // lines not in doubt
            if (pose.t_s > 35.0 && pose.t_s < 60.0) late_straight += doubt, ++late_lines;
            if (pose.t_s > 80.0) after_turn += doubt;
        }
        EXPECT_EQ(before, 0u) << drop;
        EXPECT_EQ(after_turn, 0u) << drop;
        if (drop) {
            EXPECT_EQ(straight, 0u);
            EXPECT_EQ(late_straight, late_lines);
            EXPECT_GT(late_lines, 200u);
        } else {
            EXPECT_EQ(late_straight, 0u);
        }
    }
}

// Two start scales on odometry alone (no map): each hypothesis keeps its scale, their NLLs differ
// only by the scale prior (0.5 (0.2 / 0.2)^2 = 0.5), so the output of the lower (scale 1) carries
// the other's offset, 0.2 of the path, with a weight of exp(-0.5) / (1 + exp(-0.5)) = 0.38 in its
// covariance.
TEST(Online, TheCovarianceHoldsTheHypothesesOfCloseNll) {
    auto last = [](const std::vector<double>& starts) {
        OnlineConfig cfg;
        cfg.synchronous = true;
        cfg.corrector.start_scales = starts;
        cfg.corrector.model.scale_prior_sigma = 0.2;
        cfg.corrector.model.scale_range_sigma = 0.0;
        OnlineCorrector online(nullptr, cfg);
        PushResult r;
        for (int i = 0; i < 200; ++i) {
            r = online.Push(PlanarPose{0.5 * i, {1.0 * i, 0.0}, 0.0, 0.0});
            EXPECT_TRUE(r.Accepted());
        }
        EXPECT_TRUE(r.covariance_ok);
        return r;
    };
    const PushResult two = last({1.0, 1.2});
    const PushResult one = last({1.0});
    // Along the track (East) each hypothesis's own variance is about the scale prior's (0.2 of
    // the path, as the offset); the mixture adds w offset^2. Across it nothing changes.
    const double offset_m = 0.2 * 199.0;
    const double along_two = two.covariance.xy_m2(0, 0), along_one = one.covariance.xy_m2(0, 0);
    std::printf("along-track sd from two starts %.2f m, from one %.2f m; offset %.1f m\n",
                std::sqrt(along_two), std::sqrt(along_one), offset_m);
    EXPECT_EQ(two.start_scale, 1.0);
    EXPECT_NEAR(two.corrected.p_en.x(), one.corrected.p_en.x(), 0.5);
    const double w = std::exp(-0.5) / (1.0 + std::exp(-0.5));
    EXPECT_NEAR(along_two - along_one, w * offset_m * offset_m, 0.15 * w * offset_m * offset_m);
    EXPECT_NEAR(two.covariance.xy_m2(1, 1), one.covariance.xy_m2(1, 1),
                0.5 * one.covariance.xy_m2(1, 1));
}

// Before every hypothesis has solved, the outputs come from the start nearest the scale prior's
// mean, and on odometry alone (NLLs apart only by the prior about that mean) they stay with it:
// each output lies at that start's scale times the odometry's path.
TEST(Online, TheOutputsStartFromTheStartNearestTheScalePriorMean) {
    for (const auto& [mean, nearest] : {std::pair{1.0, 1.0}, {1.2, 1.25}, {1.45, 1.5}}) {
        OnlineConfig cfg;
        cfg.synchronous = true;
        cfg.corrector.start_scales = {1.0, 1.25, 1.5};
        cfg.corrector.model.scale_prior_mean = mean;
        cfg.corrector.model.scale_range_sigma = 0.0;
        OnlineCorrector online(nullptr, cfg);
        for (int i = 0; i < 200; ++i) {
            const PushResult r = online.Push(PlanarPose{0.5 * i, {1.0 * i, 0.0}, 0.0, 0.0});
            ASSERT_TRUE(r.Accepted());
            ASSERT_EQ(r.start_scale, nearest) << "mean " << mean << ", pose " << i;
            EXPECT_NEAR(r.corrected.p_en.x(), nearest * i, 0.02 * i + 0.1) << mean << " " << i;
        }
    }
}

TEST(TumLine, ParsesAndRejects) {
    const io::TumLine ok = io::ParseTumLine(" 1.5 1 2 3 0 0 0 2\r");
    ASSERT_EQ(ok.kind, io::TumLine::Kind::kPose);
    EXPECT_DOUBLE_EQ(ok.t_s, 1.5);
    EXPECT_DOUBLE_EQ(ok.q_frame_body.w(), 1.0);
    EXPECT_EQ(io::ParseTumLine("# comment").kind, io::TumLine::Kind::kSkip);
    EXPECT_EQ(io::ParseTumLine("   ").kind, io::TumLine::Kind::kSkip);
    for (const char* bad : {"1 2 3", "1 2 3 4 5 6 7 8 9", "1 2 x 4 0 0 0 1", "1 nan 3 4 0 0 0 1",
                            "1 2 3 4 0 0 0 0", "garbage"}) {
        const io::TumLine r = io::ParseTumLine(bad);
        EXPECT_EQ(r.kind, io::TumLine::Kind::kError) << bad;
        EXPECT_FALSE(r.error.empty()) << bad;
    }
}

// The line is the one printf's "%.6f ... %.9f" gives, to the character: values of every
// magnitude a trajectory holds, halfway cases of both decimals, negative zero and tiny negatives
// (printed "-0.000000"); and a value too long for the buffer is refused, not cut.
TEST(TumLine, FormatsAsPrintfDoes) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-12, 9);
    std::vector<double> special = {
        0.0,    -0.0,   0.5e-6, 1.5e-6,    2.5e-6,    -0.5e-6,      0.5e-9,
        2.5e-9, -4e-10, -4e-7,  0.1234565, 1.0000005, 1e9 + 0.5e-6, 1700000000.123456789,
        4541.05};
    char printf_line[512], line[512];
    for (int trial = 0; trial < 20000; ++trial) {
        double v[8];
        for (int k = 0; k < 8; ++k) {
            v[k] = trial < int(special.size()) ? special[std::size_t(trial)]
                                               : mantissa(rng) * std::pow(10.0, exponent(rng));
        }
        const Eigen::Vector3d p(v[1], v[2], v[3]);
        const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // w, x, y, z: not normalised here
        const int expected = std::snprintf(printf_line, sizeof(printf_line),
                                           "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", v[0], v[1],
                                           v[2], v[3], v[4], v[5], v[6], v[7]);
        const std::size_t n = io::FormatTumLine(line, sizeof(line), v[0], p, q);
        ASSERT_EQ(std::string(line, n), std::string(printf_line, std::size_t(expected))) << trial;
        EXPECT_EQ(io::FormatTumLine(v[0], p, q), std::string(printf_line)) << trial;
    }
    const Eigen::Vector3d far(1e300, 0.0, 0.0);
    EXPECT_EQ(io::FormatTumLine(line, 256, 0.0, far, Eigen::Quaterniond::Identity()), 0u);
}

std::string Slurp(const std::string& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::size_t CountLines(const std::string& text) {
    return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

// Valid lines, a garbage line, a NaN line, a repeated timestamp, more valid lines and a truncated
// last line through `driftcorr stream`: one output line per valid input line, each bad line named
// on stderr, and the smoothed output written at the end.
TEST_F(OnlineSynthetic, PipeThroughTheBinary) {
    const Trajectory est = io::LoadTrajectory(run_->scenario.estimate);
    std::string input;
    auto line = [&](std::size_t i) {
        return io::FormatTumLine(est.t_s[i], est.p_frame[i], est.q_frame_body[i]);
    };
    for (std::size_t i = 0; i < 20; ++i) input += line(i);
    input += "this is not a pose\n";  // line 21
    input += "99 nan 0 0 0 0 0 1\n";  // line 22
    input += line(19);                // line 23: repeated timestamp
    for (std::size_t i = 20; i < 40; ++i) input += line(i);
    std::string last = line(40);
    input += last.substr(0, last.size() / 2);  // line 44: ends mid-line
    const std::string dir = TmpDir("pipe");
    fs::create_directories(dir);
    std::ofstream(dir + "/in.tum") << input;
    const std::string cmd = "cat " + dir + "/in.tum | " + std::string(DRIFTCORR_BINARY_DIR) +
                            "/examples/driftcorr stream " + *dir_ + " --smoothed-out " + dir +
                            "/smoothed.tum > " + dir + "/out.tum 2> " + dir + "/err.txt";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd << "\n" << Slurp(dir + "/err.txt");
    const std::string err = Slurp(dir + "/err.txt");
    EXPECT_EQ(CountLines(Slurp(dir + "/out.tum")), 40u) << err;
    EXPECT_NE(err.find("line 21"), std::string::npos) << err;
    EXPECT_NE(err.find("line 22"), std::string::npos) << err;
    EXPECT_NE(err.find("line 23"), std::string::npos) << err;
    EXPECT_NE(err.find("line 44"), std::string::npos) << err;
    EXPECT_EQ(io::ReadTum(dir + "/out.tum").size(), 40u);
    EXPECT_EQ(io::ReadTum(dir + "/smoothed.tum").size(), 40u);
}

// A producer that pauses longer than gap_warn_s and resumes: the stream goes on and says so once;
// --status-column adds the correction's age, the pose's covariance and why it may be wrong to
// every line; the summary says how fresh they were.
TEST_F(OnlineSynthetic, PauseIsReportedOnceAndStatusColumnsAreWritten) {
    const Trajectory est = io::LoadTrajectory(run_->scenario.estimate);
    const std::string dir = TmpDir("pause");
    fs::create_directories(dir);
    {
        std::ofstream a(dir + "/a.tum"), b(dir + "/b.tum");
        for (std::size_t i = 0; i < 300; ++i) {
            (i < 150 ? a : b) << io::FormatTumLine(est.t_s[i], est.p_frame[i], est.q_frame_body[i]);
        }
        std::ofstream(dir + "/params.yaml") << "online: {gap_warn_s: 0.3}\n";
    }
    // The pause starts once the first 150 lines have come out (the map is loaded by then).
    const std::string out_path = dir + "/out.txt";
    std::ofstream(out_path).flush();
    const std::string cmd =
        "(cat " + dir + "/a.tum; while [ $(wc -l < " + out_path +
        ") -lt 150 ]; do sleep 0.05; done; sleep 0.8; cat " + dir + "/b.tum) | " +
        std::string(DRIFTCORR_BINARY_DIR) + "/examples/driftcorr stream " + *dir_ + " --config " +
        dir + "/params.yaml --status-column > " + out_path + " 2> " + dir + "/err.txt";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd << "\n" << Slurp(dir + "/err.txt");
    const std::string err = Slurp(dir + "/err.txt");
    std::size_t pauses = 0;
    for (std::size_t at = err.find("pause"); at != std::string::npos;
         at = err.find("pause", at + 1)) {
        ++pauses;
    }
    EXPECT_EQ(pauses, 1u) << err;
    EXPECT_NE(err.find("line 151"), std::string::npos) << err;
    EXPECT_NE(err.find("freshness"), std::string::npos) << err;
    EXPECT_NE(err.find("solve time per window"), std::string::npos) << err;
    EXPECT_NE(err.find("verdict"), std::string::npos) << err;
    std::ifstream out(dir + "/out.txt");
    std::string line;
    std::size_t lines = 0;
    while (std::getline(out, line)) {
        std::istringstream ss(line);
        std::vector<double> v;
        for (std::string field; ss >> field;) v.push_back(std::strtod(field.c_str(), nullptr));
        ASSERT_EQ(v.size(), 15u) << "line " << lines + 1 << ": " << line;
        // The pose's horizontal covariance: from the known start (0) growing along the odometry,
        // a solved window's marginal after each solve.
        const double var_e = v[11], cov_en = v[12], var_n = v[13];
        EXPECT_TRUE(var_e >= 0.0 && var_n >= 0.0 && cov_en * cov_en <= var_e * var_n + 1e-12)
            << "line " << lines + 1 << ": " << line;
        if (lines > 0) {
            EXPECT_GT(var_e + var_n, 0.0) << "line " << lines + 1;
        }
        // Why the pose may be wrong (OnlineDoubt bits).
        EXPECT_TRUE(v[14] >= 0.0 && v[14] <= 255.0 && v[14] == std::floor(v[14])) << line;
        ++lines;
    }
    EXPECT_EQ(lines, 300u);
}

// An unwritable --smoothed-out is refused before the first pose is read (exit 2), not after an
// hour of streaming.
TEST_F(OnlineSynthetic, SmoothedOutIsCheckedBeforeStreaming) {
    const std::string dir = TmpDir("smoothed_out");
    fs::create_directories(dir);
    const std::string cmd = "echo '1 0 0 0 0 0 0 1' | " + std::string(DRIFTCORR_BINARY_DIR) +
                            "/examples/driftcorr stream " + *dir_ + " --smoothed-out " + dir +
                            "/missing/smoothed.tum > " + dir + "/out.tum 2> " + dir + "/err.txt";
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2);
    const std::string err = Slurp(dir + "/err.txt");
    EXPECT_NE(err.find("--smoothed-out"), std::string::npos) << err;
    EXPECT_NE(err.find("does not exist"), std::string::npos) << err;
    EXPECT_EQ(Slurp(dir + "/out.tum"), "");
}

}  // namespace
