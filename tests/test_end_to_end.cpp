// End to end: drift injected into a known trajectory on a known map must come out measurably
// better, and the real KITTI scenarios must meet the road issue's acceptance figures.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/optim/online_corrector.h"
#include "driftcorr/pipeline/online.h"
#include "driftcorr/pipeline/pipeline.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace driftcorr;

namespace {

std::string TmpDir(const std::string& name) {
    static const fs::path root = test::FreshProcessDir("e2e");
    return test::EmptySubdir(root, name);
}

// Runs the committed generator into a fresh folder; returns the folder.
std::string Generate(const std::string& name, const std::string& args) {
    const std::string dir = TmpDir(name);
    EXPECT_EQ(test::GenerateRoadScenario(dir, args), 0) << args;
    return dir;
}

struct SyntheticCase {
    const char* name;
    const char* generator_args;
};

void PrintTo(const SyntheticCase& c, std::ostream* os) { *os << c.name; }

class SyntheticRoad : public ::testing::TestWithParam<SyntheticCase> {};

// Heading-bias random walk plus step-length scale error on a street grid with parallel streets
// 25 m apart; ground truth drives 1.5 m right of the centre line, so ~1.5-2 m of ATE is the lane.
TEST_P(SyntheticRoad, DriftIsRemoved) {
    const std::string dir = Generate(GetParam().name, GetParam().generator_args);
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    ASSERT_TRUE(run.before && run.after);
    EXPECT_GT(run.before->ate_m, 30.0) << "the scenario must drift for the test to mean anything";
    EXPECT_LE(run.after->ate_m, 3.0);
    EXPECT_LE(run.after->max_m, 5.0);
    EXPECT_LE(run.after->final_m, 0.1 * run.before->final_m);
}

INSTANTIATE_TEST_SUITE_P(
    Seeds, SyntheticRoad,
    ::testing::Values(
        SyntheticCase{"default_seed42", ""},
        SyntheticCase{"short_steps_seed7",
                      "--seed 7 --scale-error 0.93 --heading-bias-deg-per-sqrt-s 0.003"},
        SyntheticCase{"long_steps_seed11",
                      "--seed 11 --scale-error 1.05 --heading-bias-deg-per-sqrt-s 0.003"}),
    [](const auto& p) { return std::string(p.param.name); });

// The corrected trajectory written in the estimate's own frame maps back onto the solver's
// world-plane solution, and keeps the estimate's timestamps.
TEST(EndToEnd, OutputFrameRoundTrip) {
    const std::string dir = Generate("roundtrip", "--duration-s 60");
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(run.result.status));
    const std::string out = dir + "/corrected.tum";
    io::WriteTum(out, run.corrected_frame);
    const Trajectory back = io::ReadTum(out);
    ASSERT_EQ(back.size(), run.estimate.size());
    pipeline::WorldFrame world(run.scenario.anchor);
    const PlanarTrajectory planar = ToPlanar(back, run.scenario.frame, world.planar_anchor());
    for (std::size_t i = 0; i < back.size(); ++i) {
        EXPECT_NEAR(back.t_s[i], run.estimate.t_s[i], 1e-6);
        EXPECT_NEAR((planar.p_en[i] - run.result.corrected.p_en[i]).norm(), 0.0, 1e-5);
        EXPECT_NEAR(std::remainder(planar.yaw_rad[i] - run.result.corrected.yaw_rad[i], 2 * M_PI),
                    0.0, 1e-6);
    }
}

struct KittiCase {
    const char* folder;
    double max_ate_m;    ///< acceptance: corrected ATE at most this
    double final_ratio;  ///< acceptance: corrected final <= ratio * estimate final (0: none)
    bool no_worse_than_estimate;  ///< acceptance: ATE no worse than the estimate's
};

void PrintTo(const KittiCase& c, std::ostream* os) { *os << c.folder; }

class KittiAcceptance : public ::testing::TestWithParam<KittiCase> {};

TEST_P(KittiAcceptance, MeetsTheRoadAccuracyFigures) {
    const std::string dir = std::string(DRIFTCORR_SHARED_DATASETS) + "/" + GetParam().folder;
    if (!fs::exists(dir + "/scenario.yaml")) {
        GTEST_SKIP() << "real data not present: " << dir;
    }
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    ASSERT_TRUE(run.before && run.after);
    EXPECT_LE(run.after->ate_m, GetParam().max_ate_m);
    if (GetParam().final_ratio > 0) {
        EXPECT_LE(run.after->final_m, GetParam().final_ratio * run.before->final_m);
    }
    if (GetParam().no_worse_than_estimate) {
        EXPECT_LE(run.after->ate_m, run.before->ate_m);
    }
}

// Only the scenarios that meet the acceptance are asserted here; the closing note of the road
// issue lists the measured figures of all of them, including those that do not.
INSTANTIATE_TEST_SUITE_P(
    Shared, KittiAcceptance,
    ::testing::Values(KittiCase{"kitti00_cvo_stereo_geometric", 3.0, 0.1, true},
                      KittiCase{"kitti07_cvo_stereo_geometric", 3.0, 0.1, true},
                      KittiCase{"kitti00_gicp_frame2frame", 8.0, 0.0, true},
                      KittiCase{"kitti00_orb2_longruidong", 5.42, 0.0, true}),
    [](const auto& p) { return std::string(p.param.folder); });

// Do no harm: an input the map cannot tell wrong comes back as it was. On the generator's map the
// ground truth drives 1.5 m right of the centre line, so a correction of the true trajectory lands
// about 1.9 m from it (its ATE); the true trajectory lies inside the correction's 95 % region at
// most poses, and is kept. The same drive with its drift is corrected.
TEST(DoNoHarm, AnInputTheMapCannotTellWrongIsKept) {
    const std::string dir = Generate("do_no_harm", "--seed 1 --duration-s 120");
    fs::copy_file(dir + "/ground_truth.tum", dir + "/estimate.tum",
                  fs::copy_options::overwrite_existing);
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    ASSERT_TRUE(run.before && run.after);
    EXPECT_TRUE(run.result.input_kept)
        << run.result.agreement_inside << " of " << run.result.agreement_poses << " inside";
    EXPECT_EQ(run.after->ate_m, run.before->ate_m);
    EXPECT_LT(run.after->ate_m, 1e-3);

    pipeline::PipelineConfig off;
    off.corrector.keep_agreeing_input = false;
    const pipeline::CorrectionRun moved = pipeline::RunCorrection(dir, off);
    ASSERT_TRUE(moved.after);
    EXPECT_FALSE(moved.result.input_kept);
    EXPECT_GT(moved.after->ate_m, 1.0) << "the correction must move the input for the test to mean "
                                          "anything";
    EXPECT_EQ(moved.result.agreement_inside, run.result.agreement_inside);

    // The kept input's covariance is its error's second moment: the correction's covariance plus
    // the outer product of the input's offset from the correction.
    const std::vector<PoseCovariance>& kept = run.result.covariance.poses;
    const std::vector<PoseCovariance>& corrected = moved.result.covariance.poses;
    ASSERT_EQ(kept.size(), corrected.size());
    ASSERT_EQ(kept.size(), moved.result.corrected.size());
    for (std::size_t i = 1; i < kept.size(); ++i) {
        const Eigen::Vector2d d = run.result.corrected.p_en[i] - moved.result.corrected.p_en[i];
        const Eigen::Matrix2d expected = corrected[i].xy_m2 + d * d.transpose();
        ASSERT_LT((kept[i].xy_m2 - expected).norm(), 1e-9 * (1.0 + expected.norm()))
            << "pose " << i;
    }
}

