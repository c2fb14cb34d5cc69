// Tests of the NLL cost terms (core/src/cost_terms.cpp): every term costs zero with zero gradient
// at a step block built consistently with its observation ("value at truth"), and its analytic
// gradient and Hessian equal central differences at random points (fixed seeds).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <ostream>
#include <random>
#include <string>

#include "driftcorr/core/cost_terms.h"

namespace driftcorr {
namespace {

// Central differences: h = 1e-6 on variables of order 1..10 keeps both the truncation error
// (h^2 * f''' ~ 1e-10) and the round-off error (eps * f / h ~ 1e-8 for costs below 100) far
// below the tolerance |analytic - numeric| <= kAbsTol + kRelTol * max(|analytic|, |numeric|).
constexpr double kStep = 1e-6;
constexpr double kAbsTol = 1e-6;
constexpr double kRelTol = 1e-5;

bool Close(double analytic, double numeric) {
    return std::abs(analytic - numeric) <=
           kAbsTol + kRelTol * std::max(std::abs(analytic), std::abs(numeric));
}

using StepFn = std::function<double(const StepVector&, StepVector*, StepMatrix*)>;

/// The observation parameters shared by all step terms; a truth block satisfies all of them.
struct StepParams {
    double length_m = 2.5, direction_rad = 0.3, dheading_rad = -0.2, dup_m = 0.4;
    double sigma = 0.3, weight = 0.8, scale = 1.1;
};

enum class TermKind { kLength, kDirection, kHeadingChange, kPreservation, kHeight };

std::string Name(TermKind k) {
    switch (k) {
        case TermKind::kLength:
            return "StepLength";
        case TermKind::kDirection:
            return "StepDirection";
        case TermKind::kHeadingChange:
            return "HeadingChange";
        case TermKind::kPreservation:
            return "HeadingPreservation";
        default:
            return "HeightChange";
    }
}

void PrintTo(TermKind k, std::ostream* os) { *os << Name(k); }

StepFn MakeTerm(TermKind kind, const StepParams& p) {
    switch (kind) {
        case TermKind::kLength: {
            const StepLengthTerm t{p.length_m, p.direction_rad, p.sigma, p.weight};
            return [t](const StepVector& x, StepVector* g, StepMatrix* h) {
                return t.Evaluate(x, g, h);
            };
        }
        case TermKind::kDirection: {
            const StepDirectionTerm t{p.direction_rad, p.sigma, p.weight};
            return [t](const StepVector& x, StepVector* g, StepMatrix* h) {
                return t.Evaluate(x, g, h);
            };
        }
        case TermKind::kHeadingChange: {
            const HeadingChangeTerm t{p.dheading_rad, p.sigma, p.weight};
            return [t](const StepVector& x, StepVector* g, StepMatrix* h) {
                return t.Evaluate(x, g, h);
            };
        }
        case TermKind::kPreservation: {
            const HeadingPreservationTerm t{p.sigma, p.weight};
            return [t](const StepVector& x, StepVector* g, StepMatrix* h) {
                return t.Evaluate(x, g, h);
            };
        }
        default: {
            const HeightChangeTerm t{p.dup_m, p.sigma, p.weight};
            return [t](const StepVector& x, StepVector* g, StepMatrix* h) {
                return t.Evaluate(x, g, h);
            };
        }
    }
}

using LinFn = std::function<Linearisation<9>(const StepVector&)>;

/// The same term's Linearise.
LinFn MakeLinearisation(TermKind kind, const StepParams& p) {
    switch (kind) {
        case TermKind::kLength: {
            const StepLengthTerm t{p.length_m, p.direction_rad, p.sigma, p.weight};
            return [t](const StepVector& x) { return t.Linearise(x); };
        }
        case TermKind::kDirection: {
            const StepDirectionTerm t{p.direction_rad, p.sigma, p.weight};
            return [t](const StepVector& x) { return t.Linearise(x); };
        }
        case TermKind::kHeadingChange: {
            const HeadingChangeTerm t{p.dheading_rad, p.sigma, p.weight};
            return [t](const StepVector& x) { return t.Linearise(x); };
        }
        case TermKind::kPreservation: {
            const HeadingPreservationTerm t{p.sigma, p.weight};
            return [t](const StepVector& x) { return t.Linearise(x); };
        }
        default: {
            const HeightChangeTerm t{p.dup_m, p.sigma, p.weight};
            return [t](const StepVector& x) { return t.Linearise(x); };
        }
    }
}

/// Pose a at (3, -2, 1) with yaw 0.4; pose b displaced by s * L along yaw_a + direction, raised
/// by dup and turned by dheading: the block every step observation agrees with.
StepVector TruthBlock(const StepParams& p) {
    StepVector x;
    const double yaw_a = 0.4, phi = yaw_a + p.direction_rad, len = p.scale * p.length_m;
    x << 3.0, -2.0, 1.0, yaw_a, 3.0 + len * std::cos(phi), -2.0 + len * std::sin(phi),
        1.0 + p.dup_m, yaw_a + p.dheading_rad, p.scale;
    return x;
}

StepParams RandomParams(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.0, 1.0);
    StepParams p;
    p.length_m = 5.0 * pos(rng);
    p.direction_rad = 3.0 * u(rng);
    p.dheading_rad = 1.5 * u(rng);
    p.dup_m = 2.0 * u(rng);
    p.sigma = 0.3 + 1.7 * pos(rng);
    p.weight = 0.1 + 0.9 * pos(rng);
    return p;
}

StepVector RandomBlock(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    StepVector x;
    for (int k = 0; k < kStepVars; ++k) x[k] = 5.0 * u(rng);
    x[kYawA] = 3.5 * u(rng);
    x[kYawB] = 3.5 * u(rng);
    x[kScale] = 1.0 + 0.3 * u(rng);
    return x;
}

/// Expects the analytic gradient and Hessian of `f` at x to equal central differences (of the
/// cost, and of the analytic gradient respectively).
void ExpectDerivativesMatch(const StepFn& f, const StepVector& x, const std::string& where) {
    StepVector g;
    StepMatrix h;
    f(x, &g, &h);
    for (int k = 0; k < kStepVars; ++k) {
        StepVector xp = x, xm = x;
        xp[k] += kStep;
        xm[k] -= kStep;
        const double num_g = (f(xp, nullptr, nullptr) - f(xm, nullptr, nullptr)) / (2.0 * kStep);
        EXPECT_PRED2(Close, g[k], num_g) << where << " d/dx[" << k << "]";
        StepVector gp, gm;
        f(xp, &gp, nullptr);
        f(xm, &gm, nullptr);
        const StepVector num_h = (gp - gm) / (2.0 * kStep);
        for (int r = 0; r < kStepVars; ++r) {
            EXPECT_PRED2(Close, h(r, k), num_h[r]) << where << " d2/dx[" << r << "]dx[" << k << "]";
        }
    }
    EXPECT_TRUE(h.isApprox(h.transpose(), 1e-12)) << where << " Hessian not symmetric";
}

class StepTermTest : public ::testing::TestWithParam<TermKind> {};

TEST_P(StepTermTest, ZeroCostAndGradientAtTruth) {
    StepParams p;
    if (GetParam() == TermKind::kPreservation) p.dheading_rad = 0.0;  // its truth: no turn
    const StepFn f = MakeTerm(GetParam(), p);
    StepVector g;
    StepMatrix h;
    EXPECT_NEAR(f(TruthBlock(p), &g, &h), 0.0, 1e-20);
    EXPECT_LT(g.cwiseAbs().maxCoeff(), 1e-12) << g.transpose();
    // The Gauss-Newton part remains: positive semi-definite at truth.
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<StepMatrix>(h).eigenvalues().minCoeff(), -1e-12);
}

