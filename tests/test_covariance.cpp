// Tests of the per-pose covariance (optim/src/covariance.cpp) and the terms' linearisation it
// rests on (WindowProblem::LineariseTerms): the selected inverse equals a dense inverse of the same
// Gauss-Newton Hessian, the Gauss-Newton Hessian equals the exact one where the residuals vanish,
// dead reckoning grows and a road bounds the cross-track uncertainty, and the variance factor's
// redundancy numbers add up to m - n.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/metrics.h"
#include "driftcorr/core/observables.h"
#include "driftcorr/mapping/road_network.h"
#include "driftcorr/optim/corrector.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/window_problem.h"
#include "test_state.h"

namespace driftcorr {
namespace {

/// A curve of n poses: `step_m` steps turning `turn_rad` per step, 0.2 s apart, a gentle climb,
/// and (if `stop`) pose n/2 repeating pose n/2 - 1.
PlanarTrajectory Curve(int n, double turn_rad = 0.04, bool stop = true, double step_m = 2.0) {
    PlanarTrajectory t;
    Eigen::Vector2d p(10.0, -5.0);
    double yaw = 0.3;
    for (int i = 0; i < n; ++i) {
        if (i > 0) {
            const double len = (stop && i == n / 2) ? 0.0 : step_m;
            p += len * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
            yaw += turn_rad;
        }
        t.t_s.push_back(0.2 * i);
        t.p_en.push_back(p);
        t.up_m.push_back(1.0 + 0.05 * i);
        t.yaw_rad.push_back(yaw);
    }
    return t;
}

/// A road along the trajectory (extended 20 m at both ends), rasterised at 0.5 m.
TraversableField RoadAlong(const PlanarTrajectory& truth) {
    RoadPolyline road{1, "residential", 3.5, {}};
    const Eigen::Vector2d d0(std::cos(truth.yaw_rad.front()), std::sin(truth.yaw_rad.front()));
    const Eigen::Vector2d d1(std::cos(truth.yaw_rad.back()), std::sin(truth.yaw_rad.back()));
    road.points_en.push_back(truth.p_en.front() - 20.0 * d0);
    for (std::size_t i = 0; i < truth.size(); ++i) {
        if (i == 0 || (truth.p_en[i] - truth.p_en[i - 1]).norm() > 0.0) {
            road.points_en.push_back(truth.p_en[i]);
        }
    }
    road.points_en.push_back(truth.p_en.back() + 20.0 * d1);
    RoadNetwork net;
    net.roads = {road};
    Eigen::AlignedBox2d box;
    for (const auto& p : truth.p_en) box.extend(p);
    RoadFieldConfig cfg;
    cfg.margin_m = 30.0;
    cfg.truncation_m = 20.0;
    return RasteriseRoads(net, box, cfg);
}

/// A "distance" field that is linear in the position with a unit gradient, d(p) = 0.3 + u . (p - c)
/// (u horizontal for a planar field): an exact distance (to a plane) with zero Hessian, so the map
/// term's Gauss-Newton curvature is exact wherever its curvature rho'' is positive.
TraversableField LinearField(const PlanarTrajectory& truth, bool planar) {
    Eigen::AlignedBox2d box;
    for (const auto& p : truth.p_en) box.extend(p);
    const Eigen::Vector3d u =
        planar ? Eigen::Vector3d(0.8, -0.6, 0.0) : Eigen::Vector3d(0.6, -0.48, 0.64);
    const Eigen::Vector3d c(box.center().x(), box.center().y(), 1.0);
    GridSpec spec;
    spec.resolution_m = 1.0;
    spec.origin_m =
        Eigen::Vector3d(box.min().x() - 10.0, box.min().y() - 10.0, planar ? 0.0 : -5.0);
    spec.nx = static_cast<int>(box.sizes().x()) + 21;
    spec.ny = static_cast<int>(box.sizes().y()) + 21;
    spec.nz = planar ? 1 : 20;
    std::vector<float> values(spec.size()), corridor(spec.size(), -1.0f);
    for (int k = 0; k < spec.nz; ++k) {
        for (int j = 0; j < spec.ny; ++j) {
            for (int i = 0; i < spec.nx; ++i) {
                values[spec.Index(i, j, k)] =
                    static_cast<float>(0.3 + u.dot(spec.Position(i, j, k) - c));
            }
        }
    }
    return TraversableField(InterpolatedField(spec, values), InterpolatedField(spec, corridor),
                            20.0);
}

using test::StateFrom;

/// Moves poses 1.. by ~0.3 m, ~0.02 rad (and heights ~0.1 m) and scales by ~0.02: residuals
/// that are not zero, so the Gauss-Newton Hessian differs from the exact one.
void Perturb(TrajectoryState& s, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    for (std::size_t i = 1; i < s.poses.size(); ++i) {
        s.poses[i].p += Eigen::Vector3d(0.3 * n(rng), 0.3 * n(rng), 0.1 * n(rng));
        s.poses[i].yaw_rad += 0.02 * n(rng);
    }
    for (double& scale : s.scales) scale += 0.02 * n(rng);
}

/// Moves poses 1.. `offset_m` to the left of their heading (a lane beside the centre line).
void ShiftLeft(TrajectoryState& s, double offset_m) {
    for (std::size_t i = 1; i < s.poses.size(); ++i) {
        const double yaw = s.poses[i].yaw_rad;
        s.poses[i].p += offset_m * Eigen::Vector3d(-std::sin(yaw), std::cos(yaw), 0.0);
    }
}

/// Dense Gauss-Newton Hessian of the whole-trajectory problem at the state, without the fixed
/// heights (planar mode), and the map from window variable to its row (-1: removed).
struct DenseReference {
    Eigen::MatrixXd h;
    std::vector<int> row;
};

DenseReference ReferenceHessian(const WindowProblem& p, const TrajectoryState& s) {
    std::vector<double> x(p.NumVariables());
    p.InitialPoint(x.data());
    const Eigen::MatrixXd full = DenseGaussNewtonHessian(p, x.data());
    DenseReference ref;
    ref.row.assign(p.NumVariables(), -1);
    std::vector<int> keep;
    for (int v = 0; v < p.NumVariables(); ++v) {
        const bool fixed_height = s.fix_height && v < 4 * int(p.last()) && v % 4 == 2;
        if (!fixed_height) ref.row[v] = static_cast<int>(keep.size()), keep.push_back(v);
    }
    ref.h.resize(keep.size(), keep.size());
    for (std::size_t a = 0; a < keep.size(); ++a) {
        for (std::size_t b = 0; b < keep.size(); ++b) ref.h(a, b) = full(keep[a], keep[b]);
    }
    return ref;
}

struct CovarianceCase {
    int poses;
    bool fix_height;
    bool with_field;
    bool all_terms;  ///< robust step length and speed continuity as well
    unsigned seed;
};

void PrintTo(const CovarianceCase& c, std::ostream* os) {
    *os << c.poses << " poses" << (c.fix_height ? " planar" : " free height")
        << (c.with_field ? ", field" : ", no field") << (c.all_terms ? ", all terms" : "")
        << ", seed " << c.seed;
}

class CovarianceVsDense : public ::testing::TestWithParam<CovarianceCase> {};

/// Expects the marginals in `r` to equal the blocks of the inverse of `h` (dense, in long double
/// so that the reference's own error is far below the tolerance): each entry within 1e-9 of
/// sqrt(Sigma_aa Sigma_bb), the scale Cauchy-Schwarz gives it. `unknowns[i]`: pose i's unknowns.
void ExpectMarginalsOfTheInverse(const CovarianceResult& r, const Eigen::MatrixXd& h,
                                 const std::vector<std::array<int, 4>>& unknowns, bool fix_height) {
    using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
    const MatL hl = h.cast<long double>();
    const Eigen::MatrixXd sigma =
        hl.llt().solve(MatL::Identity(hl.rows(), hl.cols())).cast<double>();
    auto expect_entry = [&](double got, int a, int b, const std::string& what, std::size_t i) {
        const double want = sigma(a, b), scale = std::sqrt(sigma(a, a) * sigma(b, b));
        EXPECT_LE(std::abs(got - want), 1e-9 * scale) << what << " of pose " << i;
    };
    EXPECT_EQ(r.poses[0].xy_m2, Eigen::Matrix2d::Zero());
    EXPECT_EQ(r.poses[0].yaw_rad2, 0.0);
    for (std::size_t i = 1; i < r.poses.size(); ++i) {
        const auto [x, y, z, yaw] = unknowns[i];
        const PoseCovariance& pc = r.poses[i];
        expect_entry(pc.xy_m2(0, 0), x, x, "var East", i);
        expect_entry(pc.xy_m2(1, 1), y, y, "var North", i);
        expect_entry(pc.xy_m2(0, 1), x, y, "cov East-North", i);
        EXPECT_EQ(pc.xy_m2(0, 1), pc.xy_m2(1, 0));
        expect_entry(pc.yaw_rad2, yaw, yaw, "var yaw", i);
        expect_entry(pc.xy_yaw_m_rad.x(), x, yaw, "cov East-yaw", i);
        expect_entry(pc.xy_yaw_m_rad.y(), y, yaw, "cov North-yaw", i);
        if (fix_height) {
            EXPECT_EQ(z, -1);
            EXPECT_EQ(pc.z_m2, 0.0);
        } else {
            expect_entry(pc.z_m2, z, z, "var height", i);
        }
    }
}

// (a) The selected inverse equals the dense inverse of the same matrix: the solver's own
// Gauss-Newton Hessian (no map offset, no variance components), and the default model.
TEST_P(CovarianceVsDense, MarginalsEqualBlocksOfTheDenseInverse) {
    const CovarianceCase c = GetParam();
    ModelConfig model;
    model.scale_segment_m = 20.0;  // several scale segments
    if (c.all_terms) model.step_robust_k = 3.0, model.accel_sigma_mps2 = 2.0;
    const PlanarTrajectory truth = Curve(c.poses);
    const TraversableField field = RoadAlong(truth);
    const TraversableField* f = c.with_field ? &field : nullptr;
    TrajectoryState s = StateFrom(truth, model, c.fix_height);
    Perturb(s, c.seed);

    // The solver's model: the matrix is the Gauss-Newton Hessian of the NLL.
    CovarianceConfig plain;
    plain.map_offset_share = 0.0;
    plain.map_across_travel = false;
    plain.family_variance_components = false;
    CovarianceSystem system;
    const CovarianceResult r = ComputeCovariance(s, f, model, plain, &system);
    ASSERT_EQ(r.status, CovarianceStatus::kOk) << r.message;
    ASSERT_EQ(r.poses.size(), s.poses.size());
    EXPECT_FALSE(r.variance_factor_applied);
    const std::size_t n = s.poses.size();
    TrajectoryState copy = s;
    const WindowProblem p(copy, f, model, 1, n - 1, std::vector<std::uint8_t>(n - 1, 0));
    const DenseReference ref = ReferenceHessian(p, s);
    ASSERT_EQ(ref.h.rows(), static_cast<Eigen::Index>(r.unknowns));
    std::vector<std::array<int, 4>> ref_unknowns(n, {-1, -1, -1, -1});
    for (std::size_t i = 1; i < n; ++i) {
        for (int k = 0; k < 4; ++k) ref_unknowns[i][k] = ref.row[p.PoseVar(i, k)];
    }
    ExpectMarginalsOfTheInverse(r, ref.h, ref_unknowns, c.fix_height);
    // The drive's mean scale: its scale unknowns weighted by the estimated path of each.
    {
        using VecL = Eigen::Matrix<long double, Eigen::Dynamic, 1>;
        VecL w = VecL::Zero(ref.h.rows());
        long double path_m = 0.0L;
        for (std::size_t i = 1; i < n; ++i) path_m += s.obs[i].length_m;
        for (std::size_t i = 1; i < n; ++i) {
            w[ref.row[p.ScaleVar(s.scale_segment[i])]] += s.obs[i].length_m / path_m;
        }
        const VecL hw = ref.h.cast<long double>().llt().solve(w);
        const double want = std::sqrt(static_cast<double>(w.dot(hw)));
        ASSERT_GT(want, 0.0);
        EXPECT_NEAR(r.mean_scale_sd, want, 1e-9 * want);
    }
    // The same matrix, ordered differently.
    const Eigen::MatrixXd h = Eigen::MatrixXd(system.information);
    for (std::size_t i = 1; i < n; ++i) {
        for (int a = 0; a < 4; ++a) {
            for (int b = 0; b < 4; ++b) {
                const int ra = ref_unknowns[i][a], rb = ref_unknowns[i][b];
                if (ra < 0 || rb < 0) continue;
                EXPECT_NEAR(h(system.pose_unknowns[i][a], system.pose_unknowns[i][b]),
                            ref.h(ra, rb), 1e-12 * ref.h.cwiseAbs().maxCoeff());
            }
        }
    }
    // The factor's fill stays linear: a bounded number of entries per unknown.
    EXPECT_LE(r.factor_nonzeros, 12 * r.unknowns);

    // The default model: map offset process and variance components.
    const CovarianceResult d = ComputeCovariance(s, f, model, CovarianceConfig{}, &system);
    ASSERT_EQ(d.status, CovarianceStatus::kOk) << d.message;
    if (c.with_field) {
        EXPECT_GT(d.unknowns, r.unknowns) << "offset unknowns";
    }
    ExpectMarginalsOfTheInverse(d, Eigen::MatrixXd(system.information), system.pose_unknowns,
                                c.fix_height);
    EXPECT_LE(d.factor_nonzeros, 12 * d.unknowns);

    // With the step length's error process as well (a correlation length of a few steps).
    CovarianceConfig stepped;
    stepped.step_error_sd = 0.1;
    stepped.step_error_correlation_m = 6.0;
    const CovarianceResult e = ComputeCovariance(s, f, model, stepped, &system);
    ASSERT_EQ(e.status, CovarianceStatus::kOk) << e.message;
    EXPECT_GT(e.unknowns, d.unknowns) << "step error unknowns";
    EXPECT_GT(e.families[int(TermFamily::kStepError)].terms, 0u);
    ExpectMarginalsOfTheInverse(e, Eigen::MatrixXd(system.information), system.pose_unknowns,
                                c.fix_height);
    // One more open unknown (the step error's stretch) beside each pose's elimination.
    EXPECT_LE(e.factor_nonzeros, 14 * e.unknowns);
}

INSTANTIATE_TEST_SUITE_P(SmallProblems, CovarianceVsDense,
                         ::testing::Values(CovarianceCase{3, true, false, false, 11u},
                                           CovarianceCase{4, false, true, false, 12u},
                                           CovarianceCase{12, true, true, false, 13u},
                                           CovarianceCase{12, false, false, true, 14u},
                                           CovarianceCase{25, true, true, true, 15u},
                                           CovarianceCase{40, true, false, false, 16u},
                                           CovarianceCase{40, true, true, false, 17u},
                                           CovarianceCase{40, false, true, false, 18u},
                                           CovarianceCase{40, false, true, true, 19u}),
                         [](const ::testing::TestParamInfo<CovarianceCase>& info) {
                             const CovarianceCase& c = info.param;
                             return std::to_string(c.poses) + "_poses" +
                                    (c.fix_height ? "_planar" : "_free_height") +
                                    (c.with_field ? "_field" : "_no_field") +
                                    (c.all_terms ? "_all_terms" : "");
                         });

// (b) Where every residual is zero the Gauss-Newton Hessian is the exact Hessian: the same model.
// At the estimate itself every odometry residual vanishes (the heading-preservation and scale
// terms are linear, so their residuals drop no curvature); the speed is constant (no stop), and
// the map distance is linear (zero Hessian), so the map term drops nothing either.
// Dead reckoning's covariance, by hand: a known pose heading North, one step of 10 m at scale 1.1.
// The step adds its length variance along the track (North), its lateral variance across it
// (East), its heading variance; the pose's heading variance v moves the new position across the
// track by (scale * length)^2 * v, correlated with the heading.
TEST(PropagateStep, AddsTheStepNoiseAndCarriesTheHeadingAcrossTheTrack) {
    ModelConfig m;
    PoseState a;
    a.yaw_rad = M_PI / 2.0;
    StepObservation o;
    o.length_m = 10.0;
    o.dt_s = 1.0;
    o.dheading_rad = 0.02;
    const StepNoise n = StepNoiseOf(m, o);
    PoseMatrix sigma_a = PoseMatrix::Zero();
    sigma_a(3, 3) = 1e-4;
    const PoseMatrix b = PropagateStep(sigma_a, a, o, 1.1, false, m);
    const double across = 11.0 * 11.0 * 1e-4;
    EXPECT_NEAR(b(0, 0), n.lateral_m * n.lateral_m + across, 1e-12);  // East: across the track
    EXPECT_NEAR(b(1, 1), n.length_m * n.length_m, 1e-12);             // North: along it
    EXPECT_NEAR(b(0, 1), 0.0, 1e-12);
    EXPECT_NEAR(b(2, 2), n.height_m * n.height_m, 1e-12);
    EXPECT_NEAR(b(3, 3), 1e-4 + n.heading_rad * n.heading_rad, 1e-12);
    EXPECT_NEAR(b(0, 3), -11.0 * 1e-4, 1e-12);  // d East / d yaw = -len sin(yaw)
    EXPECT_NEAR(b(3, 0), b(0, 3), 0.0);
    EXPECT_EQ(PropagateStep(sigma_a, a, o, 1.1, true, m)(2, 2), 0.0) << "fixed height";
    const PoseMatrix back = ToPoseMatrix(ToPoseCovariance(b));
    EXPECT_NEAR((back - b).norm(), 0.0, 1e-15);
}

TEST(GaussNewtonHessian, EqualsTheExactHessianAtZeroResiduals) {
    for (bool fix_height : {true, false}) {
        for (bool all_terms : {false, true}) {
            SCOPED_TRACE(std::string(fix_height ? "planar" : "free height") +
                         (all_terms ? ", all terms" : ""));
            ModelConfig model;
            model.scale_segment_m = 20.0;
            model.map_giveup_m = 1000.0;  // the plane's distance reaches tens of metres
            if (all_terms) model.step_robust_k = 3.0, model.accel_sigma_mps2 = 2.0;
            const PlanarTrajectory truth = Curve(30, 0.04, false);
            const TraversableField field = LinearField(truth, fix_height);
            TrajectoryState s = StateFrom(truth, model, fix_height);
            for (std::size_t first : {std::size_t(1), std::size_t(9)}) {
                const std::size_t n = s.poses.size();
                const WindowProblem p(s, &field, model, first, n - 1,
                                      std::vector<std::uint8_t>(n - first, 0));
                std::vector<double> x(p.NumVariables());
                p.InitialPoint(x.data());
                const Eigen::MatrixXd gn = DenseGaussNewtonHessian(p, x.data());
                std::vector<double> values(p.HessianStructure().size());
                p.HessianValues(x.data(), 1.0, nullptr, values.data());
                Eigen::MatrixXd exact = Eigen::MatrixXd::Zero(p.NumVariables(), p.NumVariables());
                for (std::size_t k = 0; k < values.size(); ++k) {
                    const auto [r, c] = p.HessianStructure()[k];
                    exact(r, c) += values[k];
                    if (r != c) exact(c, r) += values[k];
                }
                // The field's samples are floats: |d| up to ~50 m rounds by ~3e-6 m, which gives
                // the interpolated plane a Hessian of ~1e-6 / m, times rho'(d) <= 12 / m^2.
                const double scale = exact.cwiseAbs().maxCoeff();
                EXPECT_LE((gn - exact).cwiseAbs().maxCoeff(), 1e-10 * scale) << "first " << first;
                // And the map terms are there: the field's gradient enters.
                std::vector<LinearisedTerm> terms;
                p.LineariseTerms(x.data(), terms);
                const auto maps = std::count_if(terms.begin(), terms.end(), [](const auto& t) {
                    return t.family == TermFamily::kMapDistance && t.information > 0.0;
                });
                EXPECT_EQ(std::size_t(maps), n - first);
            }
        }
    }
}

/// A map term whose Jacobian is the field's gradient: |grad d| ~ 1 more than 2 cells (1 m) from
/// the centre line (within, the probes' unit normal stands in for it).
bool OutsideBand(const LinearisedTerm& t) {
    double norm2 = 0.0;
    for (int a = 0; a < t.size; ++a) norm2 += t.jacobian[a] * t.jacobian[a];
    return std::sqrt(norm2) >= 0.99 && t.residual > 1.2;
}

// The terms' residuals and Jacobians: central differences of the residual each term reports
// (map terms outside the centre line's rounding band, where the Jacobian is grad d).
TEST(GaussNewtonHessian, TermJacobiansMatchCentralDifferencesOfTheirResiduals) {
    for (bool fix_height : {true, false}) {
        ModelConfig model;
        model.scale_segment_m = 20.0;
        model.step_robust_k = 3.0, model.accel_sigma_mps2 = 2.0;
        const PlanarTrajectory truth = Curve(20);
        const TraversableField field = RoadAlong(truth);
        TrajectoryState s = StateFrom(truth, model, fix_height);
        ShiftLeft(s, 1.5);  // most map terms outside the centre line's rounding band
        Perturb(s, 21u);
        const WindowProblem p(s, &field, model, 4, 19, std::vector<std::uint8_t>(16, 0));
        std::vector<double> x(p.NumVariables());
        p.InitialPoint(x.data());
        std::vector<LinearisedTerm> terms;
        p.LineariseTerms(x.data(), terms);
        const auto exact_maps = std::count_if(terms.begin(), terms.end(), [](const auto& t) {
            return t.family == TermFamily::kMapDistance && OutsideBand(t);
        });
        EXPECT_GE(exact_maps, 10);
        const double h = 1e-6;
        for (int v = 0; v < p.NumVariables(); ++v) {
            std::vector<double> xp = x, xm = x;
            xp[v] += h, xm[v] -= h;
            std::vector<LinearisedTerm> tp, tm;
            p.LineariseTerms(xp.data(), tp);
            p.LineariseTerms(xm.data(), tm);
            ASSERT_EQ(tp.size(), terms.size());
            ASSERT_EQ(tm.size(), terms.size());
            for (std::size_t k = 0; k < terms.size(); ++k) {
                const LinearisedTerm& t = terms[k];
                if (t.family == TermFamily::kMapDistance && !OutsideBand(t)) continue;
                double analytic = 0.0;
                for (int a = 0; a < t.size; ++a) analytic += t.var[a] == v ? t.jacobian[a] : 0.0;
                const double numeric = (tp[k].residual - tm[k].residual) / (2.0 * h);
                EXPECT_NEAR(analytic, numeric, 1e-6 * (1.0 + std::abs(numeric)))
                    << ToString(t.family) << " term " << k << ", variable " << v;
            }
        }
    }
}

// On a centre line the interpolated distance's gradient vanishes and turns; the map term's
// Jacobian is the road's unit normal there, and grad d a pose's lane width away.
TEST(GaussNewtonHessian, MapJacobianIsTheRoadNormalOnTheCentreLine) {
    ModelConfig model;
    const PlanarTrajectory truth = Curve(60, 0.0, false);  // 120 m straight at 0.3 rad
    const TraversableField field = RoadAlong(truth);
    const Eigen::Vector2d normal(-std::sin(0.3), std::cos(0.3));
    for (double offset_m : {0.0, 0.1, 0.3, 0.5, 1.5, -2.0}) {
        TrajectoryState s = StateFrom(truth, model, true);
        ShiftLeft(s, offset_m);
        const WindowProblem p(s, &field, model, 1, 59, std::vector<std::uint8_t>(59, 0));
        std::vector<double> x(p.NumVariables());
        p.InitialPoint(x.data());
        std::vector<LinearisedTerm> terms;
        p.LineariseTerms(x.data(), terms);
        std::size_t maps = 0;
        for (const LinearisedTerm& t : terms) {
            if (t.family != TermFamily::kMapDistance) continue;
            ++maps;
            ASSERT_EQ(t.size, 2) << "planar field: x and y";
            const Eigen::Vector2d j(t.jacobian[0], t.jacobian[1]);
            EXPECT_NEAR(std::abs(j.dot(normal)), 1.0, 1e-3) << "offset " << offset_m;
            EXPECT_NEAR(j.norm(), 1.0, 1e-3) << "offset " << offset_m;
        }
        EXPECT_EQ(maps, 59u);
    }
}

/// Along-track and cross-track variance of pose i against the direction `yaw`.
std::pair<double, double> AlongCross(const PoseCovariance& c, double yaw) {
    const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw)), n(-std::sin(yaw), std::cos(yaw));
    return {u.dot(c.xy_m2 * u), n.dot(c.xy_m2 * n)};
}

