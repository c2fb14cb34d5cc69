// Tests of the distance fields: the exact EDT and signed distance (mapping/src/grid.cpp), the
// cubic B-spline field (mapping/src/interpolated_field.cpp), the traversable field and road
// rasterisation (mapping/src/traversable_field.cpp, road_network.cpp), and the road class table.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <ostream>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "driftcorr/mapping/grid.h"
#include "driftcorr/mapping/interpolated_field.h"
#include "driftcorr/mapping/road_network.h"
#include "driftcorr/mapping/traversable_field.h"

namespace driftcorr {
namespace {

// ---- Exact Euclidean distance transform --------------------------------------------------------

struct EdtCase {
    int nx, ny, nz;
    double resolution_m;
    double density;  ///< share of feature samples
    unsigned seed;
};

void PrintTo(const EdtCase& c, std::ostream* os) {
    *os << c.nx << "x" << c.ny << "x" << c.nz << " at " << c.resolution_m << " m, density "
        << c.density << ", seed " << c.seed;
}

std::string CaseName(const ::testing::TestParamInfo<EdtCase>& param_info) {
    const EdtCase& c = param_info.param;
    return std::to_string(c.nx) + "x" + std::to_string(c.ny) + "x" + std::to_string(c.nz) +
           "_seed" + std::to_string(c.seed);
}

GridSpec Spec(const EdtCase& c) {
    GridSpec s;
    s.origin_m = Eigen::Vector3d(-3.0, 1.0, 0.5);
    s.resolution_m = c.resolution_m;
    s.nx = c.nx, s.ny = c.ny, s.nz = c.nz;
    return s;
}

std::vector<std::uint8_t> RandomMask(const GridSpec& s, double density, unsigned seed) {
    std::mt19937 rng(seed);
    std::bernoulli_distribution b(density);
    std::vector<std::uint8_t> m(s.size());
    for (auto& v : m) v = b(rng) ? 1 : 0;
    return m;
}

/// Brute force: the distance from each sample to the nearest sample with mask == 1.
std::vector<double> BruteForceDistance(const GridSpec& s, const std::vector<std::uint8_t>& mask) {
    std::vector<double> d(s.size(), std::numeric_limits<double>::infinity());
    for (int k = 0; k < s.nz; ++k)
        for (int j = 0; j < s.ny; ++j)
            for (int i = 0; i < s.nx; ++i)
                for (int c = 0; c < s.nz; ++c)
                    for (int b = 0; b < s.ny; ++b)
                        for (int a = 0; a < s.nx; ++a) {
                            if (!mask[s.Index(a, b, c)]) continue;
                            const double r = (s.Position(i, j, k) - s.Position(a, b, c)).norm();
                            double& out = d[s.Index(i, j, k)];
                            out = std::min(out, r);
                        }
    return d;
}

class EdtTest : public ::testing::TestWithParam<EdtCase> {};

TEST_P(EdtTest, EqualsBruteForce) {
    const EdtCase c = GetParam();
    const GridSpec s = Spec(c);
    const std::vector<std::uint8_t> mask = RandomMask(s, c.density, c.seed);
    const std::vector<float> edt = EuclideanDistanceTransform(s, mask);
    const std::vector<double> ref = BruteForceDistance(s, mask);
    ASSERT_EQ(edt.size(), s.size());
    for (std::size_t n = 0; n < s.size(); ++n) {
        // float storage: relative 1e-6 of the distance.
        ASSERT_NEAR(edt[n], ref[n], 1e-6 * (1.0 + ref[n])) << "sample " << n;
    }
}

TEST_P(EdtTest, SignedDistanceMatchesItsDefinition) {
    const EdtCase c = GetParam();
    const GridSpec s = Spec(c);
    std::vector<std::uint8_t> inside = RandomMask(s, 0.5, c.seed + 1);
    const std::vector<float> sdt = SignedDistanceTransform(s, inside);
    std::vector<std::uint8_t> outside(inside.size());
    for (std::size_t n = 0; n < inside.size(); ++n) outside[n] = !inside[n];
    const std::vector<double> to_in = BruteForceDistance(s, inside);
    const std::vector<double> to_out = BruteForceDistance(s, outside);
    const double half = 0.5 * s.resolution_m;
    for (std::size_t n = 0; n < s.size(); ++n) {
        const double expected = inside[n] ? -(to_out[n] - half) : to_in[n] - half;
        ASSERT_NEAR(sdt[n], expected, 1e-5 * (1.0 + std::abs(expected))) << "sample " << n;
        if (inside[n])
            ASSERT_LT(sdt[n], 0.0f);
        else
            ASSERT_GT(sdt[n], 0.0f);
    }
}

TEST_P(EdtTest, CapKeepsTheDistancesWithinIt) {
    const EdtCase c = GetParam();
    const GridSpec s = Spec(c);
    const std::vector<std::uint8_t> mask = RandomMask(s, c.density, c.seed);
    const std::vector<float> full = EuclideanDistanceTransform(s, mask);
    std::size_t dropped = 0;
    for (double cap_cells : {0.0, 1.0, 2.5, 6.0}) {
        const double cap = cap_cells * s.resolution_m;
        const std::vector<float> capped = EuclideanDistanceTransform(s, mask, cap);
        for (std::size_t n = 0; n < s.size(); ++n) {
            if (full[n] <= cap) {
                ASSERT_EQ(capped[n], full[n]) << "cap " << cap << ", sample " << n;
            } else {
                // Beyond the cap: the same number or more (up to +infinity), never less.
                ASSERT_GE(capped[n], full[n]) << "cap " << cap << ", sample " << n << ": "
                                              << capped[n] << " against " << full[n];
                dropped += capped[n] > full[n];
            }
        }
    }
    // The cap does leave features out (else this test could not tell it from no cap).
    if (c.density < 0.1) {
        EXPECT_GT(dropped, 0u);
    }
}

INSTANTIATE_TEST_SUITE_P(
    RandomMasks, EdtTest,
    ::testing::Values(EdtCase{37, 23, 1, 0.25, 0.03, 11u}, EdtCase{37, 23, 1, 1.0, 0.005, 12u},
                      EdtCase{37, 23, 1, 0.5, 0.3, 13u}, EdtCase{1, 29, 1, 0.5, 0.1, 14u},
                      EdtCase{11, 9, 7, 0.5, 0.02, 21u}, EdtCase{11, 9, 7, 0.2, 0.1, 22u}),
    CaseName);

TEST(SegmentRowSpan, HoldsEverySampleWithinReachAndIsTight) {
    std::mt19937 rng(5u);
    std::uniform_real_distribution<double> u(-10.0, 10.0), r(0.0, 4.0);
    for (int trial = 0; trial < 200; ++trial) {
        const Eigen::Vector2d a(u(rng), u(rng));
        // A quarter of the segments degenerate, axis-parallel or tiny.
        Eigen::Vector2d b(u(rng), u(rng));
        if (trial % 8 == 0) b = a;
        if (trial % 8 == 1) b.y() = a.y();
        if (trial % 8 == 2) b.x() = a.x();
        if (trial % 8 == 3) b = a + Eigen::Vector2d(1e-9, -1e-9);
        const double reach = r(rng);
        for (double y = -15.0; y <= 15.0; y += 0.37) {
            double lo = 0.0, hi = 0.0;
            const bool hit = SegmentRowSpan(a, b, reach, y, lo, hi);
            bool any = false;
            for (double x = -16.0; x <= 16.0; x += 0.05) {
                const double d = PointSegmentDistance(Eigen::Vector2d(x, y), a, b);
                if (d > reach) continue;
                any = true;
                ASSERT_TRUE(hit && x >= lo - 1e-9 && x <= hi + 1e-9)
                    << "trial " << trial << ", y " << y << ", x " << x << " within reach, span ["
                    << lo << ", " << hi << "]";
            }
            if (!hit) continue;
            // Tight: the span's ends lie on the capsule's boundary.
            EXPECT_NEAR(PointSegmentDistance(Eigen::Vector2d(lo, y), a, b), reach, 1e-6)
                << "trial " << trial << ", y " << y << (any ? "" : " (no sample inside)");
            EXPECT_NEAR(PointSegmentDistance(Eigen::Vector2d(hi, y), a, b), reach, 1e-6)
                << "trial " << trial << ", y " << y;
        }
    }
}

TEST(SegmentRowCells, HoldEverySampleWithinReach) {
    // A sub-grid placed at sample (di, dj) of a whole grid, as the road field's tiles are.
    GridSpec whole;
    whole.origin_m = Eigen::Vector3d(-12.3, -7.9, 0.0);
    whole.resolution_m = 0.5;
    whole.nx = 60, whole.ny = 50;
    const int di = 7, dj = 4;
    GridSpec sub = whole;
    sub.origin_m = whole.Position(di, dj);
    sub.nx = 40, sub.ny = 35;
    std::mt19937 rng(9u);
    std::uniform_real_distribution<double> u(-10.0, 12.0), r(0.0, 5.0);
    std::size_t within = 0;
    for (int trial = 0; trial < 100; ++trial) {
        const Eigen::Vector2d a(u(rng), u(rng));
        const Eigen::Vector2d b = trial % 5 == 0 ? a : Eigen::Vector2d(u(rng), u(rng));
        const double reach = r(rng);
        const CellBox box = SegmentCells(sub, a, b, reach);
        for (int j = 0; j < sub.ny; ++j) {
            int i0 = 0, i1 = -1;
            const bool any = j >= box.j0 && j <= box.j1 &&
                             SegmentRowCells(whole, di, dj, j, a, b, reach, box, i0, i1);
            for (int i = 0; i < sub.nx; ++i) {
                const Eigen::Vector2d p = whole.Position(i + di, j + dj).head<2>();
                if (PointSegmentDistance(p, a, b) > reach) continue;
                ++within;
                ASSERT_TRUE(any && i >= i0 && i <= i1)
                    << "trial " << trial << ", sample (" << i << ", " << j << ") within reach, "
                    << "row cells [" << i0 << ", " << i1 << "]";
            }
        }
    }
    EXPECT_GT(within, 1000u);
}

TEST(AssignLarge, FillsLikeAssignAtEverySize) {
    // Below and above the size from which huge pages are asked for, growing and shrinking.
    std::vector<float> v = {1.0f, 2.0f};
    for (std::size_t n : {std::size_t(3), std::size_t(5) << 20, std::size_t(100),
                          std::size_t(3) << 20, std::size_t(7) << 20}) {
        AssignLarge(v, n, 0.25f);
        ASSERT_EQ(v.size(), n);
        for (std::size_t i = 0; i < n; i += 4099)
            ASSERT_EQ(v[i], 0.25f) << "n " << n << ", i " << i;
        ASSERT_EQ(v.back(), 0.25f);
    }
    std::vector<std::uint8_t> m;
    AssignLarge(m, std::size_t(9) << 20, std::uint8_t(1));
    EXPECT_EQ(std::count(m.begin(), m.end(), std::uint8_t(1)), std::ptrdiff_t(9) << 20);
}

TEST(Edt, EmptyMaskGivesInfinity) {
    for (int nz : {1, 5}) {
        GridSpec s;
        s.nx = 13, s.ny = 8, s.nz = nz;
        const std::vector<float> d =
            EuclideanDistanceTransform(s, std::vector<std::uint8_t>(s.size(), 0));
        for (float v : d) ASSERT_TRUE(std::isinf(v) && v > 0) << "nz = " << nz;
    }
}

TEST(Edt, SingleFeatureGivesScaledDistance) {
    GridSpec s;
    s.resolution_m = 0.5;
    s.nx = 9, s.ny = 7;
    std::vector<std::uint8_t> m(s.size(), 0);
    m[s.Index(2, 3)] = 1;
    const std::vector<float> d = EuclideanDistanceTransform(s, m);
    EXPECT_FLOAT_EQ(d[s.Index(2, 3)], 0.0f);
    EXPECT_FLOAT_EQ(d[s.Index(5, 7 - 3)], 0.5f * std::sqrt(9.0f + 1.0f));
    EXPECT_FLOAT_EQ(d[s.Index(8, 3)], 3.0f);
}

// The strip-wise transform laid under exact distances gives the floats of the whole-grid
// transform followed by the merge, across strip boundaries (256 rows) and caps that reach over
// them.
TEST(Edt, MergedCappedTransformEqualsTransformThenMerge) {
    const float inf = std::numeric_limits<float>::infinity();
    std::size_t finite_transforms = 0, capped_out = 0;
    unsigned seed = 1;
    for (int ny : {1, 2, 255, 256, 257, 300, 700}) {
        for (double density : {0.0005, 0.004, 0.05}) {
            for (double cap : {0.5, 3.0, 20.0}) {
                GridSpec s;
                s.origin_m = Eigen::Vector3d(-3.0, 1.0, 0.0);
                s.resolution_m = 0.5;
                s.nx = 37, s.ny = ny;
                const std::vector<std::uint8_t> mask = RandomMask(s, density, ++seed);
                std::mt19937 rng(seed);
                std::uniform_real_distribution<float> value(-1.0f, 30.0f);
                std::bernoulli_distribution known(0.2);
                std::vector<float> exact(s.size());
                for (float& e : exact) e = known(rng) ? value(rng) : inf;
                const float offset = seed % 2 ? -0.25f : 0.0f, ceiling = 12.0f;
                const std::vector<float> edt = EuclideanDistanceTransform(s, mask, cap);
                std::vector<float> merged = exact;
                MergeCappedDistanceTransform(s, mask, cap, offset, ceiling, merged);
                for (std::size_t n = 0; n < s.size(); ++n) {
                    const float expected =
                        std::min(ceiling, exact[n] < inf ? exact[n] : edt[n] + offset);
                    ASSERT_EQ(std::memcmp(&merged[n], &expected, sizeof(float)), 0)
                        << "ny " << ny << ", density " << density << ", cap " << cap << ", sample "
                        << n << ": " << merged[n] << " against " << expected;
                    finite_transforms += exact[n] == inf && edt[n] < ceiling;
                    capped_out += exact[n] == inf && edt[n] == inf && density > 0.001;
                }
            }
        }
    }
    // Both cases occur: distances the transform gives and samples beyond the cap.
    EXPECT_GT(finite_transforms, 1000u);
    EXPECT_GT(capped_out, 1000u);
}

// ---- Cubic B-spline field -----------------------------------------------------------------

GridSpec FieldSpec(bool planar) {
    GridSpec s;
    s.origin_m = Eigen::Vector3d(-2.0, 3.0, -1.0);
    s.resolution_m = 0.5;
    s.nx = 24, s.ny = 18, s.nz = planar ? 1 : 12;
    return s;
}

template <typename F>
InterpolatedField Sampled(const GridSpec& s, F f) {
    std::vector<float> v(s.size());
    for (int k = 0; k < s.nz; ++k)
        for (int j = 0; j < s.ny; ++j)
            for (int i = 0; i < s.nx; ++i) v[s.Index(i, j, k)] = float(f(s.Position(i, j, k)));
    return InterpolatedField(s, std::move(v));
}

/// A random point at least `border` cells inside the grid.
Eigen::Vector3d RandomInterior(const GridSpec& s, std::mt19937& rng, double border) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Eigen::Vector3d g(border + (s.nx - 1 - 2 * border) * u(rng),
                      border + (s.ny - 1 - 2 * border) * u(rng),
                      s.planar() ? 0.0 : border + (s.nz - 1 - 2 * border) * u(rng));
    return s.origin_m + s.resolution_m * g;
}

class FieldTest : public ::testing::TestWithParam<bool> {};  // planar?

TEST_P(FieldTest, ReproducesLinearFunctionsExactly) {
    const GridSpec s = FieldSpec(GetParam());
    const Eigen::Vector3d a(0.7, -1.3, GetParam() ? 0.0 : 0.4);
    auto f = [&](const Eigen::Vector3d& p) { return 2.0 + a.dot(p); };
    const InterpolatedField field = Sampled(s, f);
    std::mt19937 rng(5u);
    for (int trial = 0; trial < 200; ++trial) {
        const Eigen::Vector3d p = RandomInterior(s, rng, 1.0);
        const auto q = field.Query(p);
        ASSERT_TRUE(q.has_value()) << p.transpose();
        // Samples are stored as float: exact up to float rounding of values of order 10.
        EXPECT_NEAR(q->value, f(p), 1e-5);
        EXPECT_LT((q->gradient - a).norm(), 1e-5);
        EXPECT_LT(q->hessian.cwiseAbs().maxCoeff(), 1e-4);
    }
}

TEST_P(FieldTest, DerivativesMatchCentralDifferences) {
    const GridSpec s = FieldSpec(GetParam());
    auto f = [](const Eigen::Vector3d& p) {
        return 3.0 * std::sin(0.9 * p.x()) * std::cos(0.7 * p.y()) +
               std::cos(0.5 * p.z() + 0.3 * p.x());
    };
    const InterpolatedField field = Sampled(s, f);
    const int dims = GetParam() ? 2 : 3;
    // h = 1e-5 m on a 0.5 m grid; the spline is C2, so the Hessian check across a knot is off by
    // at most h times the jump of the third derivative (~1e-5): tolerance 1e-5 + 1e-6 relative.
    const double h = 1e-5;
    std::mt19937 rng(8u);
    for (int trial = 0; trial < 100; ++trial) {
        const Eigen::Vector3d p = RandomInterior(s, rng, 1.05);
        const FieldSample c = *field.Query(p);
        for (int k = 0; k < dims; ++k) {
            Eigen::Vector3d pp = p, pm = p;
            pp[k] += h;
            pm[k] -= h;
            const FieldSample sp = *field.Query(pp), sm = *field.Query(pm);
            EXPECT_NEAR(c.gradient[k], (sp.value - sm.value) / (2 * h),
                        1e-6 + 1e-6 * std::abs(c.gradient[k]))
                << "trial " << trial << " k " << k;
            const Eigen::Vector3d col = (sp.gradient - sm.gradient) / (2 * h);
            for (int r = 0; r < 3; ++r) {
                EXPECT_NEAR(c.hessian(r, k), col[r], 2e-5 + 1e-6 * std::abs(col[r]))
                    << "trial " << trial << " (" << r << ", " << k << ")";
            }
        }
        EXPECT_LT((c.hessian - c.hessian.transpose()).cwiseAbs().maxCoeff(), 1e-12);
        if (GetParam()) {
            EXPECT_EQ(c.gradient.z(), 0.0);
            EXPECT_EQ(c.hessian.row(2).cwiseAbs().sum(), 0.0);
        }
        // A B-spline approximates (does not interpolate): error ~ res^2 / 6 * |f''| <= 0.17 here.
        EXPECT_NEAR(c.value, f(p), 0.25);
    }
}

TEST_P(FieldTest, ValueAndGradientAreContinuousAcrossKnots) {
    const GridSpec s = FieldSpec(GetParam());
    auto f = [](const Eigen::Vector3d& p) { return std::abs(p.x() - 3.3) + 0.2 * p.y() * p.y(); };
    const InterpolatedField field = Sampled(s, f);
    // Step across the knot x = origin + 10 * res along x.
    const double knot = s.origin_m.x() + 10 * s.resolution_m;
    const Eigen::Vector3d lo(knot - 1e-9, 5.1, 0.2), hi(knot + 1e-9, 5.1, 0.2);
    const FieldSample a = *field.Query(lo), b = *field.Query(hi);
    EXPECT_NEAR(a.value, b.value, 1e-7);
    EXPECT_LT((a.gradient - b.gradient).norm(), 1e-6);
    EXPECT_LT((a.hessian - b.hessian).norm(), 1e-5);
}

TEST_P(FieldTest, QueryMissesOutsideAndNearTheBorder) {
    const GridSpec s = FieldSpec(GetParam());
    const InterpolatedField field = Sampled(s, [](const Eigen::Vector3d&) { return 1.0; });
    const double r = s.resolution_m;
    const Eigen::Vector3d mid =
        s.origin_m + r * Eigen::Vector3d(s.nx / 2, s.ny / 2, GetParam() ? 0 : s.nz / 2);
    ASSERT_TRUE(field.Query(mid).has_value());
    EXPECT_NEAR(field.Query(mid)->value, 1.0, 1e-12);
    const double x0 = s.origin_m.x(), x1 = s.origin_m.x() + (s.nx - 1) * r;
    for (double x : {x0 - 10.0, x0 - 1e-3, x0, x0 + 0.99 * r, x1 - r, x1, x1 + 5.0}) {
        Eigen::Vector3d p = mid;
        p.x() = x;
        EXPECT_FALSE(field.Query(p).has_value()) << "x = " << x;
    }
    // One cell in from the low border is the first valid position.
    Eigen::Vector3d p = mid;
    p.x() = x0 + r;
    EXPECT_TRUE(field.Query(p).has_value());
    p.x() = x1 - 1.01 * r;
    EXPECT_TRUE(field.Query(p).has_value());
    const double y1 = s.origin_m.y() + (s.ny - 1) * r;
    p = mid;
    p.y() = y1 + 1.0;
    EXPECT_FALSE(field.Query(p).has_value());
    p = mid;
    p.z() = 1e4;  // planar fields ignore height; 3D fields miss
    EXPECT_EQ(field.Query(p).has_value(), GetParam());
    EXPECT_FALSE(field.Query(mid + Eigen::Vector3d(std::nan(""), 0, 0)).has_value());
}

TEST_P(FieldTest, QueryPairAndValueMatchQuery) {
    const GridSpec s = FieldSpec(GetParam());
    const InterpolatedField f1 =
        Sampled(s, [](const Eigen::Vector3d& p) { return p.squaredNorm(); });
    const InterpolatedField f2 =
        Sampled(s, [](const Eigen::Vector3d& p) { return std::sin(p.x()); });
    std::mt19937 rng(3u);
    FieldSample a, b;
    for (int trial = 0; trial < 20; ++trial) {
        const Eigen::Vector3d p = RandomInterior(s, rng, 1.0);
        ASSERT_TRUE(InterpolatedField::QueryPair(f1, f2, p, a, b));
        const FieldSample q1 = *f1.Query(p), q2 = *f2.Query(p);
        EXPECT_EQ(a.value, q1.value);
        EXPECT_EQ(a.gradient, q1.gradient);
        EXPECT_EQ(a.hessian, q1.hessian);
        EXPECT_EQ(b.value, q2.value);
        EXPECT_EQ(b.gradient, q2.gradient);
        EXPECT_EQ(b.hessian, q2.hessian);
        EXPECT_EQ(*f1.Value(p), q1.value);
        EXPECT_EQ(*f2.Value(p), q2.value);
    }
    EXPECT_FALSE(InterpolatedField::QueryPair(f1, f2, s.origin_m, a, b));
    EXPECT_FALSE(f1.Value(s.origin_m).has_value());
}

INSTANTIATE_TEST_SUITE_P(PlanarAnd3d, FieldTest, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& param_info) {
                             return std::string(param_info.param ? "planar" : "volume");
                         });