TEST_P(StepTermTest, DerivativesMatchCentralDifferencesAtRandomPoints) {
    std::mt19937 rng(1234u + static_cast<unsigned>(GetParam()));
    for (int trial = 0; trial < 50; ++trial) {
        const StepParams p = RandomParams(rng);
        const StepVector x = RandomBlock(rng);
        ExpectDerivativesMatch(MakeTerm(GetParam(), p), x, "trial " + std::to_string(trial));
    }
}

TEST_P(StepTermTest, DerivativesMatchNearTruth) {
    std::mt19937 rng(99u + static_cast<unsigned>(GetParam()));
    std::normal_distribution<double> n(0.0, 0.05);
    StepParams p;
    const StepFn f = MakeTerm(GetParam(), p);
    for (int trial = 0; trial < 20; ++trial) {
        StepVector x = TruthBlock(p);
        for (int k = 0; k < kStepVars; ++k) x[k] += n(rng);
        ExpectDerivativesMatch(f, x, "trial " + std::to_string(trial));
    }
}

TEST_P(StepTermTest, StationaryStepIsFiniteEverywhere) {
    // L = 0, direction 0 (what ComputeObservations reports for a stop); poses coincide or not.
    StepParams p;
    p.length_m = 0.0;
    p.direction_rad = 0.0;
    const StepFn f = MakeTerm(GetParam(), p);
    std::mt19937 rng(7u + static_cast<unsigned>(GetParam()));
    for (int trial = 0; trial < 20; ++trial) {
        StepVector x = RandomBlock(rng);
        if (trial % 2 == 0) x.segment<3>(kXb) = x.segment<3>(kXa);  // exactly stationary
        StepVector g;
        StepMatrix h;
        const double c = f(x, &g, &h);
        EXPECT_TRUE(std::isfinite(c));
        EXPECT_TRUE(g.allFinite());
        EXPECT_TRUE(h.allFinite());
        ExpectDerivativesMatch(f, x, "stationary trial " + std::to_string(trial));
    }
    if (GetParam() == TermKind::kLength || GetParam() == TermKind::kDirection) {
        StepVector x = TruthBlock(p);  // pose b == pose a
        StepVector g;
        EXPECT_NEAR(f(x, &g, nullptr), 0.0, 1e-20);
        EXPECT_LT(g.cwiseAbs().maxCoeff(), 1e-12);
    }
}