// (c) Dead reckoning: the uncertainty grows along the chain. A road along it bounds the
// cross-track uncertainty (the map term, sigma 2 m, seen by every pose), not the along-track one
// (a straight road says nothing about how far along it the platform is).
TEST(Covariance, DeadReckoningGrowsAndARoadBoundsTheCrossTrack) {
    ModelConfig model;
    const PlanarTrajectory truth = Curve(300, 0.0, false);  // 600 m straight
    const TraversableField field = RoadAlong(truth);
    const TrajectoryState s = StateFrom(truth, model, true);
    const CovarianceResult free = ComputeCovariance(s, nullptr, model);
    const CovarianceResult road = ComputeCovariance(s, &field, model);
    ASSERT_EQ(free.status, CovarianceStatus::kOk) << free.message;
    ASSERT_EQ(road.status, CovarianceStatus::kOk) << road.message;
    const double yaw = truth.yaw_rad[0];
    for (std::size_t i = 2; i < s.poses.size(); ++i) {
        EXPECT_GT(free.poses[i].xy_m2.trace(), free.poses[i - 1].xy_m2.trace()) << "pose " << i;
        EXPECT_GT(free.poses[i].yaw_rad2, free.poses[i - 1].yaw_rad2) << "pose " << i;
        EXPECT_GT(AlongCross(road.poses[i], yaw).first, AlongCross(road.poses[i - 1], yaw).first)
            << "pose " << i;
    }
    const auto [free_along, free_cross] = AlongCross(free.poses.back(), yaw);
    const auto [road_along, road_cross] = AlongCross(road.poses.back(), yaw);
    // Without the map the cross-track error of 600 m of heading random walk is metres.
    EXPECT_GT(free_cross, 4.0);
    double max_cross = 0.0;
    for (std::size_t i = 1; i < s.poses.size(); ++i) {
        max_cross = std::max(max_cross, AlongCross(road.poses[i], yaw).second);
    }
    // With it, no pose's cross-track variance exceeds one map observation's (2 m)^2.
    EXPECT_LT(max_cross, model.map_sigma_m * model.map_sigma_m);
    EXPECT_GT(road_cross, 0.0);
    EXPECT_LT(road_cross, 0.1 * free_cross);
    // Along the road the map adds (almost) nothing.
    EXPECT_GT(road_along, 0.9 * free_along);
}