TEST(DoNoHarm, ADriftingInputIsCorrected) {
    const std::string dir = Generate("do_no_harm_drift", "--seed 1 --duration-s 120");
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    ASSERT_TRUE(run.before && run.after);
    EXPECT_FALSE(run.result.input_kept);
    EXPECT_GT(run.result.agreement_poses, 1000u);
    EXPECT_LT(double(run.result.agreement_inside), 0.5 * double(run.result.agreement_poses));
    EXPECT_LT(run.after->ate_m, 0.5 * run.before->ate_m);
}

// The heading-rate bias as a freedom decided per input: kept where the odometry's heading
// drifts (the generator's heading-rate bias random walk), left out where it does not; the result
// is then the correction without it, to the bit.
TEST(DecidedFreedoms, TheHeadingBiasIsKeptOnlyWhereTheHeadingDrifts) {
    pipeline::PipelineConfig decide;
    decide.corrector.decide_heading_bias = true;
    const std::string drifting =
        Generate("bias_drifting", "--seed 3 --duration-s 300 --heading-bias-deg-per-sqrt-s 0.05");
    const pipeline::CorrectionRun a = pipeline::RunCorrection(drifting, decide);
    ASSERT_TRUE(a.result.heading_bias.has_value());
    EXPECT_TRUE(a.result.heading_bias->kept)
        << a.result.heading_bias->nll_with << " + " << a.result.heading_bias->price << " vs "
        << a.result.heading_bias->nll_without;

    const std::string steady =
        Generate("bias_steady", "--seed 3 --duration-s 300 --heading-bias-deg-per-sqrt-s 0");
    const pipeline::CorrectionRun b = pipeline::RunCorrection(steady, decide);
    ASSERT_TRUE(b.result.heading_bias.has_value());
    EXPECT_FALSE(b.result.heading_bias->kept)
        << b.result.heading_bias->nll_with << " + " << b.result.heading_bias->price << " vs "
        << b.result.heading_bias->nll_without;
    pipeline::PipelineConfig off;
    off.corrector.model.heading_bias_segment_s = 0.0;
    const pipeline::CorrectionRun c = pipeline::RunCorrection(steady, off);
    ASSERT_TRUE(b.after && c.after);
    EXPECT_EQ(b.after->ate_m, c.after->ate_m);
    EXPECT_FALSE(c.result.heading_bias.has_value());
}

// Runs the committed stress generator on the scenario `input` into `out` with `args`; its output
// goes to out.log. Returns the exit status.
int MakeStressVariants(const std::string& input, const std::string& out, const std::string& args) {
    const std::string command = std::string("\"") + DRIFTCORR_BINARY_DIR +
                                "/datasets/driftcorr_make_stress_variants\" \"" + input + "\" \"" +
                                out + "\" " + args + " > \"" + out + ".log\" 2>&1";
    return std::system(command.c_str());
}