// Linearise: its Jacobian is the residual's (central differences of the residual it reports);
// the Gaussian term's gradient is information * r * J and its cost 0.5 * information * r^2 =
// 0.5 * chi2; at the truth information * J J^T is the exact Hessian.
TEST_P(StepTermTest, LinearisationMatchesTheTerm) {
    std::mt19937 rng(4321u + static_cast<unsigned>(GetParam()));
    for (int trial = 0; trial < 30; ++trial) {
        const StepParams p = RandomParams(rng);
        const StepVector x = RandomBlock(rng);
        const StepFn f = MakeTerm(GetParam(), p);
        const LinFn lin = MakeLinearisation(GetParam(), p);
        const Linearisation<9> l = lin(x);
        for (int k = 0; k < kStepVars; ++k) {
            StepVector xp = x, xm = x;
            xp[k] += kStep;
            xm[k] -= kStep;
            const double num = (lin(xp).residual - lin(xm).residual) / (2.0 * kStep);
            EXPECT_PRED2(Close, l.jacobian[k], num) << "trial " << trial << " dr/dx[" << k << "]";
        }
        StepVector g;
        const double cost = f(x, &g, nullptr);
        EXPECT_NEAR(l.information, p.weight / (p.sigma * p.sigma), 1e-12 * l.information);
        EXPECT_NEAR(cost, 0.5 * l.chi2, 1e-12 * (1.0 + cost));
        EXPECT_LT((g - l.information * l.residual * l.jacobian).cwiseAbs().maxCoeff(),
                  1e-9 * (1.0 + g.cwiseAbs().maxCoeff()));
    }
    StepParams p;
    if (GetParam() == TermKind::kPreservation) p.dheading_rad = 0.0;
    const Linearisation<9> l = MakeLinearisation(GetParam(), p)(TruthBlock(p));
    StepMatrix h;
    MakeTerm(GetParam(), p)(TruthBlock(p), nullptr, &h);
    EXPECT_NEAR(l.residual, 0.0, 1e-12);
    EXPECT_LT((h - l.information * l.jacobian * l.jacobian.transpose()).cwiseAbs().maxCoeff(),
              1e-9 * h.cwiseAbs().maxCoeff());
}

INSTANTIATE_TEST_SUITE_P(AllStepTerms, StepTermTest,
                         ::testing::Values(TermKind::kLength, TermKind::kDirection,
                                           TermKind::kHeadingChange, TermKind::kPreservation,
                                           TermKind::kHeight),
                         [](const ::testing::TestParamInfo<TermKind>& param_info) {
                             return Name(param_info.param);
                         });

TEST(StepLengthTerm, CostIsHalfWeightedSquaredResidual) {
    // Pose b 3 m ahead of a along yaw_a + direction, observed 2 m at scale 1: r = 1 m.
    const StepLengthTerm t{2.0, 0.5, 0.25, 0.5};
    StepVector x = StepVector::Zero();
    x[kYawA] = 0.2;
    x[kXb] = 3.0 * std::cos(0.7);
    x[kYb] = 3.0 * std::sin(0.7);
    x[kScale] = 1.0;
    EXPECT_NEAR(t.Evaluate(x, nullptr, nullptr), 0.5 * 0.5 * (1.0 / 0.25) * (1.0 / 0.25), 1e-12);
}

TEST(StepDirectionTerm, SidewaysMotionIsPenalisedWithSign) {
    // Moving 1 m to the left of yaw_a + direction: r = +1.
    const StepDirectionTerm t{0.0, 0.5, 1.0};
    StepVector x = StepVector::Zero();
    x[kYb] = 1.0;  // yaw_a = 0, motion along +North = left
    StepVector g;
    EXPECT_NEAR(t.Evaluate(x, &g, nullptr), 0.5 * 4.0, 1e-12);
    EXPECT_NEAR(g[kYb], 4.0, 1e-12);  // k * r * dr/dy_b = 4 * 1 * 1
}

// ---- Scale terms -------------------------------------------------------------------------

TEST(RandomWalkTerm, ZeroAtTruthAndDerivativesMatch) {
    const RandomWalkTerm t{0.02, 0.7};
    Eigen::Vector2d g;
    Eigen::Matrix2d h;
    EXPECT_NEAR(t.Evaluate(Eigen::Vector2d(1.1, 1.1), &g, &h), 0.0, 1e-20);
    EXPECT_LT(g.cwiseAbs().maxCoeff(), 1e-12);
    std::mt19937 rng(2024u);
    std::uniform_real_distribution<double> u(0.7, 1.3);
    for (int trial = 0; trial < 50; ++trial) {
        const Eigen::Vector2d x(u(rng), u(rng));
        t.Evaluate(x, &g, &h);
        for (int k = 0; k < 2; ++k) {
            Eigen::Vector2d xp = x, xm = x;
            xp[k] += kStep;
            xm[k] -= kStep;
            const double num =
                (t.Evaluate(xp, nullptr, nullptr) - t.Evaluate(xm, nullptr, nullptr)) / (2 * kStep);
            EXPECT_PRED2(Close, g[k], num) << "trial " << trial << " k " << k;
            Eigen::Vector2d gp, gm;
            t.Evaluate(xp, &gp, nullptr);
            t.Evaluate(xm, &gm, nullptr);
            for (int r = 0; r < 2; ++r) {
                EXPECT_PRED2(Close, h(r, k), (gp[r] - gm[r]) / (2 * kStep)) << "trial " << trial;
            }
        }
    }
    EXPECT_NEAR(t.Evaluate(Eigen::Vector2d(1.0, 1.04), nullptr, nullptr),
                0.5 * 0.7 * (0.04 / 0.02) * (0.04 / 0.02), 1e-12);
}