TEST(InterpolatedField, EmptyFieldAlwaysMisses) {
    const InterpolatedField empty;
    EXPECT_FALSE(empty.Query(Eigen::Vector3d::Zero()).has_value());
    const TraversableField none;
    EXPECT_TRUE(none.empty());
    EXPECT_FALSE(none.Query(Eigen::Vector3d::Zero()).has_value());
}

// ---- A straight road -----------------------------------------------------------------------

RoadNetwork StraightRoad(double half_width_m) {
    RoadNetwork net;
    net.roads.push_back(RoadPolyline{1, "residential", half_width_m, {{0.0, 0.0}, {100.0, 0.0}}});
    return net;
}

Eigen::AlignedBox2d Box(double x0, double y0, double x1, double y1) {
    return Eigen::AlignedBox2d(Eigen::Vector2d(x0, y0), Eigen::Vector2d(x1, y1));
}

RoadFieldConfig FineConfig() {
    RoadFieldConfig c;
    c.resolution_m = 0.25;
    c.margin_m = 20.0;
    c.truncation_m = 10.0;
    c.exact_band_m = 6.0;
    return c;
}

TEST(RoadField, StraightRoadCentreAndCorridorDistances) {
    const TraversableField field =
        RasteriseRoads(StraightRoad(4.0), Box(0, -5, 100, 5), FineConfig());
    ASSERT_FALSE(field.empty());
    EXPECT_TRUE(field.planar());
    EXPECT_EQ(field.truncation_m(), 10.0);
    for (double x : {10.0, 33.3, 50.0, 71.9}) {
        for (double y : {-7.0, -3.0, -1.5, 1.2, 3.0, 4.0, 6.0, 8.5}) {
            const auto q = field.Query(Eigen::Vector3d(x, y, 0.0));
            ASSERT_TRUE(q.has_value()) << x << ", " << y;
            // Tolerance 0.05 m at 0.25 m resolution, away from the centre-line kink (|y| > 1).
            EXPECT_NEAR(q->centre.value, std::abs(y), 0.05) << x << ", " << y;
            EXPECT_NEAR(q->corridor.value, std::abs(y) - 4.0, 0.05) << x << ", " << y;
            const Eigen::Vector3d dir(0.0, y > 0 ? 1.0 : -1.0, 0.0);
            EXPECT_LT((q->centre.gradient - dir).norm(), 0.02) << x << ", " << y;
            EXPECT_LT((q->corridor.gradient - dir).norm(), 0.02) << x << ", " << y;
        }
    }
    const auto q3 = field.Query(Eigen::Vector3d(40.0, 3.0, 0.0));
    EXPECT_NEAR(q3->centre.value, 3.0, 0.05);
    EXPECT_NEAR(q3->corridor.value, -1.0, 0.05);
    EXPECT_NEAR(field.Query(Eigen::Vector3d(40.0, 6.0, 0.0))->corridor.value, 2.0, 0.05);
    // On the centre line the V is rounded: small, continuous, near-zero slope across the road.
    const auto q0 = field.Query(Eigen::Vector3d(40.0, 0.0, 0.0));
    EXPECT_LT(q0->centre.value, 0.25);
    EXPECT_LT(std::abs(q0->centre.gradient.y()), 0.05);
    EXPECT_GT(q0->centre.hessian(1, 1), 0.0);
}