// KITTI 07's accurate LiDAR odometry with the street it drives along the longest removed from the
// map (the stress generator's road_removed): the correction pulls the drive onto other streets
// and explains the data worse than the input itself does, so the input comes back as it was,
// degraded with that reason.
TEST(DoNoHarm, AnInputThatExplainsTheDataBetterIsKeptAndDegraded) {
    const std::string real = std::string(DRIFTCORR_SHARED_DATASETS) + "/kitti07_imls_aloam_fork";
    if (!fs::exists(real + "/scenario.yaml")) GTEST_SKIP() << "real data not present: " << real;
    const std::string out = TmpDir("road_removed");
    ASSERT_EQ(MakeStressVariants(real, out, ""), 0);
    const pipeline::CorrectionRun run =
        pipeline::RunCorrection(out + "/road_removed", pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    ASSERT_TRUE(run.before && run.after);
    EXPECT_TRUE(run.result.input_nll_lower)
        << run.result.input_nll << " against " << run.result.nll;
    EXPECT_TRUE(run.result.input_kept);
    EXPECT_EQ(run.after->ate_m, run.before->ate_m);
    // Its covariance is the model's at the input, not the correction's.
    ASSERT_EQ(run.result.covariance.status, CovarianceStatus::kOk);
    ASSERT_EQ(run.result.covariance.poses.size(), run.result.corrected.size());
    EXPECT_EQ(run.verdict.level, VerdictLevel::kDegraded);
    EXPECT_TRUE(std::any_of(
        run.verdict.reasons.begin(), run.verdict.reasons.end(),
        [](const std::string& r) { return r.find("worse than the input") != std::string::npos; }));

    pipeline::PipelineConfig off;
    off.corrector.keep_agreeing_input = false;
    const pipeline::CorrectionRun moved = pipeline::RunCorrection(out + "/road_removed", off);
    ASSERT_TRUE(moved.after);
    EXPECT_GT(moved.after->ate_m, run.before->ate_m + 1.0)
        << "the correction must be worse than the input for the test to mean anything";
    ASSERT_EQ(moved.result.covariance.status, CovarianceStatus::kOk);
    double most = 0.0;
    for (std::size_t i = 0; i < run.result.covariance.poses.size(); ++i) {
        most = std::max(most, std::abs(run.result.covariance.poses[i].xy_m2(0, 0) -
                                       moved.result.covariance.poses[i].xy_m2(0, 0)));
    }
    EXPECT_GT(most, 1e-6) << "the kept input's covariance is its own";
}

// KITTI 07's stereo drive as a monocular tracker would have written it (a tenth of its size, the
// scale drifting 2 % per sqrt(100 m)): taken as metric it is bad input naming anchor.scale; with
// `scale: auto` its size is found from the map and it is corrected about as well as the metric
// drive.
TEST(Monocular, ItsSizeIsFoundFromTheMapAndWithoutScaleAutoItIsNamed) {
    const std::string real =
        std::string(DRIFTCORR_SHARED_DATASETS) + "/kitti07_cvo_stereo_geometric";
    if (!fs::exists(real + "/scenario.yaml")) GTEST_SKIP() << "real data not present: " << real;
    const std::string out = TmpDir("monocular");
    ASSERT_EQ(MakeStressVariants(real, out, "--monocular 0.1"), 0);
    try {
        pipeline::RunCorrection(out + "/mono_0.1", pipeline::PipelineConfig{});
        ADD_FAILURE() << "a monocular estimate taken as metric must be bad input";
    } catch (const InputError& e) {
        EXPECT_EQ(e.key(), "anchor.scale");
        EXPECT_NE(std::string(e.what()).find("monocular"), std::string::npos) << e.what();
    }
    const pipeline::CorrectionRun metric =
        pipeline::RunCorrection(real, pipeline::PipelineConfig{});
    const pipeline::CorrectionRun mono =
        pipeline::RunCorrection(out + "/mono_0.1_auto", pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(mono.result.status)) << mono.result.message;
    ASSERT_TRUE(metric.after && mono.after && mono.before);
    EXPECT_NEAR(mono.global_scale, 10.0, 0.5);
    EXPECT_NE(mono.verdict.level, VerdictLevel::kFailed);
    EXPECT_LE(mono.after->ate_m, 1.5 * metric.after->ate_m);
    EXPECT_LT(mono.after->ate_m, 0.5 * mono.before->ate_m);
}

// A generated drive (starting 800 m from its frame's origin, on a regular grid of streets) as a
// monocular tracker would write it: the frame's origin at the first pose (the anchor moved there),
// a tenth of the size, drifting 2 % per sqrt(100 m). On the grid the leading kilometre fits
// several wrong scales better than the right one, and the scale drifts over the first 400 m: the
// scale is found among the leading path's six best fits by their whole corrections, the start is
// checked at the scale the leading path fits best, and the drive is corrected about as well as
// the metric one.
TEST(Monocular, AGeneratedDriveOnAGridIsCorrected) {
    const std::string dir = Generate("mono_grid_drive", "--seed 1");
    const std::string out = TmpDir("mono_grid");
    ASSERT_EQ(MakeStressVariants(dir, out, "--monocular 0.1 --monocular-drift 0.02 --seed 1"), 0);
    const pipeline::CorrectionRun metric = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    const pipeline::CorrectionRun mono =
        pipeline::RunCorrection(out + "/mono_0.1_auto", pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(mono.result.status)) << mono.result.message;
    ASSERT_TRUE(metric.after && mono.after && mono.ground_truth);
    EXPECT_NE(mono.verdict.level, VerdictLevel::kFailed);
    EXPECT_LE(mono.after->ate_m, 1.5 * metric.after->ate_m);
    const double truth =
        PathLength(*mono.ground_truth) / (PathLength(mono.estimate) / mono.global_scale);
    EXPECT_NEAR(pipeline::DriveScaleOf(mono).value, truth, 0.05 * truth);
}

// KITTI 00's stereo drive as a monocular tracker would write it (a tenth of its size, drifting
// 2 % per sqrt(100 m)), streamed with `scale: auto`: the first outputs are the input at the best
// scale so far (flagged, no covariance); once that scale's leading path is 1000 m the scale is
// found, the online correction takes every pose so far and its outputs are corrections; the
// smoothed result is about as good as the batch's.
TEST(Monocular, TheStreamFindsTheScaleThenCorrects) {
    const std::string real =
        std::string(DRIFTCORR_SHARED_DATASETS) + "/kitti00_cvo_stereo_geometric";
    if (!fs::exists(real + "/scenario.yaml")) GTEST_SKIP() << "real data not present: " << real;
    const std::string out = TmpDir("mono_stream");
    ASSERT_EQ(MakeStressVariants(real, out, "--monocular 0.1"), 0);
    const std::string mono = out + "/mono_0.1_auto";
    const pipeline::CorrectionRun batch = pipeline::RunCorrection(mono, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(batch.result.status) && batch.after && batch.ground_truth);
    OnlineConfig online;
    online.synchronous = true;
    online.corrector = pipeline::CorrectorFor(batch.scenario, pipeline::PipelineConfig{});
    pipeline::StreamSession session(pipeline::LoadStreamSetup(mono, {}), online, VerdictConfig{});
    std::size_t searching = 0, first_correction = 0;
    for (std::size_t i = 0; i < batch.estimate_frame.size(); ++i) {
        const auto o = session.Push(batch.estimate_frame.t_s[i], batch.estimate_frame.p_frame[i],
                                    batch.estimate_frame.q_frame_body[i]);
        ASSERT_TRUE(o.result.Accepted()) << i << ": " << o.result.message;
        if (o.result.doubt & kDoubtScaleSearch) {
            ++searching;
            EXPECT_EQ(first_correction, 0u) << "flagged again at pose " << i;
            EXPECT_FALSE(o.result.covariance_ok) << i;
        } else if (first_correction == 0) {
            first_correction = i;
        }
    }
    EXPECT_GT(searching, 10u);
    EXPECT_EQ(first_correction, searching) << "the outputs are corrections once the scale is found";
    EXPECT_LT(first_correction, batch.estimate_frame.size() / 2);
    const auto end = session.Finish();
    ASSERT_TRUE(end && Usable(end->result.status)) << (end ? end->result.message : "");
    ASSERT_TRUE(end->scale.has_value());
    EXPECT_EQ(end->outputs_before_scale, searching);
    EXPECT_NEAR(end->scale->scale, batch.global_scale, 0.1 * batch.global_scale);
    const double smoothed = ComputeMetrics(end->result.corrected, *batch.ground_truth).ate_m;
    std::printf(
        "monocular stream: scale %.3f (batch %.3f) after %zu poses; smoothed ATE %.2f m, "
        "batch %.2f m\n",
        end->scale->scale, batch.global_scale, searching, smoothed, batch.after->ate_m);
    EXPECT_LE(smoothed, 1.5 * batch.after->ate_m + 0.5);
}

// Rewrites the TUM estimate in `dir` with its steps stretched by `first` over the first half of
// the poses and by `second` after: an odometry whose scale changes during the drive.
void ChangeScaleHalfway(const std::string& dir, double first, double second) {
    std::istringstream in(test::ReadFile(dir + "/estimate.tum"));
    std::vector<std::vector<double>> rows;
    for (std::string line; std::getline(in, line);) {
        std::istringstream fields(line);
        std::vector<double> row(8);
        for (double& v : row) fields >> v;
        if (fields) rows.push_back(row);
    }
    ASSERT_GT(rows.size(), 10u);
    std::ostringstream out;
    out.precision(10);
    double x = rows[0][1], y = rows[0][2];
    for (std::size_t i = 0; i < rows.size(); ++i) {
        if (i > 0) {
            const double k = i < rows.size() / 2 ? first : second;
            x += k * (rows[i][1] - rows[i - 1][1]);
            y += k * (rows[i][2] - rows[i - 1][2]);
        }
        out << rows[i][0] << ' ' << x << ' ' << y;
        for (int c = 3; c < 8; ++c) out << ' ' << rows[i][c];
        out << '\n';
    }
    test::WriteFile(dir + "/estimate.tum", out.str());
}

// One scale for a drive whose odometry keeps its scale, the walk where the scale changes; each
// as good as the other choice forced.
TEST(DecidedFreedoms, TheScaleWalkIsKeptOnlyWhereTheScaleChanges) {
    pipeline::PipelineConfig decide;
    decide.corrector.decide_scale_walk = true;
    pipeline::PipelineConfig one = decide;  // the walk's segments longer than the drive
    one.corrector.decide_scale_walk = false;
    one.corrector.model.scale_segment_m = 1e6;
    pipeline::PipelineConfig walk = decide;
    walk.corrector.decide_scale_walk = false;

    const std::string args = "--seed 3 --duration-s 300 --heading-bias-deg-per-sqrt-s 0";
    const std::string steady = Generate("walk_steady", args + " --scale-error 0.97");
    const pipeline::CorrectionRun a = pipeline::RunCorrection(steady, decide);
    ASSERT_TRUE(a.result.scale_walk.has_value() && a.after);
    EXPECT_EQ(a.result.scale_walk->kept, ScaleWalkDecision::Kept::kOneScale)
        << a.result.scale_walk->nll_one_scale << " vs " << a.result.scale_walk->nll_refined << " + "
        << a.result.scale_walk->price_refined;
    const pipeline::CorrectionRun a_walk = pipeline::RunCorrection(steady, walk);
    ASSERT_TRUE(a_walk.after);
    EXPECT_LE(a.after->ate_m, 1.05 * a_walk.after->ate_m + 0.1);

    const std::string changing = Generate("walk_changing", args + " --scale-error 1.0");
    ChangeScaleHalfway(changing, 0.92, 1.08);
    const pipeline::CorrectionRun b = pipeline::RunCorrection(changing, decide);
    ASSERT_TRUE(b.result.scale_walk.has_value() && b.after);
    EXPECT_NE(b.result.scale_walk->kept, ScaleWalkDecision::Kept::kOneScale)
        << b.result.scale_walk->nll_one_scale << " vs " << b.result.scale_walk->nll_refined << " + "
        << b.result.scale_walk->price_refined;
    const pipeline::CorrectionRun b_one = pipeline::RunCorrection(changing, one);
    ASSERT_TRUE(b_one.after);
    EXPECT_LE(b.after->ate_m, 1.05 * b_one.after->ate_m + 0.1);
}

// The synthetic grid town (datasets/large_town/make_large_town.py, 4 km, a steady 1 % scale
// error): the windows stretch the last segments before the drive's turn (scale 0.99 -> 1.08) and
// the final solve stays in that basin (measured ATE 52.87 m against the input's 19.64 m, NLL
// 25.6); the same solution with one scale has a lower NLL of the same model and lies on the
// truth's street.
TEST(OneScaleStart, APoorerBasinOfTheWalkIsLeftForOneScales) {
    const std::string dir = TmpDir("town");
    const std::string cmd = "/usr/bin/python3 " + std::string(DRIFTCORR_SOURCE_DIR) +
                            "/datasets/large_town/make_large_town.py " + dir +
                            " --size 4000 --leg 2000 > /dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    pipeline::PipelineConfig with, without;
    with.corrector.one_scale_start = true;
    without.corrector.one_scale_start = false;
    const pipeline::CorrectionRun a = pipeline::RunCorrection(dir, with);
    const pipeline::CorrectionRun b = pipeline::RunCorrection(dir, without);
    ASSERT_TRUE(a.before && a.after && b.after);
    ASSERT_TRUE(a.result.one_scale_start.has_value());
    EXPECT_FALSE(b.result.one_scale_start.has_value());
    const OneScaleStart& d = *a.result.one_scale_start;
    std::printf(
        "NLL %.2f from the windows, %.2f with one scale, %.2f refined; ATE %.2f m with, "
        "%.2f m without (input %.2f m)\n",
        d.nll_walk, d.nll_one_scale, d.nll_refined, a.after->ate_m, b.after->ate_m,
        a.before->ate_m);
    EXPECT_TRUE(d.from_one_scale);
    EXPECT_LT(d.nll_one_scale, d.nll_walk);
    EXPECT_LE(d.nll_refined, d.nll_one_scale + 1e-6);
    EXPECT_NEAR(a.result.nll, d.nll_refined, 1e-9);
    EXPECT_NEAR(b.result.nll, d.nll_walk, 1e-6);  // the same windows and final solve
    EXPECT_LT(a.after->ate_m, 1.0);
    EXPECT_GT(b.after->ate_m, a.before->ate_m) << "without it, worse than the input";
}

// On a drive whose walk solution is the better basin, the result is the walk's, unchanged.
TEST(OneScaleStart, TheWalksBasinIsKeptWhereOneScaleIsPoorer) {
    const std::string dir = Generate("one_scale_start", "--seed 2");
    pipeline::PipelineConfig with, without;
    with.corrector.one_scale_start = true;
    without.corrector.one_scale_start = false;
    const pipeline::CorrectionRun a = pipeline::RunCorrection(dir, with);
    const pipeline::CorrectionRun b = pipeline::RunCorrection(dir, without);
    ASSERT_TRUE(a.after && b.after && a.result.one_scale_start.has_value());
    EXPECT_FALSE(a.result.one_scale_start->from_one_scale);
    EXPECT_GT(a.result.one_scale_start->nll_one_scale, a.result.one_scale_start->nll_walk);
    ASSERT_EQ(a.result.corrected.p_en.size(), b.result.corrected.p_en.size());
    for (std::size_t i = 0; i < a.result.corrected.p_en.size(); ++i) {
        ASSERT_EQ(a.result.corrected.p_en[i], b.result.corrected.p_en[i]) << "pose " << i;
    }
}

// The accurate LiDAR odometry of KITTI 07 (0.57 m ATE) comes back as it was.
TEST(DoNoHarm, AccurateLidarOdometryComesBackAsItWas) {
    const std::string dir = std::string(DRIFTCORR_SHARED_DATASETS) + "/kitti07_imls_aloam_fork";
    if (!fs::exists(dir + "/scenario.yaml")) GTEST_SKIP() << "real data not present: " << dir;
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    ASSERT_TRUE(run.before && run.after);
    EXPECT_TRUE(run.result.input_kept);
    EXPECT_LE(run.after->ate_m, run.before->ate_m + 0.3);
    EXPECT_EQ(run.verdict.level, VerdictLevel::kOk);
}

// The same input gives the same bits: kitti05 cvo's final solve needs Ipopt, whose result hangs
// on MUMPS's fill-reducing ordering. With METIS (MUMPS's automatic choice) the two runs below
// differed in all 2760 poses, three tries out of three.
TEST(Reproducible, TheSameDriveTwiceGivesTheSameBits) {
    const std::string dir =
        std::string(DRIFTCORR_SHARED_DATASETS) + "/kitti05_cvo_stereo_geometric";
    if (!fs::exists(dir + "/scenario.yaml")) {
        GTEST_SKIP() << "real data not present: " << dir;
    }
    const pipeline::CorrectionRun a = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    const pipeline::CorrectionRun b = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(a.result.status)) << a.result.message;
    EXPECT_EQ(a.result.message, b.result.message);
    EXPECT_EQ(a.verdict.level, b.verdict.level);
    ASSERT_EQ(a.result.corrected.p_en.size(), b.result.corrected.p_en.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.result.corrected.p_en.size(); ++i) {
        differ += a.result.corrected.p_en[i] != b.result.corrected.p_en[i] ||
                  a.result.corrected.yaw_rad[i] != b.result.corrected.yaw_rad[i];
    }
    EXPECT_EQ(differ, 0u) << "poses that differ between two runs of the same input";
}

}  // namespace