TEST(HeadingChangeBiasTerm, ZeroAtTruthAndDerivativesMatch) {
    // 0.1 s step turning 0.02 rad of which a bias of 0.05 rad/s explains 0.005 rad.
    const HeadingChangeBiasTerm t{0.015, 0.1, 0.004, 0.8};
    Eigen::Vector3d g;
    Eigen::Matrix3d h;
    EXPECT_NEAR(t.Evaluate(Eigen::Vector3d(0.3, 0.32, 0.05), &g, &h), 0.0, 1e-20);
    EXPECT_NEAR(g.norm(), 0.0, 1e-9);
    std::mt19937 rng(78u);
    std::normal_distribution<double> n(0.0, 0.05);
    for (int trial = 0; trial < 20; ++trial) {
        const Eigen::Vector3d x(n(rng), n(rng), n(rng));
        t.Evaluate(x, &g, &h);
        for (int k = 0; k < 3; ++k) {
            Eigen::Vector3d xp = x, xm = x, gp, gm;
            xp[k] += kStep, xm[k] -= kStep;
            const double num =
                (t.Evaluate(xp, &gp, nullptr) - t.Evaluate(xm, &gm, nullptr)) / (2 * kStep);
            EXPECT_PRED2(Close, g[k], num) << "trial " << trial;
            for (int r = 0; r < 3; ++r) {
                EXPECT_PRED2(Close, h(r, k), (gp[r] - gm[r]) / (2 * kStep)) << "trial " << trial;
            }
        }
        const Linearisation<3> lin = t.Linearise(x);
        EXPECT_NEAR((lin.information * lin.residual * lin.jacobian - g).norm(), 0.0, 1e-9);
    }
}

TEST(ScaleRangeTerm, FreeInsideGaussianOutside) {
    const ScaleRangeTerm t{0.8, 1.25, 0.05, 1.0};
    Vector1d g, h;
    for (double s : {0.8, 0.95, 1.0, 1.25}) {
        EXPECT_EQ(t.Evaluate(Vector1d(s), &g, &h), 0.0) << s;
        EXPECT_EQ(g[0], 0.0);
        EXPECT_EQ(h[0], 0.0);
    }
    EXPECT_NEAR(t.Evaluate(Vector1d(1.35), &g, &h), 0.5 * (0.1 / 0.05) * (0.1 / 0.05), 1e-12);
    EXPECT_NEAR(g[0], 0.1 / 0.0025, 1e-9);
    EXPECT_NEAR(t.Evaluate(Vector1d(0.7), &g, &h), 0.5 * (0.1 / 0.05) * (0.1 / 0.05), 1e-12);
    EXPECT_NEAR(g[0], -0.1 / 0.0025, 1e-9);
    for (double s : {0.5, 0.79, 1.3, 2.0}) {  // away from the kinks at the ends
        t.Evaluate(Vector1d(s), &g, &h);
        Vector1d gp, gm;
        const double num = (t.Evaluate(Vector1d(s + kStep), &gp, nullptr) -
                            t.Evaluate(Vector1d(s - kStep), &gm, nullptr)) /
                           (2 * kStep);
        EXPECT_PRED2(Close, g[0], num) << s;
        EXPECT_PRED2(Close, h[0], (gp[0] - gm[0]) / (2 * kStep)) << s;
    }
}

TEST(ScalePriorTerm, ZeroAtOneAndDerivativesMatch) {
    const ScalePriorTerm t{0.1, 0.9};
    double g = -1.0, h = -1.0;
    EXPECT_NEAR(t.Evaluate(1.0, &g, &h), 0.0, 1e-20);
    EXPECT_NEAR(g, 0.0, 1e-15);
    EXPECT_NEAR(h, 0.9 / 0.01, 1e-9);
    std::mt19937 rng(77u);
    std::uniform_real_distribution<double> u(0.5, 1.5);
    for (int trial = 0; trial < 50; ++trial) {
        const double s = u(rng);
        t.Evaluate(s, &g, &h);
        const double num_g =
            (t.Evaluate(s + kStep, nullptr, nullptr) - t.Evaluate(s - kStep, nullptr, nullptr)) /
            (2 * kStep);
        double gp, gm;
        t.Evaluate(s + kStep, &gp, nullptr);
        t.Evaluate(s - kStep, &gm, nullptr);
        EXPECT_PRED2(Close, g, num_g) << "s = " << s;
        EXPECT_PRED2(Close, h, (gp - gm) / (2 * kStep)) << "s = " << s;
    }
}

// ---- Map distance term -------------------------------------------------------------------

/// A synthetic distance field d(p) = |p - c| with its exact gradient and Hessian, composed with
/// the term: the total cost f(p) = rho(d(p)) and its analytic derivatives with respect to p.
struct PointDistance {
    Eigen::Vector3d c{1.0, -2.0, 0.5};
    double Cost(const MapDistanceTerm& t, const Eigen::Vector3d& p, Eigen::Vector3d* grad,
                Eigen::Matrix3d* hess) const {
        const Eigen::Vector3d v = p - c;
        const double d = v.norm();
        const Eigen::Vector3d u = v / d;
        const Eigen::Matrix3d hd = (Eigen::Matrix3d::Identity() - u * u.transpose()) / d;
        return t.Evaluate(d, u, hd, grad, hess);
    }
};