TEST(RoadField, BeyondTheEndTheDistanceIsToTheEndPoint) {
    const TraversableField field =
        RasteriseRoads(StraightRoad(4.0), Box(0, -5, 100, 5), FineConfig());
    const auto q = field.Query(Eigen::Vector3d(-3.0, 4.0, 0.0));  // 5 m from (0, 0)
    ASSERT_TRUE(q.has_value());
    EXPECT_NEAR(q->centre.value, 5.0, 0.05);
    EXPECT_LT((q->centre.gradient - Eigen::Vector3d(-0.6, 0.8, 0.0)).norm(), 0.02);
}

TEST(RoadField, FarAwayValuesEqualTruncation) {
    const RoadFieldConfig cfg = FineConfig();
    const TraversableField field = RasteriseRoads(StraightRoad(4.0), Box(0, -5, 100, 5), cfg);
    // The grid spans the road's bounds grown by the truncation; near its corners every sample of
    // the B-spline support is farther than the truncation from the road's centre line.
    for (const Eigen::Vector3d& p :
         {Eigen::Vector3d(-8.5, -8.5, 0.0), Eigen::Vector3d(108.0, 8.0, 0.0),
          Eigen::Vector3d(-8.0, 8.5, 3.0)}) {
        const auto q = field.Query(p);
        ASSERT_TRUE(q.has_value()) << p.transpose();
        EXPECT_NEAR(q->centre.value, cfg.truncation_m, 1e-5) << p.transpose();
        EXPECT_LT(q->centre.gradient.norm(), 1e-5);
        EXPECT_LT(q->centre.hessian.norm(), 1e-5);
    }
    // Outside the grid: no sample.
    EXPECT_FALSE(field.Query(Eigen::Vector3d(50.0, 30.0, 0.0)).has_value());

    // Two parallel roads 60 m apart: half-way between them both fields are truncated.
    RoadNetwork two = StraightRoad(4.0);
    two.roads.push_back(RoadPolyline{2, "residential", 4.0, {{0.0, 60.0}, {100.0, 60.0}}});
    const TraversableField wide = RasteriseRoads(two, Box(0, -5, 100, 65), cfg);
    for (double y : {20.0, 30.0, 41.3}) {
        const auto q = wide.Query(Eigen::Vector3d(50.0, y, 0.0));
        ASSERT_TRUE(q.has_value()) << "y = " << y;
        EXPECT_NEAR(q->centre.value, cfg.truncation_m, 1e-5) << "y = " << y;
        EXPECT_NEAR(q->corridor.value, cfg.truncation_m, 1e-5) << "y = " << y;
        EXPECT_LT(q->centre.gradient.norm(), 1e-5);
        EXPECT_LT(q->corridor.gradient.norm(), 1e-5);
    }
    // And close to the second road it measures from that road.
    EXPECT_NEAR(wide.Query(Eigen::Vector3d(50.0, 57.0, 0.0))->centre.value, 3.0, 0.05);
}