namespace {

// Real indoor PDR walk on GeoJSON floor plans and walkways of three floors: the corrector must
// pick the right floor itself (all poses) and meet the issue's ATE <= 1.0 m (measured 0.94 m with
// the pedestrian defaults, which were chosen on other walks: CorrectorConfig::Pedestrian()).
TEST(EndToEndIndoor, HcuEightMeetsTheIndoorIssueFigures) {
    const std::string dir = std::string(DRIFTCORR_SHARED_DATASETS) + "/hcu_eight";
    if (!fs::exists(dir + "/scenario.yaml")) {
        GTEST_SKIP() << "real data not present: " << dir;
    }
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(run.result.status)) << run.result.message;
    ASSERT_TRUE(run.before && run.after);
    EXPECT_EQ(run.after->floor_accuracy, 1.0);
    EXPECT_LE(run.after->ate_m, 1.0);
}

}  // namespace

namespace {

// The numbers of each line of a text file.
std::vector<std::vector<double>> ReadNumbers(const std::string& path) {
    std::vector<std::vector<double>> rows;
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);) {
        std::istringstream ss(line);
        rows.emplace_back(std::istream_iterator<double>(ss), std::istream_iterator<double>());
    }
    return rows;
}

// The HCU walk generator (datasets/ipin21/make_hcu_walks.py): the same seed gives the same bytes,
// another seed another walk; every walk changes floor (its ground truth leaves the start floor)
// and starts its estimate at the ground truth's first pose.
TEST(HcuWalkGenerator, DeterministicAndEveryWalkChangesFloor) {
    const std::string src = std::string(DRIFTCORR_SHARED_DATASETS) + "/hcu_eight";
    if (!fs::exists(src + "/scenario.yaml")) GTEST_SKIP() << "real data not present: " << src;
    const std::string script = "/usr/bin/python3 " + std::string(DRIFTCORR_SOURCE_DIR) +
                               "/datasets/ipin21/make_hcu_walks.py ";
    const std::string a = TmpDir("hcu_gen_a"), b = TmpDir("hcu_gen_b");
    ASSERT_EQ(std::system((script + src + " " + a + " --seeds 1-4 > /dev/null").c_str()), 0);
    ASSERT_EQ(std::system((script + src + " " + b + " --seeds 1-4 > /dev/null").c_str()), 0);
    auto read = [](const std::string& path) {
        std::ifstream in(path);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    std::set<std::string> estimates;
    for (int seed = 1; seed <= 4; ++seed) {
        const std::string walk = "/walk_" + std::to_string(seed);
        for (const char* f : {"/estimate.tum", "/ground_truth.tum", "/scenario.yaml"}) {
            EXPECT_EQ(read(a + walk + f), read(b + walk + f)) << walk << f;
        }
        estimates.insert(read(a + walk + "/estimate.tum"));
        const std::vector<std::vector<double>> gt = ReadNumbers(a + walk + "/ground_truth.tum");
        const std::vector<std::vector<double>> est = ReadNumbers(a + walk + "/estimate.tum");
        ASSERT_EQ(gt.size(), est.size()) << walk;
        ASSERT_GT(gt.size(), 100u) << walk;
        for (int k = 1; k <= 3; ++k) EXPECT_EQ(gt[0][k], est[0][k]) << walk;
        double max_dz = 0.0;
        for (const auto& row : gt) max_dz = std::max(max_dz, std::abs(row[3] - gt[0][3]));
        EXPECT_GE(max_dz, 6.0) << walk << ": the walk must change floor (floors are 6-18 m apart)";
    }
    EXPECT_EQ(estimates.size(), 4u);
}

// The walk of `seed` from the HCU walk generator (datasets/ipin21/make_hcu_walks.py) in a fresh
// temporary folder; "" when the HCU plans are not present. Without `gait`, the walker's steps
// are alike along a leg (--gait-sd 0: the walks the tests below describe).
std::string GeneratedHcuWalk(int seed, bool gait = false) {
    const std::string src = std::string(DRIFTCORR_SHARED_DATASETS) + "/hcu_eight";
    if (!fs::exists(src + "/scenario.yaml")) return "";
    const std::string n = std::to_string(seed);
    const std::string out = TmpDir("hcu_walk_" + n);
    const std::string cmd = "/usr/bin/python3 " + std::string(DRIFTCORR_SOURCE_DIR) +
                            "/datasets/ipin21/make_hcu_walks.py " + src + " " + out + " --seeds " +
                            n + "-" + n + (gait ? "" : " --gait-sd 0") + " > /dev/null";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return out + "/walk_" + n;
}

// A generated walk whose walker varies its step with its gait (seed 16 of the generator's
// defaults, one of the seeds the pedestrian step_length_exponent was chosen on): read as they
// are, the PDR's step lengths, which follow half of the gait and err besides, put the walk along
// the wrong stretch of a corridor, measured ATE 7.62 m with verdict ok; read about their median,
// 0.56 m. Both on the right floor.
TEST(EndToEndIndoor, PdrStepsReadAboutTheirMedianKeepTheWalkOnTrack) {
    const std::string walk = GeneratedHcuWalk(16, true);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    const pipeline::CorrectionRun median = pipeline::RunCorrection(walk, {});
    pipeline::PipelineConfig as_read;
    as_read.indoor_corrector.model.step_length_exponent = 1.0;
    const pipeline::CorrectionRun read = pipeline::RunCorrection(walk, as_read);
    ASSERT_TRUE(median.after && read.after);
    std::printf(
        "read about the median: ATE %.2f m, right floor %.1f %%; as read: %.2f m, %.1f %%\n",
        median.after->ate_m, 100.0 * median.after->floor_accuracy, read.after->ate_m,
        100.0 * read.after->floor_accuracy);
    EXPECT_GT(read.after->ate_m, 4.0) << "as read, the walk must leave its track";
    EXPECT_LT(median.after->ate_m, 1.0);
    EXPECT_GE(median.after->floor_accuracy, 0.99);
    EXPECT_NE(median.verdict.level, VerdictLevel::kFailed);
}

// The pedestrian defaults with the PDR's step lengths as read (step_length_exponent 1), in which
// walks 18, 3, 5 and 40 show what the tests below need. Read about their median (the default),
// walks 18, 3 and 40 end on the right floor with or without the part a test exercises, and walk
// 5's starts part by less than its test asks.
pipeline::PipelineConfig StepsAsRead();

// The reading of the step lengths decided per walk (CorrectorConfig::decide_step_reading, on by
// default): on two generated walks whose walkers vary their steps with their gait (seeds 16 and
// 7), the correction with the step lengths as read replaces the one read about the median only
// where its NLL is lower by more than 1/2 ln n (measured: seed 16, as read 74.9 higher, ATE 7.62
// against 0.56 m; seed 7, as read 16.8 lower, 1.88 against 2.83 m), and the result is then that
// correction itself.
TEST(EndToEndIndoor, TheStepReadingIsDecidedPerWalk) {
    for (const int seed : {16, 7}) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        const std::string walk = GeneratedHcuWalk(seed, true);
        if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
        const pipeline::CorrectionRun decided = pipeline::RunCorrection(walk, {});
        pipeline::PipelineConfig median_cfg;
        median_cfg.indoor_corrector.decide_step_reading = false;
        pipeline::PipelineConfig read_cfg = StepsAsRead();
        read_cfg.indoor_corrector.decide_step_reading = false;
        const pipeline::CorrectionRun median = pipeline::RunCorrection(walk, median_cfg);
        const pipeline::CorrectionRun read = pipeline::RunCorrection(walk, read_cfg);
        ASSERT_TRUE(decided.after && median.after && read.after);
        ASSERT_TRUE(decided.result.step_reading.has_value());
        const StepReadingDecision& d = *decided.result.step_reading;
        std::printf(
            "seed %d: NLL %.1f about the median, %.1f as read, price %.1f; ATE %.2f / %.2f "
            "m, decided %.2f m\n",
            seed, d.nll_about_median, d.nll_as_read, d.price, median.after->ate_m,
            read.after->ate_m, decided.after->ate_m);
        EXPECT_EQ(d.as_read, d.nll_as_read + d.price < d.nll_about_median);
        EXPECT_EQ(d.as_read, seed == 7);
        const pipeline::CorrectionRun& expected = d.as_read ? read : median;
        ASSERT_EQ(decided.result.corrected.size(), expected.result.corrected.size());
        for (std::size_t i = 0; i < expected.result.corrected.size(); ++i) {
            EXPECT_LT((decided.result.corrected.p_en[i] - expected.result.corrected.p_en[i]).norm(),
                      1e-6)
                << "pose " << i;
        }
        EXPECT_LE(decided.after->ate_m, std::min(median.after->ate_m, read.after->ate_m) + 1e-6);
    }
}