// The map's offset along a street is one error, however many poses see it: with the offset
// process the cross-track variance changes by less than 10 % when the same drive is sampled
// twice as often, with independent map terms it falls by more than a quarter.
TEST(Covariance, TheMapOffsetDoesNotAverageAwayWithThePoseRate) {
    ModelConfig model;
    model.heading_bias_segment_s = 0.0;  // the two samplings last different times
    const PlanarTrajectory coarse = Curve(301, 0.0, false, 2.0), fine = Curve(601, 0.0, false, 1.0);
    const TraversableField field = RoadAlong(coarse);
    const Eigen::Vector2d normal(-std::sin(0.3), std::cos(0.3));
    auto middle_cross = [&](const PlanarTrajectory& t, double share) {
        CovarianceConfig cfg;
        cfg.map_offset_share = share;
        const CovarianceResult r = ComputeCovariance(StateFrom(t, model, true), &field, model, cfg);
        EXPECT_EQ(r.status, CovarianceStatus::kOk) << r.message;
        return normal.dot(r.poses[t.size() / 2].xy_m2 * normal);
    };
    // (The odometry's share changes too: its per-step sigmas do not scale with the step.)
    const double independent = middle_cross(fine, 0.0) / middle_cross(coarse, 0.0);
    EXPECT_LT(independent, 0.75);
    const double with_offset = middle_cross(fine, 0.5) / middle_cross(coarse, 0.5);
    EXPECT_NEAR(with_offset, 1.0, 0.1);
    // Over a 600 m straight the offset (share 0.5 of (2 m)^2, correlated over 100 m) averages
    // over ~3 independent stretches at most: the variance stays above 2 m^2 / 6.
    EXPECT_GT(middle_cross(coarse, 0.5), 2.0 / 6.0);
}