TEST(RoadField, DistancesBeyondTheExactBandComeFromTheEdt) {
    // A narrow exact band (1 m) and a half-width that is not a multiple of the resolution: past
    // y = 5.1 the corridor distance comes from the EDT of the inside samples. It must still be
    // the distance to the corridor edge, within half a cell, and continuous across the band edge.
    RoadFieldConfig cfg = FineConfig();
    cfg.exact_band_m = 1.0;
    cfg.truncation_m = 25.0;
    const double hw = 4.1, res = cfg.resolution_m;
    const TraversableField field = RasteriseRoads(StraightRoad(hw), Box(0, -5, 100, 5), cfg);
    for (double y : {6.0, 8.0, 12.0, 17.3, 20.0}) {
        const auto q = field.Query(Eigen::Vector3d(50.0, y, 0.0));
        ASSERT_TRUE(q.has_value()) << "y = " << y;
        EXPECT_NEAR(q->centre.value, y, 0.5 * res + 1e-3) << "y = " << y;
        EXPECT_NEAR(q->corridor.value, y - hw, 0.5 * res + 1e-3) << "y = " << y;
        EXPECT_NEAR(q->corridor.gradient.y(), 1.0, 0.05) << "y = " << y;
    }
    // Across the band edge (y = hw + band = 5.1) the corridor keeps rising at unit slope.
    const double below = field.Query(Eigen::Vector3d(50.0, 4.5, 0.0))->corridor.value;
    const double above = field.Query(Eigen::Vector3d(50.0, 5.7, 0.0))->corridor.value;
    EXPECT_NEAR(above - below, 1.2, 0.05);
}