TEST(MapDistanceTerm, ZeroCostAndGradientOnTheCentre) {
    const MapDistanceTerm t{2.0, 8.0, 1.0};
    Eigen::Vector3d g;
    Eigen::Matrix3d h;
    const Eigen::Vector3d grad_d(0.0, 1.0, 0.0);
    EXPECT_NEAR(t.Evaluate(0.0, grad_d, Eigen::Matrix3d::Zero(), &g, &h), 0.0, 1e-20);
    EXPECT_LT(g.cwiseAbs().maxCoeff(), 1e-15);
    // Curvature there is w / sigma^2 along the distance gradient.
    EXPECT_NEAR(h(1, 1), 1.0 / 4.0, 1e-12);
}

TEST(MapDistanceTerm, TotalDerivativesMatchCentralDifferences) {
    const PointDistance field;
    std::mt19937 rng(31415u);
    std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.0, 1.0);
    for (int trial = 0; trial < 50; ++trial) {
        const MapDistanceTerm t{0.5 + 2.5 * pos(rng), 2.0 + 10.0 * pos(rng), 0.1 + 0.9 * pos(rng)};
        // Random direction, distance 0.5 .. 30 m from the centre (inside and beyond give-up).
        Eigen::Vector3d dir(u(rng), u(rng), u(rng));
        dir.normalize();
        const Eigen::Vector3d p = field.c + (0.5 + 29.5 * pos(rng)) * dir;
        Eigen::Vector3d g;
        Eigen::Matrix3d h;
        field.Cost(t, p, &g, &h);
        for (int k = 0; k < 3; ++k) {
            Eigen::Vector3d pp = p, pm = p;
            pp[k] += kStep;
            pm[k] -= kStep;
            const double num_g =
                (field.Cost(t, pp, nullptr, nullptr) - field.Cost(t, pm, nullptr, nullptr)) /
                (2.0 * kStep);
            EXPECT_PRED2(Close, g[k], num_g) << "trial " << trial << " k " << k;
            Eigen::Vector3d gp, gm;
            field.Cost(t, pp, &gp, nullptr);
            field.Cost(t, pm, &gm, nullptr);
            for (int r = 0; r < 3; ++r) {
                EXPECT_PRED2(Close, h(r, k), (gp[r] - gm[r]) / (2.0 * kStep))
                    << "trial " << trial << " (" << r << ", " << k << ")";
            }
        }
        EXPECT_TRUE(h.isApprox(h.transpose(), 1e-12));
    }
}

TEST(MapDistanceTerm, DerivativesWithRespectToDistanceMatch) {
    // The scalar profile rho(d): d rho / dd and d2 rho / dd2 via a unit gradient along x.
    const MapDistanceTerm t{2.0, 8.0, 0.6};
    const Eigen::Vector3d ex = Eigen::Vector3d::UnitX();
    const Eigen::Matrix3d zero = Eigen::Matrix3d::Zero();
    auto rho = [&](double d) { return t.Evaluate(d, ex, zero, nullptr, nullptr); };
    for (double d = 0.0; d <= 40.0; d += 0.37) {
        Eigen::Vector3d g;
        Eigen::Matrix3d h;
        t.Evaluate(d, ex, zero, &g, &h);
        EXPECT_PRED2(Close, g.x(), (rho(d + kStep) - rho(d - kStep)) / (2.0 * kStep)) << "d " << d;
        Eigen::Vector3d gp, gm;
        t.Evaluate(d + kStep, ex, zero, &gp, nullptr);
        t.Evaluate(d - kStep, ex, zero, &gm, nullptr);
        EXPECT_PRED2(Close, h(0, 0), (gp.x() - gm.x()) / (2.0 * kStep)) << "d " << d;
    }
}

// The map term's Gauss-Newton curvature: max(rho''(d), 0) along grad d, the exact Hessian on the
// centre (d = 0) and for a linear distance (zero Hessian of d) wherever rho'' >= 0; none beyond.
TEST(MapDistanceTerm, LinearisationIsThePositivePartOfTheCurvature) {
    const MapDistanceTerm t{2.0, 8.0, 0.7};
    const Eigen::Vector3d u = Eigen::Vector3d(0.6, -0.8, 0.0);
    const Eigen::Matrix3d zero = Eigen::Matrix3d::Zero();
    for (double d : {0.0, 0.5, 3.0, 7.9, 8.1, 20.0}) {
        const Linearisation<3> l = t.Linearise(d, u);
        Eigen::Vector3d g;
        Eigen::Matrix3d h;
        const double cost = t.Evaluate(d, u, zero, &g, &h);
        EXPECT_EQ(l.residual, d);
        EXPECT_EQ(l.jacobian, u);
        EXPECT_GE(l.information, 0.0);
        if (d < 8.0) {
            EXPECT_LT((h - l.information * u * u.transpose()).cwiseAbs().maxCoeff(), 1e-12)
                << "d " << d;
        } else {
            EXPECT_EQ(l.information, 0.0) << "d " << d;
        }
        // chi2 is the IRLS weight rho'(d) / d times d^2; the cost is its Gaussian near zero.
        EXPECT_NEAR(l.chi2, g.dot(u) * d, 1e-12 * (1.0 + l.chi2)) << "d " << d;
        if (d <= 0.5) {
            EXPECT_NEAR(cost, 0.5 * l.chi2, 0.01 * l.chi2 + 1e-15) << "d " << d;
        }
    }
}

