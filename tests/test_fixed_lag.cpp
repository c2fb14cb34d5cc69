// Tests of the fixed-lag smoother (optim/src/fixed_lag.cpp): the marginalised boundary prior (the
// boundary pose and its scale) is the Schur complement of the window's Gauss-Newton information
// (against a dense inverse), grows along the odometry beyond the map, and the smoother's windows
// stay bounded and carry it.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "driftcorr/core/observables.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/fixed_lag.h"
#include "driftcorr/optim/incremental_corrector.h"
#include "test_state.h"

namespace driftcorr {
namespace {

/// A 40-pose curve of 2 m steps turning 0.03 rad a step, climbing 5 cm a step.
PlanarTrajectory Curve(int poses = 40) {
    PlanarTrajectory t;
    Eigen::Vector2d p(0.0, 0.0);
    double yaw = 0.2;
    for (int i = 0; i < poses; ++i) {
        if (i > 0) {
            p += 2.0 * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
            yaw += 0.03;
        }
        t.t_s.push_back(0.5 * i);
        t.p_en.push_back(p);
        t.up_m.push_back(0.05 * i);
        t.yaw_rad.push_back(yaw);
    }
    return t;
}

ModelConfig Model() {
    ModelConfig m;
    m.scale_segment_m = 20.0;
    return m;
}

PosePriorTerm SomePrior(const TrajectoryState& s, std::size_t pose, bool with_scale = false) {
    PosePriorTerm t;
    const PoseState& b = s.poses[pose];
    t.mean << b.p.x(), b.p.y(), b.p.z(), b.yaw_rad;
    t.information = Eigen::Vector4d(4.0, 2.0, 9.0, 400.0).asDiagonal();
    t.information(0, 1) = t.information(1, 0) = 0.5;
    if (s.fix_height) t.information.row(2).setZero(), t.information.col(2).setZero();
    if (with_scale) {
        t.scale_segment = s.scale_segment[pose];
        t.scale_mean = s.scales[t.scale_segment] + 0.01;
        t.cross << 0.3, -0.2, 0.0, 1.5;
        t.scale_information = 900.0;
    }
    return t;
}

// The dense reference: invert the Gauss-Newton information of window [first, last] (with the
// prior on first-1) over its poses and scales (the heading-rate biases given) and read the block
// of pose `last` and its segment's scale (x, y, yaw, scale; z too with free heights), and the same
// block of the Gauss-Newton step -H^-1 g.
struct DenseMarginal {
    Eigen::MatrixXd sigma;
    Eigen::VectorXd shift;
};
DenseMarginal DenseMarginalOf(TrajectoryState& s, const ModelConfig& model, std::size_t first,
                              std::size_t last, const PosePriorTerm& prior, bool with_scale) {
    const WindowProblem p(s, nullptr, model, first, last,
                          std::vector<std::uint8_t>(last - first + 1, 0), WindowUse::kLinearise,
                          prior);
    std::vector<double> x(p.NumVariables());
    p.InitialPoint(x.data());
    Eigen::MatrixXd h = DenseGaussNewtonHessian(p, x.data());
    std::vector<double> g(p.NumVariables());
    p.Gradient(x.data(), g.data());
    const int scale = p.ScaleVar(s.scale_segment[last]);
    const int end =
        with_scale ? scale + 1 : p.PoseVar(last, 3) + 1;  // the scales given: poses only
    std::vector<int> keep;
    for (int k = 0; k < end; ++k) {
        if (!(s.fix_height && k < p.PoseVar(last, 3) + 1 && k % 4 == 2)) keep.push_back(k);
    }
    Eigen::MatrixXd hk(keep.size(), keep.size());
    for (std::size_t r = 0; r < keep.size(); ++r) {
        for (std::size_t c = 0; c < keep.size(); ++c) hk(r, c) = h(keep[r], keep[c]);
    }
    const Eigen::MatrixXd sigma = hk.inverse();
    Eigen::VectorXd gk(keep.size());
    for (std::size_t r = 0; r < keep.size(); ++r) gk[r] = g[keep[r]];
    const Eigen::VectorXd step = -sigma * gk;
    std::vector<int> block;
    for (int c = 0; c < (with_scale ? 5 : 4); ++c) {
        if (s.fix_height && c == 2) continue;
        const int var = c < 4 ? p.PoseVar(last, c) : scale;
        for (std::size_t k = 0; k < keep.size(); ++k) {
            if (keep[k] == var) block.push_back(static_cast<int>(k));
        }
    }
    DenseMarginal out{Eigen::MatrixXd(block.size(), block.size()), Eigen::VectorXd(block.size())};
    for (std::size_t r = 0; r < block.size(); ++r) {
        for (std::size_t c = 0; c < block.size(); ++c) out.sigma(r, c) = sigma(block[r], block[c]);
        out.shift[r] = step[block[r]];
    }
    return out;
}

// The prior's information on its free entries (the height dropped when fixed; the scale when the
// prior has none).
Eigen::MatrixXd FreeInformation(const PosePriorTerm& t, bool fix_height) {
    const JointMatrix info = t.JointInformation();
    std::vector<int> idx;
    for (int k = 0; k < t.Size(); ++k) {
        if (!(fix_height && k == 2)) idx.push_back(k);
    }
    Eigen::MatrixXd out(idx.size(), idx.size());
    for (std::size_t r = 0; r < idx.size(); ++r) {
        for (std::size_t c = 0; c < idx.size(); ++c) out(r, c) = info(idx[r], idx[c]);
    }
    return out;
}

// The marginal of the boundary pose and its segment's scale: the Schur complement of the window's
// information onto them, from a prior on the pose alone or on the pose and its scale; without
// the scale (with_scale false), of the pose alone given the scales.
TEST(MarginalPrior, IsTheSchurComplementOfTheWindowInformation) {
    const ModelConfig model = Model();
    for (bool fix_height : {false, true}) {
        for (int variant = 0; variant < 3; ++variant) {
            const bool prior_scale = variant == 1, with_scale = variant < 2;
            SCOPED_TRACE(std::string(fix_height ? "planar" : "free height") +
                         (prior_scale ? ", prior with its scale" : ", prior on the pose") +
                         (with_scale ? "" : ", marginal of the pose alone"));
            TrajectoryState s = test::StateFrom(Curve(), model, fix_height);
            const PosePriorTerm prior = SomePrior(s, 4, prior_scale);
            // Off the estimate (and the prior's mean) the old terms have a gradient: the mean
            // moves.
            for (std::size_t i = 5; i <= 17; ++i) s.poses[i].p.x() += 0.02 * double(i - 4);
            const auto marginal = MarginalPrior(s, nullptr, model, 5, 17, prior, with_scale);
            ASSERT_TRUE(marginal.has_value());
            ASSERT_EQ(marginal->HasScale(), with_scale);
            if (with_scale) {
                EXPECT_EQ(marginal->scale_segment, s.scale_segment[17]);
            }
            const PoseState& b = s.poses[17];
            JointVector at;
            at << b.p.x(), b.p.y(), b.p.z(), b.yaw_rad,
                with_scale ? s.scales[s.scale_segment[17]] : 0.0;
            const JointVector shift = marginal->JointMean() - at;
            const DenseMarginal reference = DenseMarginalOf(s, model, 5, 17, prior, with_scale);
            for (int r = 0, k = 0; r < (with_scale ? 5 : 4); ++r) {
                if (fix_height && r == 2) {
                    EXPECT_EQ(shift[r], 0.0);
                    continue;
                }
                EXPECT_NEAR(shift[r], reference.shift[k++], 1e-8) << "component " << r;
            }
            EXPECT_GT(shift.head<2>().norm(), 1e-3);
            if (fix_height) {
                const JointMatrix info = marginal->JointInformation();
                EXPECT_EQ(info.row(2).norm() + info.col(2).norm(), 0.0);
            }
            const Eigen::MatrixXd sigma = FreeInformation(*marginal, fix_height).inverse();
            const Eigen::MatrixXd& dense = reference.sigma;
            EXPECT_LT((sigma - dense).cwiseAbs().maxCoeff(), 1e-8 * dense.cwiseAbs().maxCoeff())
                << "marginal\n"
                << sigma << "\ndense\n"
                << dense;
        }
    }
}

// Without a map the marginal is the dead-reckoning covariance: it grows with every step.
TEST(MarginalPrior, GrowsAlongTheOdometry) {
    const ModelConfig model = Model();
    TrajectoryState s = test::StateFrom(Curve(), model, true);
    const PosePriorTerm prior = SomePrior(s, 4);
    double previous = 0.0;
    for (std::size_t last : {6u, 12u, 24u, 36u}) {
        const auto m = MarginalPrior(s, nullptr, model, 5, last, prior);
        ASSERT_TRUE(m.has_value());
        // x, y of the marginal covariance (the scale integrated out).
        const Eigen::Matrix2d xy = FreeInformation(*m, true).inverse().topLeftCorner<2, 2>();
        EXPECT_GT(xy.trace(), previous) << "pose " << last;
        previous = xy.trace();
    }
}

// Windows of 20 m over Curve's 2 m steps, without a heading-rate bias: on the curve a bias trades
// a few mm of position against the heading-preservation prior, and the checks below are that the
// odometry alone is kept.
CorrectorConfig CurveWindows() {
    CorrectorConfig cfg;
    cfg.model = Model();
    cfg.model.heading_bias_segment_s = 0.0;
    cfg.window_m = 20.0;
    return cfg;
}

// The smoother's windows: bounded by window_m, the boundary carries the prior once the window has
// left pose 0 (or is held fixed without marginalisation), and each solve reaches its end.
TEST(FixedLagSmoother, WindowsAreBoundedAndCarryThePrior) {
    const CorrectorConfig cfg = CurveWindows();
    const PlanarTrajectory est = Curve(60);
    for (bool marginalise : {true, false}) {
        SCOPED_TRACE(marginalise ? "marginalised" : "fixed boundary");
        const TrajectoryState s = test::StateFrom(est, cfg.model, true);
        FixedLagSmoother smoother(s.poses[0], true, nullptr, cfg, marginalise);
        for (std::size_t i = 1; i < est.size(); ++i) smoother.Append(s.poses[i], s.obs[i]);
        std::size_t priors = 0;
        for (std::size_t end = 5; end < est.size(); end += 5) {
            const FixedLagSolution sol = smoother.Solve(end, false);
            EXPECT_TRUE(sol.usable);
            EXPECT_EQ(smoother.solved_end(), end);
            EXPECT_EQ(sol.poses.size(), sol.end - sol.first + 1);
            EXPECT_LE(sol.end - sol.first, 12u) << "20 m of 2 m steps, plus the boundary";
            EXPECT_TRUE(sol.end_covariance_ok);
            priors += sol.boundary_prior;
            // No map: the odometry alone, so the solution stays on the estimate.
            EXPECT_LT((sol.poses.back().p - s.poses[end].p).norm(), 1e-3) << "end " << end;
        }
        EXPECT_EQ(priors > 0, marginalise);
    }
}

// Adopt replaces the solved prefix by another solution of it (a re-localisation): the smoother
// scores the adopted poses and scales and hands them back as a solve's, and the next solve goes
// on from the adopted boundary.
TEST(FixedLagSmoother, AdoptedPrefixIsScoredAndSolvedOn) {
    const CorrectorConfig cfg = CurveWindows();
    const PlanarTrajectory est = Curve(60);
    TrajectoryState s = test::StateFrom(est, cfg.model, true);
    FixedLagSmoother smoother(s.poses[0], true, nullptr, cfg);
    for (std::size_t i = 1; i < est.size(); ++i) smoother.Append(s.poses[i], s.obs[i]);
    const std::size_t end = 30;
    ASSERT_TRUE(smoother.Solve(end, false).usable);
    // The prefix stretched by 5 % about pose 0, with the scale that explains it.
    const double stretch = 1.05;
    std::vector<PoseState> poses(s.poses.begin(), s.poses.begin() + end + 1);
    for (PoseState& p : poses)
        p.p.head<2>() = s.poses[0].p.head<2>() + stretch * (p.p - s.poses[0].p).head<2>();
    const std::vector<double> scales(end + 1, stretch);
    const FixedLagSolution adopted = smoother.Adopt(poses, scales, {});
    ASSERT_TRUE(adopted.usable);
    EXPECT_FALSE(adopted.poor);
    ASSERT_EQ(adopted.first, 1u);
    ASSERT_EQ(adopted.poses.size(), end);
    for (std::size_t i = 1; i <= end; ++i)
        EXPECT_LT((adopted.poses[i - 1].p - poses[i].p).norm(), 1e-12) << i;
    for (double v : adopted.scales) EXPECT_EQ(v, stretch);
    // Scored as the adopted state is.
    TrajectoryState expected = s;
    for (std::size_t i = 0; i <= end; ++i) expected.poses[i] = poses[i];
    for (int g = 0; g <= s.scale_segment[end]; ++g) expected.scales[g] = stretch;
    EXPECT_NEAR(smoother.Nll(end), SoftNll(expected, nullptr, cfg.model, end), 1e-9);
    // The next window's boundary prior has its mean at the prefix's Gauss-Newton minimum:
    // without a map, the odometry at the prior's scale 1, so the window returns from the
    // stretch (2.5 m at its boundary) to the estimate.
    const FixedLagSolution next = smoother.Solve(end + 5, false);
    ASSERT_TRUE(next.usable);
    EXPECT_TRUE(next.boundary_prior);
    EXPECT_GT((poses[next.first].p - s.poses[next.first].p).norm(), 2.0);
    for (std::size_t i = next.first; i <= next.end; ++i)
        EXPECT_LT((next.poses[i - next.first].p - s.poses[i].p).norm(), 1e-2) << i;
}

// Online, a step is read about the median of the steps so far (ModelConfig::step_length_exponent):
// with the odometry alone each solved step is median_so_far^(1 - e) * L^e long.
TEST(FixedLagSmoother, StepsAreReadAboutTheMedianOfTheStepsSoFar) {
    CorrectorConfig cfg;
    cfg.model = Model();
    cfg.model.heading_bias_segment_s = 0.0;
    cfg.model.step_length_exponent = 0.5;
    cfg.model.scale_prior_sigma = 1e-3;  // the scale stays 1
    cfg.window_m = 1e3;
    const double lengths[] = {0.0, 0.5, 0.9, 0.7, 0.6, 0.8, 0.55};
    const double prefix_median[] = {0.0, 0.5, 0.9, 0.7, 0.7, 0.7, 0.7};  // upper median
    PoseState pose;
    FixedLagSmoother smoother(pose, true, nullptr, cfg);
    const std::size_t n = std::size(lengths);
    for (std::size_t i = 1; i < n; ++i) {
        StepObservation o;
        o.dt_s = 0.5;
        o.length_m = lengths[i];
        pose.p.x() += lengths[i];
        smoother.Append(pose, o);
    }
    const FixedLagSolution sol = smoother.Solve(n - 1, false);
    ASSERT_TRUE(sol.usable);
    ASSERT_EQ(sol.first, 1u);  // pose 0 is the known start, at the origin
    auto at = [&](std::size_t i) {
        return i == 0 ? Eigen::Vector3d::Zero().eval() : sol.poses[i - sol.first].p;
    };
    for (std::size_t i = 1; i < n; ++i) {
        const double read = std::sqrt(prefix_median[i] * lengths[i]);
        EXPECT_NEAR((at(i) - at(i - 1)).norm(), read, 1e-4) << "step " << i;
    }
}

// A growing trajectory's dropped-step episode is repaired once the speed after it has been seen,
// and only then; an episode older than the span (20 s) is left to the batch repair.
TEST(RepairRecentEpisodes, RepairsAnEpisodeOnceItsEndIsSeen) {
    ModelConfig model;
    TrajectoryState s = StartState(PoseState{}, true, model);
    for (std::size_t i = 1; i <= 600; ++i) {  // 10 m/s at 10 Hz; steps 300-319 at a fifth
        StepObservation o;
        o.dt_s = 0.1;
        o.length_m = (i >= 300 && i < 320) ? 0.2 : 1.0;
        AppendStep(s, PoseState{}, o, double(i - 1), 0.1 * double(i - 1), model);
    }
    EXPECT_EQ(RepairRecentEpisodes(s, 315, model), 0u) << "the speed after it is not seen yet";
    EXPECT_FALSE(s.obs[305].repaired);
    EXPECT_EQ(RepairRecentEpisodes(s, 330, model), 1u);
    for (std::size_t i = 300; i < 320; ++i) {
        EXPECT_TRUE(s.obs[i].repaired) << i;
        EXPECT_NEAR(s.obs[i].length_m, 1.0, 1e-9) << i;
        EXPECT_DOUBLE_EQ(s.obs[i].observed_length_m, 0.2);
    }
    EXPECT_EQ(RepairRecentEpisodes(s, 340, model), 0u) << "repaired steps stay repaired";
    TrajectoryState late = StartState(PoseState{}, true, model);
    for (std::size_t i = 1; i <= 600; ++i) late.obs.push_back(s.obs[i]);
    for (std::size_t i = 300; i < 320; ++i) {
        late.obs[i].repaired = false;
        late.obs[i].length_m = 0.2;
    }
    EXPECT_EQ(RepairRecentEpisodes(late, 600, model), 0u) << "28 s later: outside the span";
}

}  // namespace
}  // namespace driftcorr