// The step length's slowly varying error (step_error_sd, correlation length c) adds, at a pose a
// path D from the known start along a straight road (which observes nothing along it), the
// variance of its integral: 2 sd^2 c D (1 - c / D (1 - exp(-D / c))) for a Gauss-Markov process,
// 28.0 m^2 for sd 0.1, c 10 m, D 150 m. Independent step errors would add their own variance
// only, which averages away.
TEST(Covariance, TheStepErrorAddsTheVarianceOfItsIntegralAlongTheTrack) {
    ModelConfig model;
    const PlanarTrajectory truth = Curve(151, 0.0, false, 2.0);  // 300 m straight, 2 m steps
    const TraversableField field = RoadAlong(truth);
    const TrajectoryState s = StateFrom(truth, model, true);
    CovarianceConfig cfg;
    cfg.map_offset_share = 0.0;
    cfg.family_variance_components = false;
    const CovarianceResult without = ComputeCovariance(s, &field, model, cfg);
    cfg.step_error_sd = 0.1;
    cfg.step_error_correlation_m = 10.0;
    const CovarianceResult with = ComputeCovariance(s, &field, model, cfg);
    ASSERT_EQ(without.status, CovarianceStatus::kOk) << without.message;
    ASSERT_EQ(with.status, CovarianceStatus::kOk) << with.message;
    const std::size_t middle = 75;  // 150 m from the start
    const auto [along0, cross0] = AlongCross(without.poses[middle], truth.yaw_rad[middle]);
    const auto [along1, cross1] = AlongCross(with.poses[middle], truth.yaw_rad[middle]);
    const double c = 10.0, d = 150.0;
    const double expected = 2.0 * 0.01 * c * d * (1.0 - c / d * (1.0 - std::exp(-d / c)));
    EXPECT_NEAR(along1 - along0, expected, 0.1 * expected);
    EXPECT_NEAR(cross1, cross0, 0.01 * cross0);  // the road holds the cross-track as before
}