TEST(MapDistanceTerm, GaussianNearTheCentreAndGivesUpFarAway) {
    const double sigma = 2.0, giveup = 8.0, w = 0.7;
    const MapDistanceTerm t{sigma, giveup, w};
    const Eigen::Vector3d ex = Eigen::Vector3d::UnitX();
    const Eigen::Matrix3d zero = Eigen::Matrix3d::Zero();
    // d << c: rho = 0.5 w (d / sigma)^2 (1 - d^2 / (4 c^2) + ...), within 1% for d <= c / 10.
    for (double d : {0.01, 0.1, 0.4, 0.8}) {
        const double gaussian = 0.5 * w * (d / sigma) * (d / sigma);
        EXPECT_NEAR(t.Evaluate(d, ex, zero, nullptr, nullptr), gaussian, 0.01 * gaussian)
            << "d = " << d;
        Eigen::Vector3d g;
        t.Evaluate(d, ex, zero, &g, nullptr);
        EXPECT_NEAR(g.x(), w * d / (sigma * sigma), 0.01 * w * d / (sigma * sigma));
    }
    // d >> c: no pull, and the cost saturates at w (c / sigma)^2.
    for (double d : {6.0 * giveup, 10.0 * giveup, 100.0 * giveup}) {
        Eigen::Vector3d g;
        Eigen::Matrix3d h;
        const double c = t.Evaluate(d, ex, zero, &g, &h);
        EXPECT_LT(g.norm(), 1e-6) << "d = " << d;
        EXPECT_LT(h.cwiseAbs().maxCoeff(), 1e-6) << "d = " << d;
        EXPECT_NEAR(c, w * (giveup / sigma) * (giveup / sigma), 1e-6);
    }
    // Beyond the inflection d = c the cost flattens: the pull decreases with distance.
    Eigen::Vector3d g1, g2;
    t.Evaluate(1.5 * giveup, ex, zero, &g1, nullptr);
    t.Evaluate(2.5 * giveup, ex, zero, &g2, nullptr);
    EXPECT_LT(g2.x(), g1.x());
}

// ---- Pose prior (marginalised poses before a fixed-lag window) ---------------------------

PosePriorTerm MakePosePrior(bool with_scale) {
    PosePriorTerm t;
    t.mean << 3.0, -1.5, 0.2, 0.7;
    Eigen::Matrix<double, 5, 5> a;
    a << 2.0, 0.3, 0.0, 0.5, 0.2,  //
        0.1, 1.5, 0.0, -0.2, 0.1,  //
        0.0, 0.0, 0.0, 0.0, 0.0,   // a height the prior says nothing about
        0.4, -0.1, 0.0, 3.0, 0.0,  //
        0.6, -0.3, 0.0, 0.2, 4.0;
    const JointMatrix info = a * a.transpose();
    t.information = info.topLeftCorner<4, 4>();
    if (with_scale) {
        t.scale_segment = 2;
        t.scale_mean = 1.2;
        t.cross = info.topRightCorner<4, 1>();
        t.scale_information = info(4, 4);
    }
    return t;
}

TEST(PosePriorTerm, ZeroAtTheMeanAndDerivativesMatch) {
    for (bool with_scale : {false, true}) {
        SCOPED_TRACE(with_scale ? "with its scale" : "pose alone");
        const PosePriorTerm t = MakePosePrior(with_scale);
        const int n = t.Size();
        ASSERT_EQ(n, with_scale ? 5 : 4);
        JointVector g;
        JointMatrix h;
        EXPECT_NEAR(t.Evaluate(t.JointMean(), &g, &h), 0.0, 1e-20);
        EXPECT_LT(g.cwiseAbs().maxCoeff(), 1e-15);
        std::mt19937 rng(4711u);
        std::uniform_real_distribution<double> u(-5.0, 5.0);
        for (int trial = 0; trial < 50; ++trial) {
            JointVector x;
            x << u(rng), u(rng), u(rng), u(rng), u(rng);
            t.Evaluate(x, &g, &h);
            for (int k = 0; k < n; ++k) {
                JointVector xp = x, xm = x;
                xp[k] += kStep;
                xm[k] -= kStep;
                const double num =
                    (t.Evaluate(xp, nullptr, nullptr) - t.Evaluate(xm, nullptr, nullptr)) /
                    (2 * kStep);
                EXPECT_PRED2(Close, g[k], num) << "trial " << trial << " k " << k;
                JointVector gp, gm;
                t.Evaluate(xp, &gp, nullptr);
                t.Evaluate(xm, &gm, nullptr);
                for (int r = 0; r < n; ++r) {
                    EXPECT_PRED2(Close, h(r, k), (gp[r] - gm[r]) / (2 * kStep))
                        << "trial " << trial;
                }
            }
        }
        // Moving the height, which the prior does not constrain, costs nothing; without a scale,
        // neither does the fifth entry.
        JointVector up = t.JointMean();
        up[2] += 10.0;
        EXPECT_NEAR(t.Evaluate(up, nullptr, nullptr), 0.0, 1e-12);
        JointVector scaled = t.JointMean();
        scaled[4] += 0.3;
        if (with_scale) {
            EXPECT_GT(t.Evaluate(scaled, nullptr, nullptr), 0.1);
        } else {
            EXPECT_EQ(t.Evaluate(scaled, nullptr, nullptr), 0.0);
        }
    }
}