TEST(RoadField, MemoryCapTooSmallThrowsAndNamesResolution) {
    RoadFieldConfig cfg = FineConfig();
    cfg.max_memory_mb = 0.01;
    try {
        RasteriseRoads(StraightRoad(4.0), Box(0, -5, 100, 5), cfg);
        FAIL() << "expected std::invalid_argument";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("resolution"), std::string::npos) << e.what();
    }
    EXPECT_THROW(RasteriseRoads(RoadNetwork{}, Box(0, -5, 100, 5), FineConfig()),
                 std::invalid_argument);
}

TEST(RoadField, TwoRoadsTakeTheNearerOne) {
    RoadNetwork net = StraightRoad(3.0);
    net.roads.push_back(RoadPolyline{2, "service", 2.0, {{50.0, 0.0}, {50.0, 40.0}}});
    const TraversableField field = RasteriseRoads(net, Box(0, -5, 100, 45), FineConfig());
    // (47, 20): 3 m from the second road (half-width 2), 20 m from the first.
    const auto q = field.Query(Eigen::Vector3d(47.0, 20.0, 0.0));
    ASSERT_TRUE(q.has_value());
    EXPECT_NEAR(q->centre.value, 3.0, 0.05);
    EXPECT_NEAR(q->corridor.value, 1.0, 0.05);
    EXPECT_LT((q->centre.gradient - Eigen::Vector3d(-1.0, 0.0, 0.0)).norm(), 0.02);
    // Near the junction's inner corner the V between the two roads is rounded but finite.
    const auto k = field.Query(Eigen::Vector3d(46.0, 4.0, 0.0));
    ASSERT_TRUE(k.has_value());
    EXPECT_NEAR(k->centre.value, 4.0, 0.15);  // equidistant: looser near the medial axis
}