// A straight through junctions: where the car passes a crossing street in its lane, 1.5 m beside
// the centre line, that street's line is the nearer one and grad d points along the travel. The
// map says nothing there about how far along the road the car is, so the along-track variance
// at the end of a 600 m straight with a crossing street every 100 m is that of the same straight
// without them (within 10 %); read along grad d, the junctions would fix it to a fraction.
TEST(Covariance, JunctionsPassedStraightThroughDoNotFixTheAlongTrack) {
    ModelConfig model;
    const PlanarTrajectory truth = Curve(301, 0.0, false);  // 600 m straight at 0.3 rad
    const Eigen::Vector2d along(std::cos(0.3), std::sin(0.3)),
        across(-std::sin(0.3), std::cos(0.3));
    RoadNetwork plain, crossed;
    plain.roads.push_back({1,
                           "residential",
                           3.5,
                           {truth.p_en.front() - 20.0 * along, truth.p_en.back() + 20.0 * along}});
    crossed = plain;
    for (int k = 1; k <= 5; ++k) {
        const Eigen::Vector2d c = truth.p_en.front() + 100.0 * k * along;
        crossed.roads.push_back(
            {1 + k, "residential", 3.5, {c - 25.0 * across, c + 25.0 * across}});
    }
    Eigen::AlignedBox2d box;
    for (const auto& p : truth.p_en) box.extend(p);
    RoadFieldConfig road_cfg;
    road_cfg.margin_m = 30.0;
    road_cfg.truncation_m = 20.0;
    const TraversableField straight = RasteriseRoads(plain, box, road_cfg);
    const TraversableField junctions = RasteriseRoads(crossed, box, road_cfg);
    TrajectoryState s = StateFrom(truth, model, true);
    ShiftLeft(s, 1.5);
    auto end_along = [&](const TraversableField& field, bool across_travel) {
        CovarianceConfig cfg;
        cfg.map_across_travel = across_travel;
        const CovarianceResult r = ComputeCovariance(s, &field, model, cfg);
        EXPECT_EQ(r.status, CovarianceStatus::kOk) << r.message;
        return AlongCross(r.poses.back(), 0.3).first;
    };
    const double without = end_along(straight, true);
    EXPECT_NEAR(end_along(junctions, true), without, 0.1 * without);
    EXPECT_LT(end_along(junctions, false), 0.5 * end_along(straight, false));
}