TEST(PosePriorTerm, LinearisationSumsToTheInformationAndTheCost) {
    for (bool with_scale : {false, true}) {
        SCOPED_TRACE(with_scale ? "with its scale" : "pose alone");
        const PosePriorTerm t = MakePosePrior(with_scale);
        JointVector x;
        x << 2.0, -1.0, 0.5, 0.4, 1.1;
        JointMatrix sum = JointMatrix::Zero();
        double chi2 = 0.0;
        for (const Linearisation<5>& l : t.Linearise(x)) {
            EXPECT_GE(l.information, 0.0);
            JointVector e = x - t.JointMean();
            if (!with_scale) e[4] = 0.0;
            EXPECT_NEAR(l.residual, l.jacobian.dot(e), 1e-12);
            sum += l.information * l.jacobian * l.jacobian.transpose();
            chi2 += l.chi2;
        }
        EXPECT_LT((sum - t.JointInformation()).cwiseAbs().maxCoeff(), 1e-10);
        EXPECT_NEAR(0.5 * chi2, t.Evaluate(x, nullptr, nullptr), 1e-10);
    }
}

}  // namespace
}  // namespace driftcorr

namespace {

// The heavy-tailed scale walk: quadratic near zero, logarithmic far out, exact derivatives.
TEST(ScaleRandomWalkRobust, MatchesGaussianNearZeroAndCentralDifferences) {
    const driftcorr::RandomWalkTerm robust{0.01, 0.7, 3.0};
    const driftcorr::RandomWalkTerm gauss{0.01, 0.7, 0.0};
    const Eigen::Vector2d small(1.0, 1.0005);
    EXPECT_NEAR(robust.Evaluate(small, nullptr, nullptr), gauss.Evaluate(small, nullptr, nullptr),
                1e-3 * gauss.Evaluate(small, nullptr, nullptr));
    const Eigen::Vector2d far(1.0, 1.4);  // 40 sigma
    EXPECT_LT(robust.Evaluate(far, nullptr, nullptr), 0.05 * gauss.Evaluate(far, nullptr, nullptr));
    for (const Eigen::Vector2d& x :
         {Eigen::Vector2d(0.9, 1.1), Eigen::Vector2d(1.2, 1.15), Eigen::Vector2d(1.0, 1.03)}) {
        Eigen::Vector2d g;
        Eigen::Matrix2d h;
        robust.Evaluate(x, &g, &h);
        const double eps = 1e-7;
        for (int k = 0; k < 2; ++k) {
            Eigen::Vector2d xp = x, xm = x;
            xp[k] += eps;
            xm[k] -= eps;
            Eigen::Vector2d gp, gm;
            const double fd =
                (robust.Evaluate(xp, &gp, nullptr) - robust.Evaluate(xm, &gm, nullptr)) / (2 * eps);
            EXPECT_NEAR(g[k], fd, 1e-5 * (1.0 + std::abs(fd)));
            const Eigen::Vector2d hfd = (gp - gm) / (2 * eps);
            EXPECT_NEAR((h.col(k) - hfd).norm(), 0.0, 1e-4 * (1.0 + hfd.norm()));
        }
    }
}

}  // namespace