TEST(RoadField, ConfigValidateNamesTheField) {
    EXPECT_EQ(RoadFieldConfig{}.Validate(), "");
    RoadFieldConfig c;
    c.resolution_m = 0.0;
    EXPECT_NE(c.Validate().find("resolution_m"), std::string::npos);
    c = RoadFieldConfig{};
    c.truncation_m = -1.0;
    EXPECT_NE(c.Validate().find("truncation_m"), std::string::npos);
}

// ---- Road classes --------------------------------------------------------------------------

TEST(RoadClassConfig, ProfilesAndOverrides) {
    RoadClassConfig vehicle;
    EXPECT_EQ(vehicle.Validate(), "");
    auto t = vehicle.Table();
    EXPECT_EQ(t.count("residential"), 1u);
    EXPECT_EQ(t.count("motorway"), 1u);
    EXPECT_EQ(t.count("footway"), 0u);

    RoadClassConfig ped;
    ped.profile = "pedestrian";
    t = ped.Table();
    EXPECT_EQ(t.count("footway"), 1u);
    EXPECT_EQ(t.count("motorway"), 0u);

    RoadClassConfig all;
    all.profile = "all";
    t = all.Table();
    EXPECT_EQ(t.count("footway"), 1u);
    EXPECT_EQ(t.count("motorway"), 1u);

    RoadClassConfig over;
    over.half_width_overrides_m = {{"residential", 0.0}, {"footway", 2.0}, {"secondary", 9.0}};
    EXPECT_EQ(over.Validate(), "");
    t = over.Table();
    EXPECT_EQ(t.count("residential"), 0u);
    EXPECT_EQ(t.at("footway"), 2.0);
    EXPECT_EQ(t.at("secondary"), 9.0);
}