TEST(Covariance, RedundancyNumbersAddUpAndTheVarianceFactorScales) {
    ModelConfig model;
    model.scale_segment_m = 20.0;
    const PlanarTrajectory truth = Curve(40);
    const TraversableField field = RoadAlong(truth);
    TrajectoryState s = StateFrom(truth, model, false);
    Perturb(s, 31u);
    const CovarianceResult raw = ComputeCovariance(s, &field, model, CovarianceConfig{});
    CovarianceConfig scaled_cfg;
    scaled_cfg.apply_variance_factor = true;
    const CovarianceResult scaled = ComputeCovariance(s, &field, model, scaled_cfg);
    ASSERT_EQ(raw.status, CovarianceStatus::kOk) << raw.message;
    ASSERT_EQ(scaled.status, CovarianceStatus::kOk) << scaled.message;
    EXPECT_FALSE(raw.variance_factor_applied);
    EXPECT_TRUE(scaled.variance_factor_applied);
    EXPECT_GT(raw.families[int(TermFamily::kMapOffset)].terms, 0u);
    double redundancy = 0.0, chi2 = 0.0;
    std::size_t terms = 0;
    for (const FamilyStatistics& f : raw.families) {
        redundancy += f.redundancy;
        chi2 += f.chi2;
        terms += f.terms;
        EXPECT_GE(f.redundancy, -1e-9);
        EXPECT_LE(f.redundancy, double(f.terms) + 1e-9);
    }
    EXPECT_EQ(terms, raw.observations);
    // sum of the redundancy numbers = trace(I - H^-1 H) summed = m - n.
    const double m_minus_n = double(raw.observations) - double(raw.unknowns);
    EXPECT_NEAR(redundancy, m_minus_n, 1e-6 * m_minus_n);
    EXPECT_NEAR(raw.variance_factor, chi2 / m_minus_n, 1e-12 * raw.variance_factor);
    EXPECT_GT(raw.variance_factor, 0.0);
    EXPECT_EQ(raw.variance_factor, scaled.variance_factor);
    for (std::size_t i = 1; i < s.poses.size(); ++i) {
        EXPECT_NEAR(scaled.poses[i].xy_m2(0, 1), raw.variance_factor * raw.poses[i].xy_m2(0, 1),
                    1e-12 * std::abs(scaled.poses[i].xy_m2.trace()));
        EXPECT_NEAR(scaled.poses[i].z_m2, raw.variance_factor * raw.poses[i].z_m2,
                    1e-12 * scaled.poses[i].z_m2);
        EXPECT_NEAR(scaled.poses[i].yaw_rad2, raw.variance_factor * raw.poses[i].yaw_rad2,
                    1e-12 * scaled.poses[i].yaw_rad2);
    }
}