namespace {

// Central-difference gradient and Hessian (of the analytic gradient) of any term with an
// Evaluate(x, grad, hess) of fixed size.
template <typename Term, typename Vec, typename Mat>
void ExpectDerivativesMatch(const Term& term, const Vec& x, double tol) {
    Vec g;
    Mat h;
    term.Evaluate(x, &g, &h);
    const double eps = 1e-6;
    for (int k = 0; k < x.size(); ++k) {
        Vec xp = x, xm = x;
        xp[k] += eps;
        xm[k] -= eps;
        Vec gp, gm;
        const double fd =
            (term.Evaluate(xp, &gp, nullptr) - term.Evaluate(xm, &gm, nullptr)) / (2 * eps);
        EXPECT_NEAR(g[k], fd, tol * (1.0 + std::abs(fd))) << "gradient " << k;
        const Vec hfd = (gp - gm) / (2 * eps);
        for (int r = 0; r < x.size(); ++r) {
            EXPECT_NEAR(h(r, k), hfd[r], tol * (1.0 + std::abs(hfd[r])))
                << "hessian " << r << "," << k;
        }
    }
}

TEST(StepLengthRobust, DerivativesAndOutlierDownweighting) {
    std::mt19937 rng(20261122);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    const driftcorr::StepLengthTerm robust{1.2, 0.1, 0.03, 0.8, 3.0};
    for (int n = 0; n < 30; ++n) {
        driftcorr::StepVector x;
        for (int k = 0; k < x.size(); ++k) x[k] = u(rng);
        x[driftcorr::kScale] = 1.0 + 0.1 * u(rng);
        ExpectDerivativesMatch<driftcorr::StepLengthTerm, driftcorr::StepVector,
                               driftcorr::StepMatrix>(robust, x, 1e-5);
    }
    // A dropped step (observed 0 m, moved 1.2 m = 40 sigma) costs far less than under a Gaussian.
    const driftcorr::StepLengthTerm dropped_robust{0.0, 0.0, 0.03, 1.0, 3.0};
    const driftcorr::StepLengthTerm dropped_gauss{0.0, 0.0, 0.03, 1.0};
    driftcorr::StepVector moved = driftcorr::StepVector::Zero();
    moved[driftcorr::kXb] = 1.2;
    moved[driftcorr::kScale] = 1.0;
    EXPECT_LT(dropped_robust.Evaluate(moved, nullptr, nullptr),
              0.05 * dropped_gauss.Evaluate(moved, nullptr, nullptr));  // 23.3 vs 800
}

// Linearisation of the terms outside the step block and of the robust ones: Jacobian against
// central differences of the residual, gradient = information * r * J (IRLS), and the exact
// Hessian at r = 0.
template <typename Term, typename Vec, typename Mat>
void ExpectLinearisationMatches(const Term& term, const Vec& x, double tol) {
    const auto l = term.Linearise(x);
    const double eps = 1e-6;
    for (int k = 0; k < x.size(); ++k) {
        Vec xp = x, xm = x;
        xp[k] += eps;
        xm[k] -= eps;
        const double num = (term.Linearise(xp).residual - term.Linearise(xm).residual) / (2 * eps);
        EXPECT_NEAR(l.jacobian[k], num, tol * (1.0 + std::abs(num))) << "dr/dx " << k;
    }
    Vec g;
    term.Evaluate(x, &g, nullptr);
    const Vec irls = l.information * l.residual * l.jacobian;
    EXPECT_LT((g - irls).cwiseAbs().maxCoeff(), tol * (1.0 + g.cwiseAbs().maxCoeff()));
    EXPECT_NEAR(l.chi2, l.information * l.residual * l.residual, 1e-12 * (1.0 + l.chi2));
}

TEST(Linearisation, RobustSpeedAndScaleTerms) {
    std::mt19937 rng(8080u);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    const driftcorr::StepLengthTerm robust{1.2, 0.1, 0.03, 0.8, 3.0};
    const driftcorr::SpeedChangeTerm speed{0.05, 0.1, -0.03, 0.12, 0.5, 0.9};
    const driftcorr::RandomWalkTerm walk{0.02, 0.7, 0.0}, robust_walk{0.02, 0.7, 3.0};
    for (int n = 0; n < 20; ++n) {
        driftcorr::StepVector xs;
        for (int k = 0; k < xs.size(); ++k) xs[k] = u(rng);
        xs[driftcorr::kScale] = 1.0 + 0.1 * u(rng);
        ExpectLinearisationMatches<driftcorr::StepLengthTerm, driftcorr::StepVector,
                                   driftcorr::StepMatrix>(robust, xs, 1e-5);
        driftcorr::SpeedVector xv;
        for (int k = 0; k < xv.size(); ++k) xv[k] = u(rng);
        ExpectLinearisationMatches<driftcorr::SpeedChangeTerm, driftcorr::SpeedVector,
                                   driftcorr::SpeedMatrix>(speed, xv, 1e-5);
        const Eigen::Vector2d x2(1.0 + 0.05 * u(rng), 1.0 + 0.05 * u(rng));
        ExpectLinearisationMatches<driftcorr::RandomWalkTerm, Eigen::Vector2d, Eigen::Matrix2d>(
            walk, x2, 1e-5);
        ExpectLinearisationMatches<driftcorr::RandomWalkTerm, Eigen::Vector2d, Eigen::Matrix2d>(
            robust_walk, x2, 1e-5);
    }
    // At r = 0 the Cauchy weight is the Gaussian's: information * J J^T is the exact Hessian.
    driftcorr::StepVector at = driftcorr::StepVector::Zero();
    at[driftcorr::kXb] = 1.2 * std::cos(0.1), at[driftcorr::kYb] = 1.2 * std::sin(0.1);
    at[driftcorr::kScale] = 1.0;
    driftcorr::StepMatrix h;
    robust.Evaluate(at, nullptr, &h);
    const auto l = robust.Linearise(at);
    EXPECT_NEAR(l.residual, 0.0, 1e-12);
    EXPECT_LT((h - l.information * l.jacobian * l.jacobian.transpose()).cwiseAbs().maxCoeff(),
              1e-9 * h.cwiseAbs().maxCoeff());
    const driftcorr::ScalePriorTerm prior{0.1, 0.9};
    double hp = 0.0;
    prior.Evaluate(1.3, nullptr, &hp);
    const auto lp = prior.Linearise(1.3);
    EXPECT_NEAR(lp.residual, 0.3, 1e-15);
    EXPECT_NEAR(lp.information * lp.jacobian[0] * lp.jacobian[0], hp, 1e-12);
}

TEST(SpeedChange, ZeroAtConstantSpeedAndDerivatives) {
    // Three poses moving east at 8 m/s, 0.1 s apart: no speed change.
    driftcorr::SpeedVector x = driftcorr::SpeedVector::Zero();
    x[4] = 0.8, x[8] = 1.6;
    const driftcorr::SpeedChangeTerm term{0.0, 0.1, 0.0, 0.1, 0.5, 1.0};
    driftcorr::SpeedVector g;
    EXPECT_NEAR(term.Evaluate(x, &g, nullptr), 0.0, 1e-12);
    EXPECT_NEAR(g.norm(), 0.0, 1e-9);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    const driftcorr::SpeedChangeTerm curved{0.05, 0.1, -0.03, 0.12, 0.5, 0.9};
    for (int n = 0; n < 30; ++n) {
        for (int k = 0; k < x.size(); ++k) x[k] = u(rng);
        ExpectDerivativesMatch<driftcorr::SpeedChangeTerm, driftcorr::SpeedVector,
                               driftcorr::SpeedMatrix>(curved, x, 1e-5);
    }
}

}  // namespace