pipeline::PipelineConfig StepsAsRead() {
    pipeline::PipelineConfig c;
    c.indoor_corrector.model.step_length_exponent = 1.0;
    return c;
}

// A generated walk in the real HCU building (datasets/ipin21/make_hcu_walks.py, seed 13, one of
// the seeds the pedestrian defaults were chosen on): a lift ride from the 4th floor to the ground
// floor that the barometer reads 0.77x, so the floor nearest to the reading is the 1st. Only the
// floor hypotheses (restart_height_gains) find the ground floor: measured 99.8 % of the poses on
// the right floor and ATE 1.11 m with them, 59.2 % and 1.89 m without (the ATE is mostly along
// the track: the PDR's slowly varying step-length error).
TEST(EndToEndIndoor, LiftRideMisreadByTheBarometerEndsOnTheRightFloor) {
    const std::string walk = GeneratedHcuWalk(13);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    pipeline::PipelineConfig with;
    const pipeline::CorrectionRun a = pipeline::RunCorrection(walk, with);
    pipeline::PipelineConfig without;
    without.indoor_corrector.restart_height_gains.clear();
    const pipeline::CorrectionRun b = pipeline::RunCorrection(walk, without);
    ASSERT_TRUE(a.after && b.after);
    std::printf(
        "with the floor hypotheses: right floor %.1f %%, ATE %.2f m; without: %.1f %%, "
        "%.2f m\n",
        100.0 * a.after->floor_accuracy, a.after->ate_m, 100.0 * b.after->floor_accuracy,
        b.after->ate_m);
    EXPECT_LT(b.after->floor_accuracy, 0.9) << "the walk must mislead the nearest-floor choice";
    EXPECT_GE(a.after->floor_accuracy, 0.99);
    EXPECT_LT(a.after->ate_m, b.after->ate_m);
}