// The batch corrector reports the covariance of its solution (CorrectionResult::covariance).
TEST(Covariance, TheCorrectorReportsIt) {
    const PlanarTrajectory truth = Curve(40);
    const TraversableField field = RoadAlong(truth);
    PlanarTrajectory estimate = Curve(40, 0.044, true, 2.04);  // heading and scale drift
    CorrectorConfig cfg;
    cfg.model.scale_segment_m = 20.0;
    const CorrectionResult r = CorrectTrajectory(estimate, &field, cfg);
    ASSERT_TRUE(Usable(r.status)) << r.message;
    ASSERT_EQ(r.covariance.status, CovarianceStatus::kOk) << r.covariance.message;
    ASSERT_EQ(r.covariance.poses.size(), estimate.size());
    EXPECT_GE(r.covariance_s, 0.0);
    for (std::size_t i = 1; i < estimate.size(); ++i) {
        EXPECT_GT(r.covariance.poses[i].xy_m2.determinant(), 0.0) << "pose " << i;
        EXPECT_GT(r.covariance.poses[i].yaw_rad2, 0.0) << "pose " << i;
    }
    cfg.compute_covariance = false;
    EXPECT_EQ(CorrectTrajectory(estimate, &field, cfg).covariance.status,
              CovarianceStatus::kNotComputed);
}

/// A street grid's drive: 2 m steps 0.5 s apart, turning 90 degrees (over 10 steps) left and
/// right in turn every 60 steps.
PlanarTrajectory Zigzag(int n) {
    PlanarTrajectory t;
    Eigen::Vector2d p(0.0, 0.0);
    double yaw = 0.0;
    for (int i = 0; i < n; ++i) {
        if (i > 0) {
            p += 2.0 * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
            const int phase = i % 120;
            if (phase < 10) yaw += 0.05 * kPi;
            if (phase >= 60 && phase < 70) yaw -= 0.05 * kPi;
        }
        t.t_s.push_back(0.5 * i);
        t.p_en.push_back(p);
        t.up_m.push_back(1.0);
        t.yaw_rad.push_back(yaw);
    }
    return t;
}

// A drive longer than block_poses is computed block by block, each from its terms and a tenth
// of a block on either side, its past a prior: on a street grid, whose turns observe the
// along-track position, the blocks' marginals are the whole drive's to within 10 %, and where
// they differ (the last poses of a block, whose margin ends sooner than the drive) larger,
// never smaller by more than 2 %.
TEST(Covariance, ALongDriveInBlocksHasTheWholeDrivesMarginals) {
    ModelConfig model;
    model.scale_segment_m = 50.0;  // a margin spans several segments, as a 50000-pose block's does
    const PlanarTrajectory truth = Zigzag(3001);  // 6 km, 50 turns
    const TraversableField field = RoadAlong(truth);
    const TrajectoryState s = StateFrom(truth, model, true);
    CovarianceConfig block_cfg;
    block_cfg.block_poses = 1000;
    const CovarianceResult whole = ComputeCovariance(s, &field, model);
    const CovarianceResult blocks = ComputeCovariance(s, &field, model, block_cfg);
    ASSERT_EQ(whole.status, CovarianceStatus::kOk) << whole.message;
    ASSERT_EQ(blocks.status, CovarianceStatus::kOk) << blocks.message;
    // Three blocks, each but the last with a run for the next one's past.
    EXPECT_EQ(blocks.message.rfind("5 runs over blocks of at most 1000 poses", 0), 0u)
        << blocks.message;
    ASSERT_EQ(blocks.poses.size(), s.poses.size());
    double lowest = 1.0, highest = 1.0;
    for (std::size_t i = 1; i < s.poses.size(); ++i) {
        ASSERT_GT(blocks.poses[i].xy_m2.determinant(), 0.0) << "pose " << i;
        for (const double ratio : {blocks.poses[i].xy_m2.trace() / whole.poses[i].xy_m2.trace(),
                                   blocks.poses[i].yaw_rad2 / whole.poses[i].yaw_rad2}) {
            lowest = std::min(lowest, ratio);
            highest = std::max(highest, ratio);
        }
    }
    EXPECT_GT(lowest, 0.98);
    EXPECT_LT(highest, 1.1);
    EXPECT_GT(highest, 1.0) << "the blocks were not computed apart";
    // The statistics add up over the runs, their margins counted in each run that holds them.
    EXPECT_GT(blocks.observations, whole.observations);
    // The mean scale needs the whole drive's unknowns at once.
    EXPECT_GT(whole.mean_scale_sd, 0.0);
    EXPECT_TRUE(std::isnan(blocks.mean_scale_sd));
}

