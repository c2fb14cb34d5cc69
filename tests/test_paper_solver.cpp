// Tests of the paper's reference solver (optim/src/paper_solver.cpp) and of the bilinear field
// query it uses (InterpolatedField::QueryBilinear), on a straight road whose distances are known:
// the centre line is y = 0 from x = 0 to 300 m, so d(x, y) = |y| along it.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "driftcorr/mapping/road_network.h"
#include "driftcorr/optim/paper_solver.h"

namespace driftcorr {
namespace {

TraversableField StraightRoadField(double half_width_m) {
    RoadNetwork net;
    net.roads.push_back(RoadPolyline{1, "residential", half_width_m, {{0.0, 0.0}, {300.0, 0.0}}});
    RoadFieldConfig cfg;
    cfg.resolution_m = 0.25;
    cfg.margin_m = 30.0;
    cfg.truncation_m = 20.0;
    return RasteriseRoads(
        net, Eigen::AlignedBox2d(Eigen::Vector2d(0, -10), Eigen::Vector2d(300, 10)), cfg);
}

double MeanMapDistance(const PlanarTrajectory& t, const TraversableField& field) {
    double sum = 0.0;
    for (const auto& p : t.p_en) {
        const auto s = field.QueryCentreBilinear(Eigen::Vector3d(p.x(), p.y(), 0.0));
        EXPECT_TRUE(s.has_value());
        sum += s ? s->value : 0.0;
    }
    return sum / double(t.size());
}

// A drive along the road at 1 m per step (10 Hz), estimated with a constant heading error of
// 0.01 rad: the estimate leaves the centre line linearly, 1.5 m after 150 m, still on the road.
PlanarTrajectory DriftedEstimate(std::size_t poses) {
    PlanarTrajectory t;
    const double yaw_err = 0.01;
    for (std::size_t i = 0; i < poses; ++i) {
        const double s = 10.0 + double(i);
        t.t_s.push_back(0.1 * double(i));
        t.p_en.emplace_back(10.0 + (s - 10.0) * std::cos(yaw_err), (s - 10.0) * std::sin(yaw_err));
        t.up_m.push_back(0.0);
        t.yaw_rad.push_back(yaw_err);
    }
    return t;
}

TEST(QueryBilinear, StraightRoadDistanceAndGradient) {
    const TraversableField field = StraightRoadField(4.0);
    for (double x : {20.1, 77.7, 150.3}) {
        for (double y : {-3.3, -1.1, 0.6, 2.9, 5.4}) {
            const auto q = field.QueryCentreBilinear(Eigen::Vector3d(x, y, 0.0));
            ASSERT_TRUE(q.has_value());
            // Linear interpolation of |y| is exact in any cell that does not straddle y = 0.
            EXPECT_NEAR(q->value, std::abs(y), 1e-3) << x << ", " << y;
            EXPECT_NEAR(q->gradient.x(), 0.0, 1e-3);
            EXPECT_NEAR(q->gradient.y(), y > 0 ? 1.0 : -1.0, 1e-3);
            EXPECT_TRUE(q->hessian.isZero());
            // Gradient against central differences inside the cell (h well below a cell).
            const double h = 1e-4;
            const auto xp = field.QueryCentreBilinear(Eigen::Vector3d(x + h, y, 0.0));
            const auto xm = field.QueryCentreBilinear(Eigen::Vector3d(x - h, y, 0.0));
            const auto yp = field.QueryCentreBilinear(Eigen::Vector3d(x, y + h, 0.0));
            const auto ym = field.QueryCentreBilinear(Eigen::Vector3d(x, y - h, 0.0));
            EXPECT_NEAR(q->gradient.x(), (xp->value - xm->value) / (2 * h), 1e-6);
            EXPECT_NEAR(q->gradient.y(), (yp->value - ym->value) / (2 * h), 1e-6);
        }
    }
    // Outside the grid: no sample.
    EXPECT_FALSE(field.QueryCentreBilinear(Eigen::Vector3d(-1e4, 0.0, 0.0)).has_value());
    EXPECT_FALSE(InterpolatedField().QueryBilinear(Eigen::Vector3d::Zero()).has_value());
}

TEST(PaperSolver, DefaultsAreValidAndUnstableSettingsAreRejected) {
    PaperSolverConfig cfg;
    EXPECT_EQ(cfg.Validate(), "");
    EXPECT_EQ(cfg.learning_rate, 0.01);
    cfg.step_sigma_m = 0.05;  // learning_rate / sigma^2 = 4 >= 2: the descent would diverge
    EXPECT_NE(cfg.Validate().find("step_sigma_m"), std::string::npos);
    cfg = PaperSolverConfig{};
    cfg.min_step_m = 0.1;
    EXPECT_NE(cfg.Validate().find("min_step_m"), std::string::npos);
    cfg = PaperSolverConfig{};
    cfg.map_weight = 1.5;
    EXPECT_NE(cfg.Validate().find("map_weight"), std::string::npos);
}

TEST(PaperSolver, ReducesMapDistanceOnADriftedStraightDrive) {
    const TraversableField field = StraightRoadField(4.0);
    const PlanarTrajectory est = DriftedEstimate(150);
    const PaperSolverConfig cfg;
    const CorrectionResult r = CorrectWithPaperMethod(est, &field, cfg);
    ASSERT_EQ(r.status, SolveStatus::kSuccess) << r.message;
    ASSERT_EQ(r.corrected.size(), est.size());
    EXPECT_EQ(r.corrected.p_en[0], est.p_en[0]);  // pose 0 is known and fixed
    EXPECT_EQ(r.iterations, 149 * cfg.iterations_per_epoch);
    const double before = MeanMapDistance(est, field);
    const double after = MeanMapDistance(r.corrected, field);
    EXPECT_NEAR(before, 0.745, 0.01);  // mean of 0.01 * s over s = 0..149 m
    // Stated tolerance: at least a quarter less mean distance to the centre line.
    EXPECT_LT(after, 0.75 * before) << "before " << before << " m, after " << after << " m";
    // Deterministic: the same input gives the same bytes.
    const CorrectionResult again = CorrectWithPaperMethod(est, &field, cfg);
    for (std::size_t i = 0; i < est.size(); ++i)
        ASSERT_EQ(again.corrected.p_en[i], r.corrected.p_en[i]);
}

TEST(PaperSolver, WithoutMapReproducesTheEstimate) {
    // Every term is zero at the dead-reckoned start when there is no map: the estimate comes back.
    const PlanarTrajectory est = DriftedEstimate(50);
    const CorrectionResult r = CorrectWithPaperMethod(est, nullptr, PaperSolverConfig{});
    ASSERT_EQ(r.status, SolveStatus::kSuccess);
    for (std::size_t i = 0; i < est.size(); ++i) {
        EXPECT_NEAR((r.corrected.p_en[i] - est.p_en[i]).norm(), 0.0, 1e-9) << "pose " << i;
    }
}

}  // namespace
}  // namespace driftcorr