// A generated walk in the real HCU building (seed 18, one of the seeds the pedestrian defaults
// were chosen on): a lift ride from the 1st floor to the 4th, the barometer reading it 0.91x,
// and one from the 4th to the ground floor read 0.90x. The windows take the second ride to the
// 1st floor (0.72x of its reading, against 1.15x for the first); the whole correction on the ground
// floor scores 0.5 lower, within the margin that the solves' basins call for. Its rides' gains
// agree, the kept correction's do not: measured NLL 76.4 + 0.1 of the gains against 76.9 + 53.5,
// right floor 100 % (84.5 % by the NLL alone).
TEST(EndToEndIndoor, TheFloorWhoseRidesReadAlikeIsKept) {
    const std::string walk = GeneratedHcuWalk(18);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    const pipeline::CorrectionRun with = pipeline::RunCorrection(walk, StepsAsRead());
    pipeline::PipelineConfig nll_alone = StepsAsRead();
    nll_alone.indoor_corrector.floor_gain_sigma = 0.0;
    const pipeline::CorrectionRun without = pipeline::RunCorrection(walk, nll_alone);
    ASSERT_TRUE(with.after && without.after);
    std::printf("with the gains: right floor %.1f %%, ATE %.2f m; NLL alone: %.1f %%, %.2f m\n",
                100.0 * with.after->floor_accuracy, with.after->ate_m,
                100.0 * without.after->floor_accuracy, without.after->ate_m);
    EXPECT_LT(without.after->floor_accuracy, 0.9) << "the NLL alone must keep the wrong floor";
    EXPECT_GE(with.after->floor_accuracy, 0.99);
    bool kept = false;
    for (const CorrectionResult::FloorHypothesis& h : with.result.floor_hypotheses) {
        if (!h.kept) continue;
        kept = true;
        EXPECT_LT(h.gain_nll, 1.0) << "the kept floor's rides read alike";
        EXPECT_GT(h.against_gain_nll, 20.0);
    }
    EXPECT_TRUE(kept);
    for (const CorrectionResult::FloorHypothesis& h : without.result.floor_hypotheses) {
        EXPECT_FALSE(h.kept);
        EXPECT_EQ(h.gain_nll, 0.0);
    }
}

// A generated walk in the real HCU building (seed 3, one of the seeds the pedestrian defaults
// were chosen on): a lift ride from the 4th floor to the ground floor, then a stair climb to the
// 1st. Right after the ride the ground floor's walkways lie within 2 m of the 1st floor's, so the
// windows settle the 1st floor (barometer 0.9x, but its sigma is 25 % of the change) and walk
// the squeezed path on; 80 m later the ground floor's walkways part from the 1st's by 10 m, and
// the stair climb leads from the 1st floor to no floor. The whole correction on the ground floor
// explains the walk far better: measured NLL 154.3 against 250.8, right floor 100 % and ATE 1.02
// m, verdict ok; without the floor hypotheses (never kept) 66.2 %, 4.46 m, failed.
TEST(EndToEndIndoor, AWholeCorrectionOnAnotherFloorIsKeptWhenTheWalkExplainsItBetter) {
    const std::string walk = GeneratedHcuWalk(3);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    const pipeline::CorrectionRun with = pipeline::RunCorrection(walk, StepsAsRead());
    pipeline::PipelineConfig never = StepsAsRead();
    never.indoor_corrector.floor_hypothesis_margin = 1e9;
    const pipeline::CorrectionRun without = pipeline::RunCorrection(walk, never);
    ASSERT_TRUE(with.after && without.after);
    std::printf(
        "with the floor hypotheses: right floor %.1f %%, ATE %.2f m, %s; never kept: %.1f "
        "%%, %.2f m, %s\n",
        100.0 * with.after->floor_accuracy, with.after->ate_m, ToString(with.verdict.level).c_str(),
        100.0 * without.after->floor_accuracy, without.after->ate_m,
        ToString(without.verdict.level).c_str());
    EXPECT_LT(without.after->floor_accuracy, 0.9) << "the windows must settle the wrong floor";
    EXPECT_EQ(without.verdict.level, VerdictLevel::kFailed);
    EXPECT_GE(with.after->floor_accuracy, 0.99);
    EXPECT_LT(with.after->ate_m, 0.5 * without.after->ate_m);
    EXPECT_NE(with.verdict.level, VerdictLevel::kFailed);
    // The hypotheses tried are the same until one is kept; the kept one's NLL is the result's.
    const std::vector<CorrectionResult::FloorHypothesis>& tried = with.result.floor_hypotheses;
    ASSERT_FALSE(tried.empty());
    ASSERT_FALSE(without.result.floor_hypotheses.empty());
    std::size_t kept = 0;
    for (const CorrectionResult::FloorHypothesis& h : tried) {
        if (!h.kept) continue;
        ++kept;
        EXPECT_LT(h.nll + h.gain_nll,
                  h.against + h.against_gain_nll -
                      pipeline::PipelineConfig{}.indoor_corrector.floor_hypothesis_margin);
        EXPECT_NE(h.tried_m, h.chosen_m);
    }
    EXPECT_EQ(kept, 1u);
    for (const CorrectionResult::FloorHypothesis& h : without.result.floor_hypotheses) {
        EXPECT_FALSE(h.kept);
    }
    EXPECT_LT(with.result.nll, without.result.nll);
}

// `walk` corrected with the defaults (the pedestrian start scales) and from scale 1 alone.
std::pair<pipeline::CorrectionRun, pipeline::CorrectionRun> FromStartsAndFromOne(
    const std::string& walk) {
    pipeline::PipelineConfig one;
    one.indoor_corrector.start_scales = {1.0};
    return {pipeline::RunCorrection(walk, {}), pipeline::RunCorrection(walk, one)};
}

// A generated walk in the real HCU building (seed 26, one of the seeds the start scales were
// chosen on) whose steps are 1.29x the PDR's: corrected from scale 1 alone its path stays squeezed
// into a corridor beside the true one (measured ATE 6.46 m); from the pedestrian starts (1, 1.25,
// 1.5) the lowest NLL is that of a start near the true scale (1.22 m). Each start's NLL is what a
// correction from that start alone reaches, and the kept one is the lowest.
TEST(EndToEndIndoor, TheStartScaleOfLowestNllIsKept) {
    const std::string walk = GeneratedHcuWalk(26);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    const auto [all, from_one] = FromStartsAndFromOne(walk);
    ASSERT_TRUE(all.after && from_one.after);
    const CorrectionResult& r = all.result;
    ASSERT_EQ(r.start_scales.size(), 3u);
    ASSERT_EQ(r.start_nll.size(), 3u);
    EXPECT_EQ(from_one.result.start_nll.size(), 1u);
    EXPECT_DOUBLE_EQ(r.start_nll[0], from_one.result.nll);
    for (double nll : r.start_nll) EXPECT_LE(r.nll, nll);
    EXPECT_DOUBLE_EQ(r.nll, r.start_nll[r.start_chosen]);
    EXPECT_NE(r.start_chosen, 0u);
    std::printf("from scale 1: NLL %.1f, ATE %.2f m; kept start %.2f: NLL %.1f, ATE %.2f m\n",
                from_one.result.nll, from_one.after->ate_m, r.start_scales[r.start_chosen], r.nll,
                all.after->ate_m);
    EXPECT_LT(all.after->ate_m, 0.5 * from_one.after->ate_m);
}