// A drive longer than refine_block_poses has its final solve in overlapping blocks: the same
// correction to centimetres on a street grid, the report naming the blocks; and its covariance
// (covariance.block_poses) in blocks too.
TEST(Covariance, ALongDrivesFinalSolveInBlocksIsTheWholeSolve) {
    const PlanarTrajectory truth = Zigzag(1201);
    const TraversableField field = RoadAlong(truth);
    PlanarTrajectory estimate = truth;  // a heading drift of 0.5 mrad a step, steps 2 % long
    for (std::size_t i = 1; i < estimate.size(); ++i) {
        const Eigen::Vector2d step = truth.p_en[i] - truth.p_en[i - 1];
        const Eigen::Rotation2D<double> turn(0.0005 * double(i));
        estimate.p_en[i] = estimate.p_en[i - 1] + 1.02 * (turn * step);
        estimate.yaw_rad[i] = truth.yaw_rad[i] + 0.0005 * double(i);
    }
    CorrectorConfig whole_cfg, block_cfg;
    block_cfg.refine_block_poses = 400;
    block_cfg.covariance.block_poses = 500;
    const CorrectionResult whole = CorrectTrajectory(estimate, &field, whole_cfg);
    const CorrectionResult blocks = CorrectTrajectory(estimate, &field, block_cfg);
    ASSERT_TRUE(Usable(whole.status)) << whole.message;
    ASSERT_TRUE(Usable(blocks.status)) << blocks.message;
    EXPECT_EQ(blocks.refine_report.message.rfind("4 blocks of at most 400 poses, the last: ", 0),
              0u)
        << blocks.refine_report.message;
    EXPECT_EQ(whole.refine_report.message.find("blocks"), std::string::npos);
    ASSERT_EQ(blocks.corrected.size(), whole.corrected.size());
    double largest = 0.0;
    for (std::size_t i = 0; i < whole.corrected.size(); ++i) {
        largest = std::max(largest, (blocks.corrected.p_en[i] - whole.corrected.p_en[i]).norm());
    }
    EXPECT_LT(largest, 0.05);
    EXPECT_GT(largest, 0.0) << "the blocks were not solved apart";
    ASSERT_EQ(blocks.covariance.status, CovarianceStatus::kOk) << blocks.covariance.message;
    EXPECT_NE(blocks.covariance.message.find("runs over blocks"), std::string::npos);
}

// Where the solve holds the heights (planar), the corrected trajectory's heights are the
// estimate's at grades of at most max_grade: an estimate climbing 30 % along a level road comes
// back climbing 10 %, one climbing 2.5 % as it was, and the horizontal correction is the same.
TEST(Heights, ARoadCorrectionBoundsTheGradeOfItsHeights) {
    const PlanarTrajectory truth = Curve(200, 0.01, false, 2.0);
    const TraversableField field = RoadAlong(truth);
    PlanarTrajectory gentle = truth;  // a heading drift of 0.5 mrad a step, steps 2 % long
    for (std::size_t i = 1; i < gentle.size(); ++i) {
        const Eigen::Vector2d step = truth.p_en[i] - truth.p_en[i - 1];
        gentle.p_en[i] = gentle.p_en[i - 1] + 1.02 * (Eigen::Rotation2D<double>(0.0005 * i) * step);
        gentle.yaw_rad[i] = truth.yaw_rad[i] + 0.0005 * double(i);
    }
    PlanarTrajectory steep = gentle;
    for (std::size_t i = 0; i < steep.size(); ++i) steep.up_m[i] = 0.6 * double(i);  // 30 %
    CorrectorConfig cfg, unbounded;
    unbounded.model.max_grade = 0.0;
    const CorrectionResult bounded = CorrectTrajectory(steep, &field, cfg);
    const CorrectionResult as_estimated = CorrectTrajectory(steep, &field, unbounded);
    ASSERT_TRUE(Usable(bounded.status)) << bounded.message;
    ASSERT_TRUE(Usable(as_estimated.status)) << as_estimated.message;
    ASSERT_FALSE(bounded.input_kept);
    EXPECT_GT(bounded.grades.stretches, 10u);
    EXPECT_EQ(bounded.grades.limited, bounded.grades.stretches);
    EXPECT_EQ(as_estimated.grades.limited, 0u);
    EXPECT_EQ(as_estimated.corrected.up_m, steep.up_m);
    const double run_m = PathLength(bounded.corrected);
    EXPECT_NEAR(bounded.corrected.up_m.back(), 0.10 * run_m, 1e-6 * run_m);
    for (std::size_t i = 0; i < steep.size(); ++i) {
        EXPECT_EQ(bounded.corrected.p_en[i], as_estimated.corrected.p_en[i]) << "pose " << i;
    }
    const CorrectionResult climb = CorrectTrajectory(gentle, &field, cfg);  // climbs 2.5 %
    ASSERT_TRUE(Usable(climb.status)) << climb.message;
    ASSERT_FALSE(climb.input_kept);
    EXPECT_GT(climb.grades.stretches, 10u);
    EXPECT_EQ(climb.grades.limited, 0u);
    EXPECT_EQ(climb.corrected.up_m, gentle.up_m);
}

TEST(Covariance, BadStatesAreAStatusNotGarbage) {
    ModelConfig model;
    TrajectoryState s = StateFrom(Curve(10), model, true);
    s.poses[4].p.x() = std::nan("");
    const CovarianceResult nan = ComputeCovariance(s, nullptr, model);
    EXPECT_EQ(nan.status, CovarianceStatus::kNotPositiveDefinite) << nan.message;
    EXPECT_TRUE(nan.poses.empty());
    EXPECT_FALSE(nan.message.empty());

    TrajectoryState one = StateFrom(Curve(2), model, true);
    one.poses.resize(1), one.obs.resize(1), one.scale_segment.resize(1);
    const CovarianceResult bad = ComputeCovariance(one, nullptr, model);
    EXPECT_EQ(bad.status, CovarianceStatus::kBadInput);
    EXPECT_FALSE(bad.message.empty());
}

}  // namespace
}  // namespace driftcorr