TEST(RoadClassConfig, ValidateRejectsBadValues) {
    RoadClassConfig c;
    c.profile = "bicycle";
    EXPECT_NE(c.Validate().find("profile"), std::string::npos) << c.Validate();
    c = RoadClassConfig{};
    c.half_width_overrides_m["track"] = -1.0;
    EXPECT_NE(c.Validate().find("track"), std::string::npos) << c.Validate();
    c = RoadClassConfig{};
    c.default_half_width_m = 0.0;
    EXPECT_NE(c.Validate().find("default_half_width_m"), std::string::npos);
}

TEST(BuildRoadNetwork, KeepsTraversableWaysAndProjects) {
    OsmRoads osm;
    auto way = [](std::int64_t id, const std::string& hw, bool area) {
        OsmWay w;
        w.id = id;
        w.highway = hw;
        w.is_area = area;
        w.nodes = {GeoPoint{48.0, 11.0, 0.0}, GeoPoint{48.001, 11.002, 0.0}};
        return w;
    };
    osm.ways = {way(1, "residential", false), way(2, "footway", false), way(3, "pedestrian", true),
                way(4, "weird_class", false)};
    // A toy projection: 1e5 m per degree, East from longitude, North from latitude.
    auto to_en = [](const GeoPoint& g) {
        return Eigen::Vector2d((g.lon_deg - 11.0) * 1e5, (g.lat_deg - 48.0) * 1e5);
    };
    RoadClassConfig vehicle;
    RoadNetwork net = BuildRoadNetwork(osm, to_en, vehicle);
    ASSERT_EQ(net.roads.size(), 1u);
    EXPECT_EQ(net.roads[0].osm_id, 1);
    EXPECT_EQ(net.roads[0].half_width_m, 4.5);
    EXPECT_EQ(net.ways_area, 1u);
    EXPECT_EQ(net.ways_excluded_by_class, 2u);
    ASSERT_EQ(net.roads[0].points_en.size(), 2u);
    EXPECT_LT((net.roads[0].points_en[1] - Eigen::Vector2d(200.0, 100.0)).norm(), 1e-6);
    EXPECT_NEAR(net.TotalLengthM(), std::sqrt(200.0 * 200.0 + 100.0 * 100.0), 1e-6);
    EXPECT_LT((net.Bounds().max() - Eigen::Vector2d(200.0, 100.0)).norm(), 1e-6);

    RoadClassConfig all;
    all.profile = "all";
    all.default_half_width_m = 2.5;
    net = BuildRoadNetwork(osm, to_en, all);
    ASSERT_EQ(net.roads.size(), 3u);
    EXPECT_EQ(net.roads[2].highway, "weird_class");
    EXPECT_EQ(net.roads[2].half_width_m, 2.5);

    RoadClassConfig ped;
    ped.profile = "pedestrian";
    ped.half_width_overrides_m["residential"] = 0.0;
    net = BuildRoadNetwork(osm, to_en, ped);
    ASSERT_EQ(net.roads.size(), 1u);
    EXPECT_EQ(net.roads[0].highway, "footway");
}

}  // namespace
}  // namespace driftcorr