// A generated walk in the real HCU building (seed 22, one of the seeds the pedestrian defaults
// were chosen on) along corridors whose side doors repeat every few metres, so that a path
// squeezed to the PDR's scale meets a door wherever the true one turns. Each start's windows hold
// the scale about the start: from 1.25 and 1.5 they keep the true scale's basin, 8 m from the
// squeezed one that the start from 1 keeps (measured NLL 50.7 against 68.7, ATE 1.66 m against
// 9.22 m from scale 1 alone). With the windows' prior about 1 for every start, all three reached
// the squeezed path (RMS 0.13 and 0.32 m from it; ATE 9.33 m).
TEST(EndToEndIndoor, EachStartScaleIsAHypothesisItsWindowsKeep) {
    const std::string walk = GeneratedHcuWalk(22);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    const auto [all, from_one] = FromStartsAndFromOne(walk);
    ASSERT_TRUE(all.after && from_one.after);
    const CorrectionResult& r = all.result;
    ASSERT_EQ(r.start_rms_m.size(), 3u);
    std::printf(
        "starts' NLL %.1f / %.1f / %.1f, RMS to the kept one %.2f / %.2f / %.2f m; ATE "
        "%.2f m, from scale 1 alone %.2f m\n",
        r.start_nll[0], r.start_nll[1], r.start_nll[2], r.start_rms_m[0], r.start_rms_m[1],
        r.start_rms_m[2], all.after->ate_m, from_one.after->ate_m);
    EXPECT_NE(r.start_chosen, 0u);
    EXPECT_GT(r.start_rms_m[0], 3.0) << "the start from 1 must keep another basin";
    EXPECT_LT(r.nll, r.start_nll[0] - 10.0);
    EXPECT_LT(all.after->ate_m, 0.5 * from_one.after->ate_m);
}

// A generated walk in the real HCU building (seed 5, one of the seeds the pedestrian defaults
// were chosen on) whose starts reach two basins of close NLL (measured 1.6 apart, 3.8 m RMS): the
// covariance of the result is the kept correction's plus, per pose, each other start's offset
// (squared) weighted by exp(-(its NLL - the kept one's)), over the weights' sum.
TEST(EndToEndIndoor, StartsOfCloseNllWidenTheCovariance) {
    const std::string walk = GeneratedHcuWalk(5);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    const pipeline::CorrectionRun all = pipeline::RunCorrection(walk, StepsAsRead());
    const CorrectionResult& r = all.result;
    ASSERT_EQ(r.covariance.status, CovarianceStatus::kOk);
    ASSERT_EQ(r.start_scales.size(), 3u);
    std::vector<pipeline::CorrectionRun> each;
    for (const double s : r.start_scales) {
        pipeline::PipelineConfig one = StepsAsRead();
        one.indoor_corrector.start_scales = {s};
        each.push_back(pipeline::RunCorrection(walk, one));
        ASSERT_EQ(each.back().result.covariance.status, CovarianceStatus::kOk);
    }
    const CorrectionResult& kept = each[r.start_chosen].result;
    ASSERT_EQ(kept.corrected.p_en, r.corrected.p_en);
    double total = 1.0, widest = 0.0;
    std::vector<Eigen::Matrix2d> added(r.corrected.size(), Eigen::Matrix2d::Zero());
    for (std::size_t k = 0; k < each.size(); ++k) {
        if (k == r.start_chosen) continue;
        const double w = std::exp(-(r.start_nll[k] - r.nll));
        total += w;
        for (std::size_t i = 0; i < added.size(); ++i) {
            const Eigen::Vector2d d = each[k].result.corrected.p_en[i] - r.corrected.p_en[i];
            added[i] += w * d * d.transpose();
        }
    }
    for (std::size_t i = 0; i < added.size(); ++i) {
        const Eigen::Matrix2d expected = kept.covariance.poses[i].xy_m2 + added[i] / total;
        EXPECT_LT((r.covariance.poses[i].xy_m2 - expected).norm(), 1e-9 * (1.0 + expected.norm()))
            << "pose " << i;
        widest = std::max(widest, (added[i] / total).trace());
    }
    std::printf("NLL of the starts %.1f / %.1f / %.1f; the widest pose gains %.2f m^2\n",
                r.start_nll[0], r.start_nll[1], r.start_nll[2], widest);
    EXPECT_GT(widest, 1.0) << "a start of close NLL must part from the kept one";
}

// The causal output of the online corrector fed the estimate pose by pose, the start scale of each
// output, the corrector's statistics and its Finish().
struct OnlineRun {
    PlanarTrajectory causal;
    std::vector<double> start_scale;
    OnlineStatistics stats;
    CorrectionResult smoothed;
};

OnlineRun RunOnlineOn(const pipeline::PreparedScenario& ps, const OnlineConfig& oc) {
    OnlineRun run;
    OnlineCorrector online(&ps.field, oc);
    const PlanarTrajectory& est = ps.estimate;
    for (std::size_t i = 0; i < est.size(); ++i) {
        PlanarPose pose{est.t_s[i], est.p_en[i], est.up_m[i], std::nullopt};
        if (est.HasYaw()) pose.yaw_rad = est.yaw_rad[i];
        const PushResult r = online.Push(pose);
        EXPECT_TRUE(r.Accepted()) << "pose " << i << ": " << r.message;
        run.causal.t_s.push_back(r.corrected.t_s);
        run.causal.p_en.push_back(r.corrected.p_en);
        run.causal.up_m.push_back(r.corrected.up_m);
        run.start_scale.push_back(r.start_scale);
    }
    run.stats = online.Statistics();
    run.smoothed = online.Finish();
    return run;
}

// The online corrector from the pedestrian start scales, one hypothesis each, on the walk above
// (seed 26). From scale 1 alone its causal output follows the squeezed path for a while
// (measured ATE 5.36 m); with the hypotheses the output moves to the
// start of lower NLL once the first chunk is solved (3.83 m) and ends on the start the batch
// keeps. Its Finish() is the batch correction,
// start scales included (from scale 1 alone it was 6.46 m). Threaded, the hypotheses run on their
// own workers and every one's solves are counted.
TEST(EndToEndIndoor, OnlineOutputFollowsTheStartScaleOfLowestNll) {
    const std::string walk = GeneratedHcuWalk(26);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    const pipeline::PipelineConfig config;
    const pipeline::PreparedScenario ps = pipeline::PrepareScenario(walk, config);
    ASSERT_TRUE(ps.ground_truth);
    OnlineConfig oc = config.online;
    oc.corrector = pipeline::CorrectorFor(ps.scenario, config);
    oc.synchronous = true;
    ASSERT_EQ(oc.corrector.start_scales.size(), 3u);
    OnlineConfig one = oc;
    one.corrector.start_scales = {1.0};
    one.first_solve_at_chunk = false;  // from the first pose, as the hypothesis from 1 solves
    const OnlineRun starts = RunOnlineOn(ps, oc);
    const OnlineRun from_one = RunOnlineOn(ps, one);
    const double ate_starts = ComputeMetrics(starts.causal, *ps.ground_truth).ate_m;
    const double ate_one = ComputeMetrics(from_one.causal, *ps.ground_truth).ate_m;
    std::printf("online causal ATE from scale 1: %.2f m, from the starts: %.2f m\n", ate_one,
                ate_starts);
    EXPECT_LT(ate_starts, ate_one);
    for (double s : from_one.start_scale) EXPECT_EQ(s, 1.0);
    const CorrectionResult batch = pipeline::Correct(ps, config);
    const CorrectionResult& smoothed = starts.smoothed;
    ASSERT_TRUE(Usable(batch.status) && Usable(smoothed.status)) << smoothed.message;
    EXPECT_EQ(smoothed.start_scales, batch.start_scales);
    // The same minimum; two starts may reach it (1.25 and 1.5 do here, NLL equal to 0.1), and
    // rounding picks one.
    EXPECT_NEAR(smoothed.nll, batch.nll, 1e-6 * std::abs(batch.nll));
    EXPECT_NE(smoothed.start_chosen, 0u);
    const double batch_ate = ComputeMetrics(batch.corrected, *ps.ground_truth).ate_m;
    const double smoothed_ate = ComputeMetrics(smoothed.corrected, *ps.ground_truth).ate_m;
    std::printf("batch ATE %.2f m, online Finish() %.2f m\n", batch_ate, smoothed_ate);
    EXPECT_LE(smoothed_ate, batch_ate + 0.1);
    // The causal output ends on a start whose batch correction reaches that minimum.
    const std::size_t last_start =
        std::find(batch.start_scales.begin(), batch.start_scales.end(), starts.start_scale.back()) -
        batch.start_scales.begin();
    ASSERT_LT(last_start, batch.start_nll.size());
    EXPECT_NEAR(batch.start_nll[last_start], batch.nll, 1e-3 * std::abs(batch.nll));
    EXPECT_EQ(starts.start_scale.front(), 1.0);  // no NLL to compare before the first chunk
    EXPECT_EQ(starts.stats.poses, ps.estimate.size());

    oc.synchronous = false;
    const OnlineRun threaded = RunOnlineOn(ps, oc);
    EXPECT_TRUE(threaded.stats.worker_error.empty()) << threaded.stats.worker_error;
    EXPECT_TRUE(Usable(threaded.smoothed.status));
    EXPECT_GT(threaded.stats.solves, from_one.stats.solves);  // three hypotheses' solves
}

