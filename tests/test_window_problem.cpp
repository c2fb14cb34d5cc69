// Tests of the window NLP (optim/src/window_problem.cpp), its Ipopt adapter
// (optim/src/ipopt_solver.cpp) and the Newton solver of its soft terms
// (optim/src/newton_solver.cpp): every solver callback against central differences of the one it
// differentiates, the objective at the truth, a small constrained solve, and the Newton solver
// against Ipopt on the same windows.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <optional>
#include <ostream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"
#include "driftcorr/core/observables.h"
#include "driftcorr/mapping/road_network.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/incremental_corrector.h"
#include "driftcorr/optim/ipopt_solver.h"
#include "driftcorr/optim/newton_solver.h"
#include "driftcorr/optim/skyline_ldlt.h"
#include "driftcorr/optim/window_problem.h"
#include "test_state.h"

namespace driftcorr {
namespace {

constexpr int kPoses = 30;

/// A 30-pose curve: 2 m steps turning 0.04 rad per step, a stop (pose 15 repeats pose 14), and a
/// gentle climb. `heading_bias_rad` per step and `scale` turn it into a drifting estimate.
PlanarTrajectory Curve(double heading_bias_rad = 0.0, double scale = 1.0) {
    PlanarTrajectory t;
    Eigen::Vector2d p(10.0, -5.0);
    double yaw = 0.3;
    for (int i = 0; i < kPoses; ++i) {
        if (i > 0) {
            const double len = (i == 15 ? 0.0 : 2.0) * scale;
            p += len * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
            yaw += 0.04 + heading_bias_rad;
        }
        t.t_s.push_back(0.2 * i);
        t.p_en.push_back(p);
        t.up_m.push_back(1.0 + 0.05 * i);
        t.yaw_rad.push_back(yaw);
    }
    return t;
}

/// Roads: one along the true curve, one crossing it at pose 20.
RoadNetwork Roads(double half_width_m) {
    const PlanarTrajectory truth = Curve();
    RoadNetwork net;
    RoadPolyline along{1, "residential", half_width_m, {}};
    const Eigen::Vector2d d0(std::cos(truth.yaw_rad[0]), std::sin(truth.yaw_rad[0]));
    along.points_en.push_back(truth.p_en[0] - 10.0 * d0);
    for (int i = 0; i < kPoses; ++i) {
        if (i != 15) along.points_en.push_back(truth.p_en[i]);
    }
    const Eigen::Vector2d n(-std::sin(truth.yaw_rad[20]), std::cos(truth.yaw_rad[20]));
    RoadPolyline cross{
        2, "service", half_width_m, {truth.p_en[20] - 30.0 * n, truth.p_en[20] + 30.0 * n}};
    net.roads = {along, cross};
    return net;
}

TraversableField Field(double half_width_m) {
    const PlanarTrajectory truth = Curve();
    Eigen::AlignedBox2d box;
    for (const auto& p : truth.p_en) box.extend(p);
    RoadFieldConfig cfg;
    cfg.resolution_m = 0.5;
    cfg.margin_m = 30.0;
    cfg.truncation_m = 20.0;
    return RasteriseRoads(Roads(half_width_m), box, cfg);
}

using test::StateFrom;

ModelConfig Model() {
    ModelConfig m;
    m.scale_segment_m = 20.0;  // several scale segments in a 56 m window
    return m;
}

std::vector<std::uint8_t> EveryThird(std::size_t first, std::size_t last) {
    std::vector<std::uint8_t> c(last - first + 1, 0);
    for (std::size_t k = 0; k < c.size(); k += 3) c[k] = 1;
    return c;
}

/// The problem's initial point perturbed: positions by ~0.3 m, yaws by ~0.03 rad, scales ~0.02.
std::vector<double> Perturbed(const WindowProblem& p, std::mt19937& rng) {
    std::vector<double> x(p.NumVariables());
    p.InitialPoint(x.data());
    std::normal_distribution<double> n(0.0, 1.0);
    const int pose_vars = p.PoseVar(p.last(), 3) + 1;
    for (int k = 0; k < p.NumVariables(); ++k) {
        const double sd = k >= pose_vars ? 0.02 : (k % 4 == 3 ? 0.03 : 0.3);
        x[k] += sd * n(rng);
    }
    return x;
}

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;

/// Central-difference Jacobian of a vector function f: R^n -> R^m.
template <typename F>
Mat CentralJacobian(F f, std::vector<double> x, int m, double h) {
    const int n = static_cast<int>(x.size());
    Mat j(m, n);
    Vec fp(m), fm(m);
    for (int k = 0; k < n; ++k) {
        const double x0 = x[k];
        x[k] = x0 + h;
        f(x.data(), fp.data());
        x[k] = x0 - h;
        f(x.data(), fm.data());
        x[k] = x0;
        j.col(k) = (fp - fm) / (2.0 * h);
    }
    return j;
}

/// Dense symmetric matrix from lower-triangle triplets (duplicates accumulate).
Mat DenseSymmetric(int n, const std::vector<std::pair<int, int>>& s, const std::vector<double>& v) {
    Mat m = Mat::Zero(n, n);
    for (std::size_t k = 0; k < s.size(); ++k) {
        EXPECT_GE(s[k].first, s[k].second) << "Hessian entry " << k << " is not lower-triangular";
        m(s[k].first, s[k].second) += v[k];
        if (s[k].first != s[k].second) m(s[k].second, s[k].first) += v[k];
    }
    return m;
}

/// max |a - b| relative to the larger of the two matrices' max norm (plus an absolute floor).
double RelError(const Mat& a, const Mat& b) {
    return (a - b).cwiseAbs().maxCoeff() /
           (1.0 + std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()));
}

// Central differences with h = 1e-6 on an objective of order 1e3 (sigmas of 2 cm, 0.3 m
// perturbations): round-off ~ eps * f / h ~ 1e-7, truncation ~ h^2 f''' ~ 1e-9; derivatives
// of order 1e3. Tolerance: max error <= 1e-6 of the largest entry.
constexpr double kH = 1e-6;
constexpr double kTol = 1e-6;

struct WindowCase {
    std::size_t first, last;
    bool fix_height;
    unsigned seed;
    bool all_terms = false;       ///< also the robust step length and the speed-continuity terms
    bool boundary_prior = false;  ///< pose first-1 a variable under a PosePriorTerm
    bool prior_scale = false;     ///< the prior joint with the scale of pose first-1's segment
};

/// A prior on pose `pose` of `s`: its mean 0.4 m / 0.05 rad off the pose, a full information
/// matrix (a fixed height's row and column zero, as the fixed-lag window passes it); with_scale:
/// joint with the scale of the pose's segment, its mean 0.03 off.
PosePriorTerm PriorOn(const TrajectoryState& s, std::size_t pose, bool with_scale = false) {
    PosePriorTerm t;
    const PoseState& b = s.poses[pose];
    t.mean << b.p.x() + 0.4, b.p.y() - 0.3, b.p.z() + 0.1, b.yaw_rad + 0.05;
    Eigen::Matrix4d a;
    a << 3.0, 0.5, 0.0, 0.2,  //
        0.2, 2.0, 0.1, -0.4,  //
        0.0, 0.3, 1.0, 0.0,   //
        0.1, 0.0, 0.0, 5.0;
    t.information = a * a.transpose();
    if (s.fix_height) t.information.row(2).setZero(), t.information.col(2).setZero();
    if (with_scale) {
        t.scale_segment = s.scale_segment[pose];
        t.scale_mean = s.scales[t.scale_segment] + 0.03;
        t.cross << 0.4, -0.3, s.fix_height ? 0.0 : 0.2, 1.0;
        t.scale_information = 50.0;
    }
    return t;
}

// Readable (and stable) parameter names in ctest output.
void PrintTo(const WindowCase& c, std::ostream* os) {
    *os << "poses [" << c.first << ", " << c.last << "]"
        << (c.fix_height ? " planar" : " free height") << ", seed " << c.seed
        << (c.all_terms ? ", all terms" : "") << (c.boundary_prior ? ", boundary prior" : "")
        << (c.prior_scale ? " with its scale" : "");
}

class WindowDerivatives : public ::testing::TestWithParam<WindowCase> {
protected:
    void SetUp() override {
        model_ = Model();
        if (GetParam().all_terms) {
            model_.step_robust_k = 3.0;
            model_.accel_sigma_mps2 = 2.0;
            model_.heading_bias_segment_s = 1.0;                    // several bias segments in 6 s
            model_.scale_range_min = model_.scale_range_max = 1.0;  // every scale off the range
        } else {
            model_.heading_bias_segment_s = 0.0;  // the heading change without a bias
        }
        field_ = Field(3.5);
        state_ = StateFrom(Curve(), model_, GetParam().fix_height);
    }
    WindowProblem Problem() {
        const WindowCase c = GetParam();
        std::optional<PosePriorTerm> prior;
        if (c.boundary_prior) prior = PriorOn(state_, c.first - 1, c.prior_scale);
        return WindowProblem(state_, &field_, model_, c.first, c.last, EveryThird(c.first, c.last),
                             WindowUse::kSolve, prior);
    }
    std::size_t VarFirst() const { return GetParam().first - (GetParam().boundary_prior ? 1 : 0); }
    ModelConfig model_;
    TraversableField field_;
    TrajectoryState state_;
};

TEST_P(WindowDerivatives, CallbacksMatchCentralDifferences) {
    const WindowCase c = GetParam();
    WindowProblem p = Problem();
    const int n = p.NumVariables(), m = p.NumConstraints();
    const int biases = state_.bias_segment.empty()
                           ? 0
                           : state_.bias_segment[c.last] - state_.bias_segment[c.first] + 1;
    ASSERT_EQ(n, 4 * int(c.last - VarFirst() + 1) +
                     (state_.scale_segment[c.last] - state_.scale_segment[c.first] + 1) + biases);
    ASSERT_EQ(m, int((c.last - c.first) / 3 + 1));
    ASSERT_EQ(p.JacobianStructure().size(), std::size_t(3 * m));

    std::mt19937 rng(c.seed);
    for (int trial = 0; trial < 3; ++trial) {
        const std::vector<double> x = Perturbed(p, rng);
        SCOPED_TRACE("trial " + std::to_string(trial));

        // Gradient vs central differences of Objective.
        Vec grad(n);
        p.Gradient(x.data(), grad.data());
        const Mat num_grad = CentralJacobian(
            [&](const double* xx, double* out) { out[0] = p.Objective(xx); }, x, 1, kH);
        EXPECT_LT(RelError(grad.transpose(), num_grad), kTol) << "gradient";

        // Objective Hessian (obj_factor = 1, lambda = 0) vs central differences of Gradient.
        std::vector<double> hv(p.HessianStructure().size());
        const std::vector<double> zero(m, 0.0);
        p.HessianValues(x.data(), 1.0, zero.data(), hv.data());
        const Mat h = DenseSymmetric(n, p.HessianStructure(), hv);
        const Mat num_h =
            CentralJacobian([&](const double* xx, double* out) { p.Gradient(xx, out); }, x, n, kH);
        EXPECT_LT(RelError(h, 0.5 * (num_h + num_h.transpose())), kTol) << "objective Hessian";
        EXPECT_LT(RelError(num_h, num_h.transpose()), kTol) << "gradient is not a gradient";

        // Jacobian vs central differences of Constraints.
        std::vector<double> jv(p.JacobianStructure().size());
        p.JacobianValues(x.data(), jv.data());
        Mat jac = Mat::Zero(m, n);
        for (std::size_t k = 0; k < jv.size(); ++k) {
            jac(p.JacobianStructure()[k].first, p.JacobianStructure()[k].second) += jv[k];
        }
        const Mat num_jac = CentralJacobian(
            [&](const double* xx, double* out) { p.Constraints(xx, out); }, x, m, kH);
        EXPECT_LT(RelError(jac, num_jac), kTol) << "constraint Jacobian";

        // Hessian of constraint k (obj_factor = 0, lambda = e_k) vs central differences of its
        // Jacobian row.
        for (int k = 0; k < m; ++k) {
            std::vector<double> lambda(m, 0.0);
            lambda[k] = 1.0;
            p.HessianValues(x.data(), 0.0, lambda.data(), hv.data());
            const Mat hk = DenseSymmetric(n, p.HessianStructure(), hv);
            const Mat num_hk = CentralJacobian(
                [&](const double* xx, double* out) {
                    std::vector<double> v(jv.size());
                    p.JacobianValues(xx, v.data());
                    for (int col = 0; col < n; ++col) out[col] = 0.0;
                    for (std::size_t e = 0; e < v.size(); ++e) {
                        if (p.JacobianStructure()[e].first == k)
                            out[p.JacobianStructure()[e].second] += v[e];
                    }
                },
                x, n, kH);
            EXPECT_LT(RelError(hk, 0.5 * (num_hk + num_hk.transpose())), kTol)
                << "Hessian of constraint " << k;
        }
    }
}

TEST_P(WindowDerivatives, BoundsFixHeightsAndScales) {
    const WindowCase c = GetParam();
    WindowProblem p = Problem();
    const int n = p.NumVariables(), m = p.NumConstraints();
    std::vector<double> xl(n), xu(n), gl(m), gu(m), x0(n);
    p.Bounds(xl.data(), xu.data(), gl.data(), gu.data());
    p.InitialPoint(x0.data());
    for (std::size_t i = VarFirst(); i <= c.last; ++i) {
        const int z = 4 * int(i - VarFirst()) + 2;
        EXPECT_EQ(x0[z], state_.poses[i].p.z());
        if (c.fix_height) {
            EXPECT_EQ(xl[z], x0[z]);
            EXPECT_EQ(xu[z], x0[z]);
        } else {
            EXPECT_LT(xl[z], -1e10);
            EXPECT_GT(xu[z], 1e10);
        }
    }
    for (int k = 0; k < m; ++k) {
        EXPECT_LT(gl[k], -1e10);
        EXPECT_EQ(gu[k], model_.corridor_slack_m);
    }
    for (int k = 4 * int(c.last - VarFirst() + 1); k < n; ++k) {
        EXPECT_LE(xl[k], x0[k]);
        EXPECT_GE(xu[k], x0[k]);
        EXPECT_LT(xl[k], 1.0);
        EXPECT_GT(xu[k], 1.0);
    }
}

// Each term block on its own (optim/term_block.h): its gradient and Hessian over its free local
// variables against central differences of its own cost through the window's variables (the map
// term reads the field at the window's positions), and its linearisation's Jacobian against the
// gradient where the term is Gaussian (grad = information * r * J).
TEST_P(WindowDerivatives, EveryTermBlockMatchesCentralDifferences) {
    const WindowCase c = GetParam();
    WindowProblem p = Problem();
    std::mt19937 rng(c.seed + 1000u);
    std::vector<double> x = Perturbed(p, rng);
    std::array<int, kTermFamilies> seen{};
    for (const auto& block : p.Blocks()) {
        ++seen[static_cast<int>(block->family())];
        const auto cost = [&](const std::vector<double>& xx) {
            return block->Evaluate(p.Context(xx.data()), block->Gather(xx.data()), nullptr,
                                   nullptr);
        };
        BlockVector g;
        BlockMatrix h;
        block->Evaluate(p.Context(x.data()), block->Gather(x.data()), &g, &h);
        for (int a = 0; a < block->size(); ++a) {
            const int va = block->var(a);
            if (va < 0) continue;
            const double xa = x[va];
            x[va] = xa + kH;
            const double fp = cost(x);
            BlockVector gp;
            block->Evaluate(p.Context(x.data()), block->Gather(x.data()), &gp, nullptr);
            x[va] = xa - kH;
            const double fm = cost(x);
            BlockVector gm;
            block->Evaluate(p.Context(x.data()), block->Gather(x.data()), &gm, nullptr);
            x[va] = xa;
            const double scale = 1.0 + g.cwiseAbs().maxCoeff() + h.cwiseAbs().maxCoeff();
            EXPECT_NEAR(g[a], (fp - fm) / (2.0 * kH), 1e-5 * scale)
                << ToString(block->family()) << " gradient, local variable " << a;
            for (int b = 0; b < block->size(); ++b) {
                if (block->var(b) < 0) continue;
                EXPECT_NEAR(h(b, a), (gp[b] - gm[b]) / (2.0 * kH), 1e-5 * scale)
                    << ToString(block->family()) << " Hessian (" << b << ", " << a << ")";
            }
        }
    }
    for (TermFamily f :
         {TermFamily::kStepLength, TermFamily::kStepDirection, TermFamily::kHeadingChange,
          TermFamily::kHeadingPreservation, TermFamily::kMapDistance, TermFamily::kScaleWalk}) {
        EXPECT_GT(seen[static_cast<int>(f)], 0) << ToString(f) << ": no block in the window";
    }
    EXPECT_EQ(seen[static_cast<int>(TermFamily::kHeightChange)] > 0, !c.fix_height);
    EXPECT_EQ(seen[static_cast<int>(TermFamily::kSpeedChange)] > 0, c.all_terms);
    EXPECT_EQ(seen[static_cast<int>(TermFamily::kHeadingBiasWalk)] > 0, c.all_terms);
    EXPECT_GT(seen[static_cast<int>(TermFamily::kScaleRange)], 0);
    EXPECT_EQ(seen[static_cast<int>(TermFamily::kBoundaryPrior)] > 0, c.boundary_prior);
}

// A block's gradient and Hessian are exact zeros outside the variables it says it reads, so the
// one-pass sums (each block adding only those) are bit for bit the sums over every entry.
TEST_P(WindowDerivatives, OnePassSumsEqualTheSumsOverEveryEntry) {
    const WindowCase c = GetParam();
    WindowProblem p = Problem();
    std::mt19937 rng(c.seed + 2000u);
    const std::vector<double> x = Perturbed(p, rng);
    const int n = p.NumVariables();
    std::map<std::pair<int, int>, std::size_t> slot;
    for (std::size_t e = 0; e < p.HessianStructure().size(); ++e) slot[p.HessianStructure()[e]] = e;
    double f_every = 0.0;
    std::vector<double> g_every(n, 0.0), h_every(p.HessianStructure().size(), 0.0);
    std::size_t unread = 0;
    for (const auto& block : p.Blocks()) {
        BlockVector g;
        BlockMatrix h;
        f_every += block->Evaluate(p.Context(x.data()), block->Gather(x.data()), &g, &h);
        for (int r = 0; r < block->size(); ++r) {
            const bool read = (block->reads() >> r) & 1u;
            unread += !read;
            if (!read) {
                EXPECT_EQ(g[r], 0.0) << ToString(block->family()) << " gradient " << r;
                for (int k = 0; k < block->size(); ++k) {
                    EXPECT_EQ(h(r, k), 0.0) << ToString(block->family()) << " Hessian " << r;
                }
            }
            const int vr = block->var(r);
            if (vr < 0) continue;
            g_every[vr] += g[r];
            for (int k = 0; k <= r; ++k) {
                const int vk = block->var(k);
                if (vk >= 0) h_every[slot.at({std::max(vr, vk), std::min(vr, vk)})] += h(r, k);
            }
        }
    }
    EXPECT_GT(unread, 0u);  // the step blocks read fewer than their nine variables
    std::vector<double> g(n), h(p.HessianStructure().size());
    const double f = p.ObjectiveGradientHessian(x.data(), g.data(), h.data());
    EXPECT_EQ(std::memcmp(&f, &f_every, sizeof f), 0) << f << " against " << f_every;
    EXPECT_EQ(std::memcmp(g.data(), g_every.data(), g.size() * sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(h.data(), h_every.data(), h.size() * sizeof(double)), 0);
    std::vector<double> g_alone(n), h_alone(h.size());
    p.Gradient(x.data(), g_alone.data());
    p.HessianValues(x.data(), 1.0, std::vector<double>(p.NumConstraints(), 0.0).data(),
                    h_alone.data());
    EXPECT_EQ(std::memcmp(g.data(), g_alone.data(), g.size() * sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(h.data(), h_alone.data(), h.size() * sizeof(double)), 0);
    const double f_alone = p.Objective(x.data());
    EXPECT_EQ(std::memcmp(&f, &f_alone, sizeof f), 0);
}

// The Newton solver and Ipopt on the same soft window of a drifting estimate (heading bias
// 4 mrad per step, steps 3 % too long) reach the same minimum; held heights stay put.
TEST_P(WindowDerivatives, NewtonReachesIpoptsMinimum) {
    const WindowCase c = GetParam();
    const TrajectoryState start = StateFrom(Curve(0.004, 1.03), model_, c.fix_height);
    std::optional<PosePriorTerm> prior;
    if (c.boundary_prior) prior = PriorOn(start, c.first - 1);
    const std::vector<std::uint8_t> soft(c.last - c.first + 1, 0);
    TrajectoryState by_newton = start, by_ipopt = start;
    WindowProblem pn(by_newton, &field_, model_, c.first, c.last, soft, WindowUse::kSolve, prior);
    WindowProblem pi(by_ipopt, &field_, model_, c.first, c.last, soft, WindowUse::kSolve, prior);
    std::vector<double> x0(pn.NumVariables());
    pn.InitialPoint(x0.data());
    const double f0 = pn.Objective(x0.data());
    std::vector<double> g0(pn.NumVariables());
    pn.Gradient(x0.data(), g0.data());
    double g0_max = 0.0;
    for (double g : g0) g0_max = std::max(g0_max, std::abs(g));
    // Each solver reports every iteration it counts (the final solve's progress lines).
    int newton_calls = 0, ipopt_calls = 0, newton_last = 0, ipopt_last = 0;
    NewtonOptions newton;
    newton.on_iteration = [&](int k) { ++newton_calls, newton_last = k; };
    const SolveReport rn = SolveWithNewton(pn, newton);
    IpoptOptions opt;
    opt.max_iterations = 200;
    opt.on_iteration = [&](int k) { ++ipopt_calls, ipopt_last = k; };
    const SolveReport ri = SolveWithIpopt(pi, opt);
    ASSERT_TRUE(Usable(rn.status)) << rn.message;
    ASSERT_TRUE(Usable(ri.status)) << ri.message;
    EXPECT_EQ(newton_calls, rn.iterations);
    EXPECT_EQ(newton_last, rn.iterations);
    EXPECT_EQ(ipopt_calls, ri.iterations);
    EXPECT_EQ(ipopt_last, ri.iterations);
    ASSERT_GT(g0_max, 0.01) << "the window must start away from its minimum";
    EXPECT_LT(rn.objective, f0);
    EXPECT_NEAR(rn.objective, ri.objective, 1e-6 * (1.0 + std::abs(ri.objective)));
    EXPECT_LE(rn.iterations, 20);
    for (std::size_t i = 0; i < start.poses.size(); ++i) {
        EXPECT_LT((by_newton.poses[i].p - by_ipopt.poses[i].p).norm(), 1e-3) << "pose " << i;
        EXPECT_NEAR(by_newton.poses[i].yaw_rad, by_ipopt.poses[i].yaw_rad, 1e-4) << "pose " << i;
        if (c.fix_height) {
            EXPECT_EQ(by_newton.poses[i].p.z(), start.poses[i].p.z()) << "pose " << i;
        }
    }
    for (std::size_t g = 0; g < start.scales.size(); ++g) {
        EXPECT_NEAR(by_newton.scales[g], by_ipopt.scales[g], 1e-4) << "scale " << g;
    }
    for (std::size_t g = 0; g < start.biases.size(); ++g) {
        EXPECT_NEAR(by_newton.biases[g], by_ipopt.biases[g], 1e-5) << "bias " << g;
    }
}

INSTANTIATE_TEST_SUITE_P(
    Windows, WindowDerivatives,
    ::testing::Values(WindowCase{1, 29, true, 101u}, WindowCase{1, 29, false, 102u},
                      WindowCase{12, 25, true, 103u}, WindowCase{12, 25, false, 104u},
                      WindowCase{14, 17, true, 105u},  // a short window around the stop
                      WindowCase{1, 29, true, 106u, true}, WindowCase{12, 25, false, 107u, true},
                      WindowCase{2, 5, true, 108u, true},
                      WindowCase{12, 25, true, 109u, false, true},
                      WindowCase{12, 25, false, 110u, true, true},
                      WindowCase{1, 29, true, 111u, false, true},  // the prior on pose 0
                      WindowCase{12, 25, false, 112u, false, true, true},
                      WindowCase{12, 25, true, 113u, true, true, true}),
    [](const ::testing::TestParamInfo<WindowCase>& param_info) {
        const WindowCase& c = param_info.param;
        return "poses_" + std::to_string(c.first) + "_" + std::to_string(c.last) +
               (c.fix_height ? "_planar" : "_free_height") + (c.all_terms ? "_all_terms" : "") +
               (c.boundary_prior ? "_boundary_prior" : "") + (c.prior_scale ? "_with_scale" : "");
    });

// ---- Lift rides ---------------------------------------------------------------------------------

// A 2 m x 2 m shaft centred at c.
ShaftOutline Square(const Eigen::Vector2d& c) {
    return {c + Eigen::Vector2d(-1, -1), c + Eigen::Vector2d(1, -1), c + Eigen::Vector2d(1, 1),
            c + Eigen::Vector2d(-1, 1)};
}

TEST(LiftShafts, DistanceIsZeroInsideToTheEdgeBesideAndToTheCornerBeyond) {
    const std::vector<ShaftOutline> shafts = {Square({0, 0}), Square({10, 0})};
    EXPECT_EQ(DistanceToShafts(shafts, {0.5, -0.5, 3.0}).value, 0.0);
    EXPECT_EQ(DistanceToShafts(shafts, {10.2, 0.9, 3.0}).gradient.norm(), 0.0);
    const FieldSample edge = DistanceToShafts(shafts, {3.0, 0.5, 3.0});  // beside the first's edge
    EXPECT_NEAR(edge.value, 2.0, 1e-12);
    EXPECT_NEAR((edge.gradient - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-12);
    EXPECT_NEAR(edge.hessian.norm(), 0.0, 1e-12);
    const FieldSample corner = DistanceToShafts(shafts, {7.0, 5.0, 3.0});  // beyond the second's
    EXPECT_NEAR(corner.value, std::hypot(2.0, 4.0), 1e-12);
    EXPECT_NEAR((corner.gradient - Eigen::Vector3d(-2, 4, 0).normalized()).norm(), 0.0, 1e-12);
    EXPECT_NEAR((corner.hessian * corner.gradient).norm(), 0.0, 1e-12);
    EXPECT_NEAR(corner.hessian.row(2).norm() + corner.hessian.col(2).norm(), 0.0, 1e-12);
}

// The curve with a 20 s stop at pose 15 during which the height rises by 4 m: a lift ride over
// poses 14-15. A shaft 3 m beside pose 14: the ride's two poses, and only they, get a lift term,
// whose derivatives match central differences outside the shaft (beside an edge and beyond a
// corner) and are zero inside it; no lift term without shafts, with lift_sigma_m 0, or planar.
TEST(WindowProblem, ALiftRideDrawsItsPosesToTheNearestShaft) {
    PlanarTrajectory walk = Curve();
    for (int i = 15; i < kPoses; ++i) walk.t_s[i] += 20.0, walk.up_m[i] += 4.0;
    ModelConfig model = Model();
    model.lift_sigma_m = 1.0;
    model.lift_giveup_m = 10.0;
    TrajectoryState state = StateFrom(walk, model, false);
    TraversableField field = Field(3.5);
    const Eigen::Vector2d beside = walk.p_en[14] + Eigen::Vector2d(3.0, 0.0);
    field.set_lift_shafts({Square(beside)});
    const std::vector<std::uint8_t> free(kPoses - 1, 0);
    auto lift_blocks = [&](TrajectoryState s, const TraversableField& f, const ModelConfig& m) {
        WindowProblem p(s, &f, m, 1, kPoses - 1, free);
        std::vector<int> poses;
        for (const TermBlock* block : p.Blocks()) {
            if (block->family() == TermFamily::kLiftDistance) poses.push_back(block->pose());
        }
        return poses;
    };
    EXPECT_EQ(lift_blocks(state, field, model), (std::vector<int>{14, 15}));
    EXPECT_TRUE(lift_blocks(state, Field(3.5), model).empty());
    ModelConfig off = model;
    off.lift_sigma_m = 0.0;
    EXPECT_TRUE(lift_blocks(state, field, off).empty());
    EXPECT_TRUE(lift_blocks(StateFrom(walk, model, true), field, model).empty());

    WindowProblem p(state, &field, model, 1, kPoses - 1, free);
    const TermBlock* lift = nullptr;
    for (const TermBlock* block : p.Blocks()) {
        if (block->family() == TermFamily::kLiftDistance) lift = block;
    }
    ASSERT_NE(lift, nullptr);
    std::vector<double> x(p.NumVariables());
    p.InitialPoint(x.data());
    const int vx = lift->var(0), vy = lift->var(1);
    for (const Eigen::Vector2d& at : {Eigen::Vector2d(beside + Eigen::Vector2d(-4.0, 0.3)),
                                      Eigen::Vector2d(beside + Eigen::Vector2d(2.5, 3.0)),
                                      Eigen::Vector2d(beside + Eigen::Vector2d(0.2, -0.4))}) {
        x[vx] = at.x(), x[vy] = at.y();
        BlockVector g;
        BlockMatrix h;
        const double cost = lift->Evaluate(p.Context(x.data()), lift->Gather(x.data()), &g, &h);
        const bool inside = (at - beside).cwiseAbs().maxCoeff() < 1.0;
        EXPECT_EQ(cost == 0.0, inside) << at.transpose();
        for (int a : {0, 1}) {
            const int va = lift->var(a);
            const double xa = x[va];
            BlockVector gp, gm;
            x[va] = xa + kH;
            const double fp =
                lift->Evaluate(p.Context(x.data()), lift->Gather(x.data()), &gp, nullptr);
            x[va] = xa - kH;
            const double fm =
                lift->Evaluate(p.Context(x.data()), lift->Gather(x.data()), &gm, nullptr);
            x[va] = xa;
            EXPECT_NEAR(g[a], (fp - fm) / (2.0 * kH), 1e-6) << at.transpose() << " gradient " << a;
            for (int b : {0, 1}) {
                EXPECT_NEAR(h(b, a), (gp[b] - gm[b]) / (2.0 * kH), 1e-5)
                    << at.transpose() << " Hessian (" << b << ", " << a << ")";
            }
        }
        EXPECT_EQ(g[2], 0.0);
    }
}

TEST(WindowProblem, WindowAfterTheStartUsesFixedEarlierPosesAndScales) {
    const ModelConfig model = Model();
    TrajectoryState s = StateFrom(Curve(), model, true);
    ASSERT_GT(s.scale_segment[12], 0) << "the window should start in a later scale segment";
    // Move pose 11 (fixed, before the window): the first step's cost must change; moving pose 5
    // (not touched by any step of the window) must not. Fixed values are read when a problem is
    // built.
    const std::vector<std::uint8_t> free(14, 0);
    WindowProblem p(s, nullptr, model, 12, 25, free);
    std::vector<double> x(p.NumVariables());
    p.InitialPoint(x.data());
    const double f0 = p.Objective(x.data());
    auto objective = [&] {
        return WindowProblem(s, nullptr, model, 12, 25, free).Objective(x.data());
    };
    s.poses[5].p.x() += 1.0;
    EXPECT_EQ(objective(), f0);
    s.poses[11].p.x() += 0.1;
    EXPECT_GT(objective(), f0 + 1.0);
    EXPECT_EQ(p.Objective(x.data()), f0) << "a built problem keeps the values it was built with";
    s.poses[11].p.x() -= 0.1;
    // The random walk ties the first free scale to the fixed previous segment's scale.
    s.scales[s.scale_segment[12] - 1] = 1.05;
    EXPECT_GT(objective(), f0 + 1.0);
    EXPECT_EQ(p.NumConstraints(), 0);
}

// The soft NLL of a drive evaluated in consecutive windows (to bound memory) is the same sum as
// in one problem: every step's and pose's terms once, and the walk and range terms of a scale or
// heading-rate bias segment that straddles two windows once, whatever the window length.
TEST(WindowProblem, SoftNllInWindowsIsTheWholeDrivesSum) {
    ModelConfig model = Model();
    model.heading_bias_segment_s = 1.0;  // bias segments of 5 steps, straddling windows too
    TrajectoryState s = StateFrom(Curve(0.01, 1.03), model, false);
    ASSERT_GT(s.scales.size(), 2u);
    ASSERT_GT(s.biases.size(), 4u);
    std::mt19937 rng(7);
    std::normal_distribution<double> n(0.0, 1.0);
    for (double& scale : s.scales) scale += 0.05 * n(rng);
    for (double& bias : s.biases) bias += 0.01 * n(rng);
    for (std::size_t i = 1; i < s.poses.size(); ++i) {
        s.poses[i].p += Eigen::Vector3d(0.5 * n(rng), 0.5 * n(rng), 0.2 * n(rng));
        s.poses[i].yaw_rad += 0.05 * n(rng);
    }
    const TraversableField field = Field(3.5);
    const std::size_t last = s.poses.size() - 1;
    const double whole = SoftNll(s, &field, model, last);
    ASSERT_GT(whole, 10.0);
    for (std::size_t block : {1, 2, 4, 5, 7, 13, 28}) {
        EXPECT_NEAR(SoftNll(s, &field, model, last, block), whole, 1e-12 * whole)
            << block << " poses a window";
    }
    // Leaving out a straddling segment's walk term, or counting it twice, would be seen: each
    // scale and bias walk term weighs more than that tolerance.
    const WindowProblem p(s, &field, model, 1, last, std::vector<std::uint8_t>(last, 0),
                          WindowUse::kLinearise);
    std::vector<double> x(p.NumVariables());
    p.InitialPoint(x.data());
    int walks = 0;
    for (const TermBlock* term : p.Blocks()) {
        if (term->family() != TermFamily::kScaleWalk &&
            term->family() != TermFamily::kHeadingBiasWalk) {
            continue;
        }
        ++walks;
        EXPECT_GT(term->Evaluate(p.Context(x.data()), term->Gather(x.data()), nullptr, nullptr),
                  1e-9 * whole);
    }
    EXPECT_EQ(walks, int(s.scales.size() + s.biases.size()));
}

TEST(WindowProblem, BoundaryPriorMakesPoseFirstMinusOneAVariable) {
    const ModelConfig model = Model();
    TrajectoryState s = StateFrom(Curve(), model, true);
    const PosePriorTerm prior = PriorOn(s, 11);
    WindowProblem fixed(s, nullptr, model, 12, 25, std::vector<std::uint8_t>(14, 0));
    WindowProblem p(s, nullptr, model, 12, 25, std::vector<std::uint8_t>(14, 0), WindowUse::kSolve,
                    prior);
    EXPECT_EQ(p.NumVariables(), fixed.NumVariables() + 4);
    EXPECT_EQ(p.PoseVar(11, 0), 0);
    EXPECT_EQ(p.PoseVar(10, 3), -1);
    EXPECT_EQ(p.PoseVar(12, 0), 4);
    std::vector<double> x(p.NumVariables()), xf(fixed.NumVariables());
    p.InitialPoint(x.data());
    fixed.InitialPoint(xf.data());
    // At the state the objective is the fixed window's plus the prior's cost at pose 11.
    const PoseState& b = s.poses[11];
    JointVector at = JointVector::Zero();
    at << b.p.x(), b.p.y(), b.p.z(), b.yaw_rad, 0.0;
    const double prior_cost = prior.Evaluate(at, nullptr, nullptr);
    EXPECT_GT(prior_cost, 0.5);
    EXPECT_NEAR(p.Objective(x.data()), fixed.Objective(xf.data()) + prior_cost, 1e-9);
    // The Gauss-Newton Hessian carries the prior's information on pose 11's block (the step
    // terms of step 12 add to it; without the prior that block comes from them alone).
    WindowProblem zero(s, nullptr, model, 12, 25, std::vector<std::uint8_t>(14, 0),
                       WindowUse::kSolve, PosePriorTerm{prior.mean, PoseMatrix::Zero()});
    const Eigen::MatrixXd with = DenseGaussNewtonHessian(p, x.data());
    const Eigen::MatrixXd without = DenseGaussNewtonHessian(zero, x.data());
    EXPECT_LT(((with - without).topLeftCorner(4, 4) - prior.information).cwiseAbs().maxCoeff(),
              1e-9);
    EXPECT_LT(
        (with - without).bottomRightCorner(with.rows() - 4, with.cols() - 4).cwiseAbs().maxCoeff(),
        1e-12);
    // Store moves pose 11 as well.
    x[0] += 0.7;
    p.Store(x.data());
    EXPECT_EQ(s.poses[11].p.x(), x[0]);
}

// A prior joint with the boundary's scale summarises that segment's walk and range terms: its
// scale becomes a variable of the window, and the segment before it no longer matters.
TEST(WindowProblem, BoundaryPriorWithItsScaleReplacesThatSegmentsWalk) {
    const ModelConfig model = Model();
    for (std::size_t first : {std::size_t(12), std::size_t(13)}) {
        TrajectoryState s = StateFrom(Curve(), model, true);
        const PosePriorTerm joint = PriorOn(s, first - 1, true), pose_only = PriorOn(s, first - 1);
        const int g = joint.scale_segment;
        ASSERT_GT(g, 0);
        const std::vector<std::uint8_t> none(26 - first, 0);
        // Fixed values are read when a problem is built: one problem per state.
        auto objective = [&](const TrajectoryState& state, const PosePriorTerm& prior) {
            TrajectoryState copy = state;
            const WindowProblem p(copy, nullptr, model, first, 25, none, WindowUse::kSolve, prior);
            std::vector<double> x(p.NumVariables());
            p.InitialPoint(x.data());
            return p.Objective(x.data());
        };
        {
            const WindowProblem p(s, nullptr, model, first, 25, none, WindowUse::kSolve, joint);
            const WindowProblem q(s, nullptr, model, first, 25, none, WindowUse::kSolve, pose_only);
            EXPECT_GE(p.ScaleVar(g), 0);
            EXPECT_EQ(p.ScaleVar(g - 1), -1);
            EXPECT_EQ(p.NumVariables(), q.NumVariables() + (s.scale_segment[first] > g ? 1 : 0));
        }
        TrajectoryState before = s;  // the segment before the prior's: no walk term reads it
        before.scales[g - 1] = 1.3;
        EXPECT_EQ(objective(before, joint), objective(s, joint));
        if (s.scale_segment[first] == g) {  // with a prior on the pose alone the walk reads it
            EXPECT_GT(objective(before, pose_only), objective(s, pose_only) + 1.0);
        }
        TrajectoryState moved = s;  // the prior (and the steps) read the segment's own scale
        moved.scales[g] += 0.2;
        EXPECT_GT(objective(moved, joint), objective(s, joint) + 0.5);
    }
}

TEST(WindowProblem, ObjectiveAtTheTruthIsOnlyThePreservationPrior) {
    // At the estimate itself every observation residual is zero; the only cost left is the
    // heading-preservation prior on the observed turns, 0.5 * w * (dheading / sigma)^2 per step.
    const ModelConfig model = Model();
    for (bool fix_height : {true, false}) {
        TrajectoryState s = StateFrom(Curve(), model, fix_height);
        for (std::size_t first : {std::size_t(1), std::size_t(12)}) {
            WindowProblem p(s, nullptr, model, first, 29, std::vector<std::uint8_t>(30 - first, 1));
            EXPECT_EQ(p.NumConstraints(), 0) << "no field, no constraints";
            std::vector<double> x(p.NumVariables());
            p.InitialPoint(x.data());
            double expected = 0.0;
            for (std::size_t i = first; i <= 29; ++i) {
                const double r = s.obs[i].dheading_rad / model.preservation_sigma_rad;
                expected += 0.5 * model.preservation_weight * r * r;
            }
            EXPECT_NEAR(p.Objective(x.data()), expected, 1e-9 * (1.0 + expected));
        }
    }
    // With the prior switched practically off the objective and its gradient vanish.
    ModelConfig weak = model;
    weak.preservation_sigma_rad = 1e8;
    TrajectoryState s = StateFrom(Curve(), weak, false);
    WindowProblem p(s, nullptr, weak, 1, 29, std::vector<std::uint8_t>(29, 0));
    std::vector<double> x(p.NumVariables()), g(p.NumVariables());
    p.InitialPoint(x.data());
    EXPECT_LT(p.Objective(x.data()), 1e-12);
    p.Gradient(x.data(), g.data());
    for (int k = 0; k < p.NumVariables(); ++k) EXPECT_LT(std::abs(g[k]), 1e-6) << "variable " << k;
}

// The first scale segment's prior is about ModelConfig::scale_prior_mean: at the same point, a
// window whose prior is about the first scale's value costs 0.5 ((s - 1) / sigma)^2 less than one
// about 1, every other term being the same.
TEST(WindowProblem, TheFirstScalesPriorIsAboutItsMean) {
    ModelConfig about_one = Model();
    about_one.scale_range_sigma = 0.0;
    ModelConfig about_s = about_one;
    about_s.scale_prior_mean = 1.3;
    TrajectoryState s = StateFrom(Curve(), about_one, true);
    std::fill(s.scales.begin(), s.scales.end(), 1.3);
    WindowProblem a(s, nullptr, about_one, 1, 29, std::vector<std::uint8_t>(29, 0));
    WindowProblem b(s, nullptr, about_s, 1, 29, std::vector<std::uint8_t>(29, 0));
    ASSERT_EQ(a.NumVariables(), b.NumVariables());
    std::vector<double> x(a.NumVariables());
    a.InitialPoint(x.data());
    const double r = 0.3 / about_one.scale_prior_sigma;
    EXPECT_NEAR(a.Objective(x.data()) - b.Objective(x.data()), 0.5 * r * r, 1e-9);
    // A window after the first segment ties its scales to the fixed ones before it: no prior.
    WindowProblem c(s, nullptr, about_one, 20, 29, std::vector<std::uint8_t>(10, 0));
    WindowProblem d(s, nullptr, about_s, 20, 29, std::vector<std::uint8_t>(10, 0));
    std::vector<double> y(c.NumVariables());
    c.InitialPoint(y.data());
    EXPECT_EQ(c.Objective(y.data()), d.Objective(y.data()));
}

// A stair tread's run is its own (MarkStairTreads): its length term does not read the scale.
// Steps 5-10 observed as treads of their own length cost nothing at the estimate, as before; at a
// scale of 1.2 the six steps' length terms, 0.5 (0.2 L / sigma)^2 each as scaled steps, are gone,
// every other term the same.
TEST(WindowProblem, AStairTreadsRunIsNotScaled) {
    const ModelConfig model = Model();
    TrajectoryState scaled = StateFrom(Curve(), model, false);
    TrajectoryState treads = scaled;
    double removed = 0.0;
    for (std::size_t i = 5; i <= 10; ++i) {
        const StepObservation& o = scaled.obs[i];
        treads.obs[i].tread = true;
        treads.obs[i].observed_length_m = o.length_m;
        const double sigma = StepNoiseOf(model, o).length_m, r = 0.2 * o.length_m / sigma;
        removed += 0.5 * model.step_weight * r * r;
    }
    WindowProblem a(scaled, nullptr, model, 1, 29, std::vector<std::uint8_t>(29, 0));
    WindowProblem b(treads, nullptr, model, 1, 29, std::vector<std::uint8_t>(29, 0));
    ASSERT_EQ(a.NumVariables(), b.NumVariables());
    std::vector<double> x(a.NumVariables());
    a.InitialPoint(x.data());
    EXPECT_NEAR(a.Objective(x.data()), b.Objective(x.data()), 1e-12);
    x[a.ScaleVar(scaled.scale_segment[5])] = 1.2;
    ASSERT_EQ(scaled.scale_segment[5], scaled.scale_segment[10]);
    EXPECT_GT(removed, 1.0);
    EXPECT_NEAR(a.Objective(x.data()) - b.Objective(x.data()), removed, 1e-9 * removed);
}

TEST(WindowProblem, StoreWritesTheSolutionBack) {
    const ModelConfig model = Model();
    TrajectoryState s = StateFrom(Curve(), model, true);
    WindowProblem p(s, nullptr, model, 3, 7, std::vector<std::uint8_t>(5, 0));
    std::vector<double> x(p.NumVariables());
    p.InitialPoint(x.data());
    x[0] += 1.5;          // pose 3 x
    x[4 * 4 + 3] -= 0.2;  // pose 7 yaw
    ASSERT_FALSE(s.bias_segment.empty());
    x[p.ScaleVar(s.scale_segment[7])] = 1.07;  // last scale of the window
    x[p.BiasVar(s.bias_segment[7])] = 0.01;    // its heading-rate bias
    p.Store(x.data());
    EXPECT_EQ(s.poses[3].p.x(), x[0]);
    EXPECT_EQ(s.poses[7].yaw_rad, x[19]);
    EXPECT_EQ(s.scales[s.scale_segment[7]], 1.07);
    EXPECT_EQ(s.biases[s.bias_segment[7]], 0.01);
}

TEST(BiasSegments, OnePerSegmentOfTimeAndNoneWhenOff) {
    std::vector<StepObservation> obs(8);
    for (std::size_t i = 1; i < obs.size(); ++i) obs[i].dt_s = 0.4;
    // Time before step i: 0, 0.4, 0.8, ...; segments of 1 s.
    const std::vector<int> expected = {0, 0, 0, 0, 1, 1, 2, 2};
    EXPECT_EQ(BiasSegments(obs, 1.0), expected);
    EXPECT_TRUE(BiasSegments(obs, 0.0).empty());
}

TEST(ScaleSegments, OnePerSegmentOfPathLength) {
    std::vector<StepObservation> obs(8);
    for (std::size_t i = 1; i < obs.size(); ++i) obs[i].length_m = 4.0;
    // Distance before step i: 0, 4, 8, ...; segments of 10 m.
    const std::vector<int> seg = ScaleSegments(obs, 10.0);
    const std::vector<int> expected = {0, 0, 0, 0, 1, 1, 2, 2};
    EXPECT_EQ(seg, expected);
}

// ---- Ipopt ---------------------------------------------------------------------------------

TEST(IpoptSolver, ConstrainedWindowEndsInsideTheCorridor) {
    // A drifting estimate (heading bias 4 mrad per step, 2% too long) against narrow roads
    // (half-width 1.5 m) around the true curve: poses within the gate carry the hard corridor.
    const ModelConfig model = Model();
    const TraversableField field = Field(1.5);
    const PlanarTrajectory truth = Curve(), est = Curve(0.004, 1.02);
    TrajectoryState s = StateFrom(est, model, true);
    const std::size_t first = 1, last = kPoses - 1;
    std::vector<std::uint8_t> constrained(last - first + 1, 0);
    double worst_start = -1e9;
    for (std::size_t i = first; i <= last; ++i) {
        const auto q = field.Query(s.poses[i].p);
        ASSERT_TRUE(q.has_value());
        if (q->corridor.value <= model.corridor_gate_m) {
            constrained[i - first] = 1;
            worst_start = std::max(worst_start, q->corridor.value);
        }
    }
    ASSERT_GT(worst_start, 0.5) << "the test needs constrained poses that start off the road";

    WindowProblem p(s, &field, model, first, last, constrained);
    IpoptOptions opt;
    opt.max_iterations = 200;
    const SolveReport r = SolveWithIpopt(p, opt);
    ASSERT_TRUE(Usable(r.status)) << ToString(r.status) << ": " << r.message;
    EXPECT_LE(r.max_violation_m, opt.constraint_tolerance + 1e-9);
    for (std::size_t i = first; i <= last; ++i) {
        if (!constrained[i - first]) continue;
        const auto q = field.Query(s.poses[i].p);  // the solution was stored into the state
        ASSERT_TRUE(q.has_value());
        EXPECT_LE(q->corridor.value, model.corridor_slack_m + 1e-3) << "pose " << i;
    }
    // The correction helps: the final error against the truth shrinks (it started at ~3.6 m).
    const double before = (est.p_en.back() - truth.p_en.back()).norm();
    const double after = (s.poses.back().p.head<2>() - truth.p_en.back()).norm();
    EXPECT_LT(after, 0.5 * before) << "before " << before << " m, after " << after << " m";
}

// ---- Newton ---------------------------------------------------------------------------------

// Odometry 4.5x too long, the poses starting on the true curve: the map asks for scales of
// 1/4.5, below kScaleMin. Newton keeps them at the bound (the projected method), where Ipopt
// ends too, with the same objective.
// A random symmetric positive definite matrix whose upper triangle lies in a random envelope
// (a band with a few columns that reach far back, like a window's scale variables).
struct EnvelopeCase {
    std::vector<int> first;
    Eigen::MatrixXd a;
};

EnvelopeCase RandomEnvelope(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    EnvelopeCase c;
    c.first.resize(n);
    for (int j = 0; j < n; ++j) {
        const int reach = (rng() % 7 == 0) ? int(rng() % (j + 1)) : int(rng() % 6);
        c.first[j] = std::max(0, j - reach);
    }
    c.a = Eigen::MatrixXd::Zero(n, n);
    for (int j = 0; j < n; ++j) {
        for (int i = c.first[j]; i < j; ++i) {
            // Some entries of the envelope stay zero, as in a Hessian's pattern.
            if (rng() % 3 == 0) continue;
            c.a(i, j) = c.a(j, i) = u(rng);
        }
    }
    // Diagonally dominant: positive definite.
    for (int j = 0; j < n; ++j) c.a(j, j) = c.a.row(j).cwiseAbs().sum() + 0.5 + 0.5 * u(rng);
    return c;
}

TEST(SkylineLdlt, SolvesAsADenseFactorisation) {
    for (unsigned seed = 1; seed <= 20; ++seed) {
        const int n = 5 + int(seed) * 7;
        const EnvelopeCase c = RandomEnvelope(n, seed);
        SkylineLdlt ldlt(c.first);
        for (int j = 0; j < n; ++j)
            for (int i = c.first[j]; i <= j; ++i) ldlt.values()[ldlt.Index(i, j)] = c.a(i, j);
        ASSERT_TRUE(ldlt.Factorize()) << "seed " << seed;
        const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
        std::vector<double> x(b.data(), b.data() + n);
        ldlt.Solve(x);
        const Eigen::VectorXd ref = c.a.ldlt().solve(b);
        for (int k = 0; k < n; ++k)
            ASSERT_NEAR(x[k], ref[k], 1e-10) << "seed " << seed << ", " << k;
        // Factorize leaves the matrix as it was: again, the same answer.
        ASSERT_TRUE(ldlt.Factorize());
        std::vector<double> again(b.data(), b.data() + n);
        ldlt.Solve(again);
        EXPECT_EQ(again, x);
    }
}

TEST(SkylineLdlt, SaysWhenTheMatrixIsNotPositiveDefinite) {
    const EnvelopeCase c = RandomEnvelope(40, 7);
    for (int bad : {0, 17, 39}) {
        SkylineLdlt ldlt(c.first);
        for (int j = 0; j < 40; ++j)
            for (int i = c.first[j]; i <= j; ++i) ldlt.values()[ldlt.Index(i, j)] = c.a(i, j);
        ldlt.values()[ldlt.Index(bad, bad)] = -1.0;  // an indefinite matrix
        EXPECT_FALSE(ldlt.Factorize()) << "negative diagonal at " << bad;
        ldlt.values()[ldlt.Index(bad, bad)] = std::nan("");
        EXPECT_FALSE(ldlt.Factorize()) << "NaN at " << bad;
    }
}

TEST(NewtonSolver, KeepsScalesAtTheirBoundLikeIpopt) {
    ModelConfig model = Model();
    model.scale_range_sigma = 0.0;  // no prior pulling the scales back into the plausible range
    const TraversableField field = Field(3.5);
    TrajectoryState start = StateFrom(Curve(0.0, 4.5), model, true);
    start.poses = StateFrom(Curve(), model, true).poses;
    TrajectoryState by_newton = start, by_ipopt = start;
    const std::vector<std::uint8_t> soft(kPoses - 1, 0);
    WindowProblem pn(by_newton, &field, model, 1, kPoses - 1, soft);
    WindowProblem pi(by_ipopt, &field, model, 1, kPoses - 1, soft);
    const SolveReport rn = SolveWithNewton(pn, NewtonOptions{});
    const SolveReport ri = SolveWithIpopt(pi, IpoptOptions{});
    ASSERT_TRUE(Usable(rn.status)) << rn.message;
    ASSERT_TRUE(Usable(ri.status)) << ri.message;
    const double lowest = *std::min_element(by_newton.scales.begin(), by_newton.scales.end());
    EXPECT_EQ(lowest, kScaleMin) << "the case must press a scale against its bound";
    for (std::size_t g = 0; g < start.scales.size(); ++g) {
        EXPECT_GE(by_newton.scales[g], kScaleMin);
        EXPECT_LE(by_newton.scales[g], kScaleMax);
        EXPECT_NEAR(by_newton.scales[g], by_ipopt.scales[g], 1e-4) << "scale " << g;
    }
    EXPECT_NEAR(rn.objective, ri.objective, 1e-5 * (1.0 + std::abs(ri.objective)));
}

// The final solve with refine_newton against Ipopt alone, on a drifting estimate (heading bias
// 4 mrad per step, steps 2 % too long): on wide roads (3.5 m) no corridor constraint is active
// at the soft minimum, which is then the answer (Ipopt's within its tolerance); on narrow ones
// (1 m) some are, and Ipopt solves the constrained program from the same start as without the
// Newton step (the same answer exactly).
TEST(NewtonSolver, FinalSolveIsIpoptsWithOrWithoutActiveConstraints) {
    for (const double half_width_m : {3.5, 1.0}) {
        SCOPED_TRACE("half width " + std::to_string(half_width_m));
        const TraversableField field = Field(half_width_m);
        const PlanarTrajectory est = Curve(0.004, 1.02);
        CorrectorConfig cfg;
        cfg.model = Model();
        cfg.chunk_m = 20.0;
        cfg.window_m = 40.0;
        cfg.compute_covariance = false;
        std::vector<CorrectionResult> results;
        for (const bool newton : {true, false}) {
            cfg.refine_newton = newton;
            IncrementalCorrector c(InitialState(est, cfg, true), &field, cfg);
            c.SolveRemaining();
            results.push_back(c.Finish(est.t_s));
            ASSERT_TRUE(Usable(results.back().status)) << results.back().message;
            EXPECT_GT(results.back().constrained_poses, 0u);
        }
        const bool inactive =
            results[0].message.find("no corridor constraint active") != std::string::npos;
        EXPECT_EQ(inactive, half_width_m > 2.0) << results[0].message;
        EXPECT_LE(results[0].refine_report.max_violation_m, cfg.refine_ipopt.constraint_tolerance);
        for (std::size_t i = 0; i < est.size(); ++i) {
            const double d = (results[0].corrected.p_en[i] - results[1].corrected.p_en[i]).norm();
            EXPECT_LT(d, inactive ? 1e-3 : 1e-9) << "pose " << i;
        }
    }
}

// Headings 10,000 turns up (an unwrapped heading after a long drive) leave the window's minimum
// where it is, but their rounding keeps the gradient above the tolerance while the decrease
// the last steps promise is below the objective's rounding. The solver takes those steps as
// Ipopt does (within ten rounding units of the objective), stops once two in a row no longer
// lower it, and calls the result acceptable: at the minimum of the same window 10,000 turns
// down, and in far fewer iterations than an exact Armijo test takes to give up (22 to 37).
TEST(NewtonSolver, StopsWhereTheObjectivesRoundingHidesTheRestOfTheGradient) {
    const ModelConfig model = Model();
    const TraversableField field = Field(3.5);
    const std::vector<std::uint8_t> soft(kPoses - 1, 0);
    const double turns = 2.0 * kPi * 10000.0;
    for (const auto& [bias, scale] :
         {std::pair{0.004, 1.03}, {0.004, 1.1}, {0.01, 1.03}, {0.01, 1.1}}) {
        TrajectoryState near = StateFrom(Curve(bias, scale), model, true), far = near;
        for (PoseState& pose : far.poses) pose.yaw_rad += turns;
        WindowProblem pn(near, &field, model, 1, kPoses - 1, soft);
        WindowProblem pf(far, &field, model, 1, kPoses - 1, soft);
        const SolveReport rn = SolveWithNewton(pn, NewtonOptions{});
        const SolveReport rf = SolveWithNewton(pf, NewtonOptions{});
        ASSERT_EQ(rn.status, SolveStatus::kSuccess) << rn.message;
        ASSERT_TRUE(Usable(rf.status)) << rf.message;  // acceptable here; lucky rounding: success
        EXPECT_LE(rf.iterations, 16) << bias << " " << scale;
        EXPECT_NEAR(rf.objective, rn.objective, 1e-9 * rn.objective);
        double dp = 0.0, dyaw = 0.0;
        for (std::size_t i = 0; i < near.poses.size(); ++i) {
            dp = std::max(dp, (far.poses[i].p - near.poses[i].p).norm());
            dyaw = std::max(dyaw, std::abs(far.poses[i].yaw_rad - turns - near.poses[i].yaw_rad));
        }
        EXPECT_LT(dp, 1e-8);
        EXPECT_LT(dyaw, 1e-9);
        for (std::size_t g = 0; g < near.scales.size(); ++g)
            EXPECT_NEAR(far.scales[g], near.scales[g], 1e-6) << "scale " << g;
    }
}

TEST(NewtonSolver, RefusesAConstrainedProblem) {
    const ModelConfig model = Model();
    const TraversableField field = Field(3.5);
    TrajectoryState s = StateFrom(Curve(), model, true);
    WindowProblem p(s, &field, model, 1, kPoses - 1, EveryThird(1, kPoses - 1));
    EXPECT_THROW(SolveWithNewton(p, NewtonOptions{}), InvariantError);
}

}  // namespace
}  // namespace driftcorr