// A generated walk in the real HCU building (seed 40, one of the seeds the pedestrian defaults
// were chosen on): a lift ride from the ground floor to the 4th, one down to the 1st, stairs down
// to the ground floor. Without the floor term (ModelConfig::floor_sigma_m) the walk after the
// first ride goes on, level, between floors, where only stair halls and lift shafts are
// traversable: measured 15.8 % of the poses on the right floor without it (52 % walk level up to
// 10.8 m from every floor), 100 % with it.
TEST(EndToEndIndoor, LevelWalkingIsDrawnToAFloor) {
    const std::string walk = GeneratedHcuWalk(40);
    if (walk.empty()) GTEST_SKIP() << "real data not present: hcu_eight";
    const pipeline::CorrectionRun a = pipeline::RunCorrection(walk, StepsAsRead());
    pipeline::PipelineConfig without = StepsAsRead();
    without.indoor_corrector.model.floor_sigma_m = 0.0;
    const pipeline::CorrectionRun b = pipeline::RunCorrection(walk, without);
    ASSERT_TRUE(a.after && b.after);
    std::printf("with the floor term: right floor %.1f %%; without: %.1f %%\n",
                100.0 * a.after->floor_accuracy, 100.0 * b.after->floor_accuracy);
    EXPECT_LT(b.after->floor_accuracy, 0.9) << "the walk must leave a floor without the term";
    EXPECT_GE(a.after->floor_accuracy, 0.99);
}

}  // namespace

namespace {

// The synthetic three-floor building (stairs and a lift, heading bias, step scale error, height
// drift) from the committed generator: the same correction whichever map format (PCD, PLY,
// OctoMap .bt or .ot) carries the walkable surfaces, ATE <= 0.5 m and every pose on the right
// floor.
TEST(EndToEndIndoor, SyntheticBuildingSameResultFromPcdPlyOctomap) {
    const std::string dir = TmpDir("building");
    const std::string cmd = std::string(DRIFTCORR_BINARY_DIR) +
                            "/datasets/driftcorr_make_building_scenario " + dir +
                            " > /dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::vector<double> ates;
    for (const char* yaml :
         {"scenario.yaml", "scenario_ply.yaml", "scenario_octomap.yaml", "scenario_ot.yaml"}) {
        const pipeline::CorrectionRun run =
            pipeline::RunCorrection(dir + "/" + yaml, pipeline::PipelineConfig{});
        ASSERT_TRUE(Usable(run.result.status)) << yaml << ": " << run.result.message;
        ASSERT_TRUE(run.before && run.after);
        EXPECT_GE(run.before->max_m, 5.0)
            << yaml << ": the walk must drift for the test to mean anything";
        EXPECT_LE(run.after->ate_m, 0.5) << yaml;
        EXPECT_EQ(run.after->floor_accuracy, 1.0) << yaml;
        ates.push_back(run.after->ate_m);
    }
    EXPECT_NEAR(ates[1], ates[0], 0.05);  // PLY holds the same points as PCD
    EXPECT_NEAR(ates[2], ates[0], 0.05);  // OctoMap quantises heights to 0.1 m voxels
    EXPECT_EQ(ates[3], ates[2]);          // .ot holds the same tree as .bt
}

// A scan does not show where a lift is: the surface map's layer declares the shaft (`lifts:`). In
// the synthetic building with a strong heading drift (seed 1, steps 0.8x, heading-rate bias
// 0.03 deg/s per sqrt(s)) the correction without the declaration puts the walker's lift ride 15 m
// from the shaft (measured), with it in the shaft.
TEST(EndToEndIndoor, ADeclaredLiftOfASurfaceMapHoldsTheRide) {
    const std::string dir = TmpDir("building_lift");
    const std::string cmd = std::string(DRIFTCORR_BINARY_DIR) +
                            "/datasets/driftcorr_make_building_scenario " + dir +
                            " --seed 1 --scale-error 0.8 --heading-bias-deg-per-sqrt-s 0.03 "
                            "--raw-spacing-m 0.5 > /dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const io::Scenario declared = io::LoadScenario(dir + "/scenario.yaml");
    ASSERT_EQ(declared.map.size(), 1u);
    ASSERT_EQ(declared.map[0].lifts.size(), 1u);
    const LiftShaft shaft = declared.map[0].lifts[0];
    io::Scenario undeclared = declared;
    undeclared.map[0].lifts.clear();
    // Farthest a pose of the ride (no horizontal motion in the estimate) lies from the shaft.
    auto ride_off_shaft_m = [&](const pipeline::CorrectionRun& run) {
        double worst = 0.0;
        std::size_t ride_poses = 0;
        for (std::size_t i = 1; i < run.estimate.size(); ++i) {
            if ((run.estimate.p_en[i] - run.estimate.p_en[i - 1]).norm() > 1e-6) continue;
            const Eigen::Vector2d p = run.result.corrected.p_en[i];
            const double dx = std::max({shaft.x0 - p.x(), 0.0, p.x() - shaft.x1});
            const double dy = std::max({shaft.y0 - p.y(), 0.0, p.y() - shaft.y1});
            worst = std::max(worst, std::hypot(dx, dy));
            ++ride_poses;
        }
        EXPECT_GE(ride_poses, 10u);
        return worst;
    };
    const pipeline::CorrectionRun with =
        pipeline::RunCorrection(declared, pipeline::PipelineConfig{});
    const pipeline::CorrectionRun without =
        pipeline::RunCorrection(undeclared, pipeline::PipelineConfig{});
    ASSERT_TRUE(Usable(with.result.status) && Usable(without.result.status));
    const double off_with = ride_off_shaft_m(with), off_without = ride_off_shaft_m(without);
    std::printf("ride off the shaft: %.2f m declared, %.2f m not; ATE %.2f / %.2f m\n", off_with,
                off_without, with.after->ate_m, without.after->ate_m);
    EXPECT_LE(off_with, 0.5);
    EXPECT_GE(off_without, 3.0)
        << "the walk must need the declaration for the test to mean anything";
}

}  // namespace
