// The road field held as tiles (RoadFieldConfig::tile_m) and only along a corridor
// (RasteriseRoadCorridor): wherever a tile is held it must give the one-grid field's samples
// (value, gradient, Hessian, bilinear), and outside the held tiles it must miss.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "driftcorr/mapping/road_network.h"

namespace driftcorr {
namespace {

// A small town: a grid of streets 40 m apart, a diagonal and a curve, over about 200 x 160 m.
RoadNetwork Town() {
    RoadNetwork net;
    std::int64_t id = 1;
    for (double x = 0.0; x <= 200.0; x += 40.0) {
        net.roads.push_back(RoadPolyline{id++, "residential", 4.5, {{x, 0.0}, {x, 160.0}}});
    }
    for (double y = 0.0; y <= 160.0; y += 40.0) {
        net.roads.push_back(RoadPolyline{id++, "secondary", 6.0, {{0.0, y}, {200.0, y}}});
    }
    net.roads.push_back(RoadPolyline{id++, "service", 3.5, {{3.0, 7.0}, {187.0, 151.0}}});
    RoadPolyline curve{id++, "tertiary", 5.5, {}};
    for (int k = 0; k <= 20; ++k) {
        const double a = 0.05 * M_PI * k;
        curve.points_en.push_back({100.0 + 70.0 * std::cos(a), 80.0 + 50.0 * std::sin(a)});
    }
    net.roads.push_back(curve);
    return net;
}

RoadFieldConfig Config(double tile_m) {
    RoadFieldConfig c;
    c.resolution_m = 0.5;
    c.margin_m = 30.0;
    c.truncation_m = 12.0;
    c.exact_band_m = 3.0;
    c.tile_m = tile_m;
    return c;
}

const Eigen::AlignedBox2d kRegion(Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(200.0, 160.0));

void ExpectSameSample(const std::optional<TraversableSample>& a,
                      const std::optional<TraversableSample>& b, const Eigen::Vector3d& p) {
    ASSERT_EQ(a.has_value(), b.has_value()) << p.transpose();
    if (!a) return;
    // The tiles' samples are computed from the same roads on the same grid: equal to float
    // rounding of the distance transform.
    EXPECT_NEAR(a->centre.value, b->centre.value, 1e-5) << p.transpose();
    EXPECT_NEAR(a->corridor.value, b->corridor.value, 1e-5) << p.transpose();
    EXPECT_LT((a->centre.gradient - b->centre.gradient).norm(), 1e-4) << p.transpose();
    EXPECT_LT((a->corridor.gradient - b->corridor.gradient).norm(), 1e-4) << p.transpose();
    EXPECT_LT((a->centre.hessian - b->centre.hessian).norm(), 1e-3) << p.transpose();
}

class TileSize : public ::testing::TestWithParam<double> {};

TEST_P(TileSize, TiledFieldEqualsOneGrid) {
    const RoadNetwork net = Town();
    const TraversableField one = RasteriseRoads(net, kRegion, Config(0.0));
    const TraversableField tiled = RasteriseRoads(net, kRegion, Config(GetParam()));
    ASSERT_FALSE(one.tiled());
    ASSERT_TRUE(tiled.tiled());
    EXPECT_EQ(tiled.spec().nx, one.spec().nx);
    EXPECT_EQ(tiled.spec().ny, one.spec().ny);
    EXPECT_GE(tiled.Samples(), one.Samples());  // the tiles' borders overlap
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> ux(-45.0, 245.0), uy(-45.0, 205.0);
    for (int k = 0; k < 4000; ++k) {
        const Eigen::Vector3d p(ux(rng), uy(rng), 0.0);
        ExpectSameSample(one.Query(p), tiled.Query(p), p);
        const auto a = one.QueryCentreBilinear(p), b = tiled.QueryCentreBilinear(p);
        ASSERT_EQ(a.has_value(), b.has_value()) << p.transpose();
        if (a) {
            EXPECT_NEAR(a->value, b->value, 1e-5) << p.transpose();
        }
        const auto c = one.QueryCorridorBilinear(p), d = tiled.QueryCorridorBilinear(p);
        ASSERT_EQ(c.has_value(), d.has_value()) << p.transpose();
        if (c) {
            EXPECT_NEAR(c->value, d->value, 1e-5) << p.transpose();
        }
    }
    // On tile borders (multiples of the tile side from the grid's origin) as well.
    const double side = GetParam();
    const Eigen::Vector3d o = one.spec().origin_m;
    for (double x = side; x < 250.0; x += side) {
        for (double y : {13.0, 40.0, 77.7, 121.0}) {
            const Eigen::Vector3d p(o.x() + x, y, 0.0);
            ExpectSameSample(one.Query(p), tiled.Query(p), p);
        }
    }
}

// 16 m: the distance transform's reach (truncation plus a cell) spans several tiles.
INSTANTIATE_TEST_SUITE_P(RoadField, TileSize, ::testing::Values(16.0, 37.0, 256.0));

TEST(RoadCorridor, HeldTilesEqualTheWholeFieldAndTheRestMisses) {
    const RoadNetwork net = Town();
    const TraversableField one = RasteriseRoads(net, kRegion, Config(0.0));
    // A drive along the bottom street and up the left one: an L.
    std::vector<FieldDisc> discs;
    for (double x = 0.0; x <= 200.0; x += 2.0) discs.push_back({{x, 0.0}, 12.0});
    for (double y = 0.0; y <= 160.0; y += 2.0) discs.push_back({{0.0, y}, 12.0});
    const TraversableField corridor = RasteriseRoadCorridor(net, kRegion, discs, Config(16.0));
    ASSERT_TRUE(corridor.tiled());
    EXPECT_LT(double(corridor.Samples()), 0.5 * double(one.Samples()));
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> ux(-45.0, 245.0), uy(-45.0, 205.0);
    int inside = 0, missed = 0;
    for (int k = 0; k < 4000; ++k) {
        const Eigen::Vector3d p(ux(rng), uy(rng), 0.0);
        const double to_l =
            std::min(std::abs(p.y()) + std::max(0.0, p.x() - 200.0) + std::max(0.0, -p.x()),
                     std::abs(p.x()) + std::max(0.0, p.y() - 160.0) + std::max(0.0, -p.y()));
        const auto q = corridor.Query(p);
        if (to_l <= 10.0) {  // well within a disc (taxicab >= Euclidean distance): a held tile
            ++inside;
            ExpectSameSample(one.Query(p), q, p);
        } else if (q) {
            ExpectSameSample(one.Query(p), q, p);  // a held tile reaching beyond the discs
        }
        // Farther than a disc plus a tile's diagonal from the L (12 + 16 sqrt 2 < 45 m): no tile.
        if (p.x() > 45.0 && p.y() > 45.0) {
            EXPECT_FALSE(q.has_value()) << p.transpose();
            ++missed;
        }
    }
    EXPECT_GT(inside, 200);
    EXPECT_GT(missed, 1000);
    EXPECT_FALSE(corridor.QueryCentre(Eigen::Vector3d(150.0, 120.0, 0.0)).has_value());
    EXPECT_FALSE(corridor.QueryCentreBilinear(Eigen::Vector3d(150.0, 120.0, 0.0)).has_value());
}

TEST(RoadCorridor, ACorridorOverMostOfTheBoxIsOneGrid) {
    const RoadNetwork net = Town();
    const TraversableField one = RasteriseRoads(net, kRegion, Config(0.0));
    std::vector<FieldDisc> discs;
    for (double x = 0.0; x <= 200.0; x += 20.0) {
        for (double y = 0.0; y <= 160.0; y += 20.0) discs.push_back({{x, y}, 30.0});
    }
    const TraversableField field = RasteriseRoadCorridor(net, kRegion, discs, Config(16.0));
    EXPECT_FALSE(field.tiled());
    EXPECT_EQ(field.Samples(), one.Samples());
    const Eigen::Vector3d p(77.7, 55.5, 0.0);
    EXPECT_EQ(field.Query(p)->centre.value, one.Query(p)->centre.value);
}

TEST(RoadCorridor, MemoryCapCountsTheHeldTiles) {
    const RoadNetwork net = Town();
    std::vector<FieldDisc> one_disc = {{{100.0, 80.0}, 10.0}};
    RoadFieldConfig cfg = Config(16.0);
    // The whole field (449 x 369 samples, 10 bytes each at peak: 1.6 MB) exceeds 1 MB; the
    // tiles near one disc (a few 36 x 36 tiles, 8 bytes a sample, plus one tile's work) do not.
    cfg.max_memory_mb = 1.0;
    RoadFieldConfig whole = Config(0.0);
    whole.max_memory_mb = 1.0;
    EXPECT_THROW(RasteriseRoads(net, kRegion, whole), std::invalid_argument);
    EXPECT_NO_THROW(RasteriseRoadCorridor(net, kRegion, one_disc, cfg));
    cfg.max_memory_mb = 0.01;
    try {
        RasteriseRoadCorridor(net, kRegion, one_disc, cfg);
        FAIL() << "expected std::invalid_argument";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("tiles"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("resolution"), std::string::npos) << e.what();
    }
}

// The value-only reads give Query's numbers to the last bit, and miss where it misses: on the
// one grid, on held tiles, on tiles not held and off the grid.
TEST(RoadCorridor, ValueReadsEqualQuery) {
    const RoadNetwork net = Town();
    std::vector<FieldDisc> discs;
    for (double x = 0.0; x <= 200.0; x += 2.0) discs.push_back({{x, 0.0}, 12.0});
    const TraversableField one = RasteriseRoads(net, kRegion, Config(0.0));
    const TraversableField tiled = RasteriseRoadCorridor(net, kRegion, discs, Config(16.0));
    ASSERT_TRUE(tiled.tiled());
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> ux(-60.0, 260.0), uy(-60.0, 220.0);
    int hits = 0, misses = 0;
    for (const TraversableField* field : {&one, &tiled}) {
        for (int k = 0; k < 3000; ++k) {
            const Eigen::Vector3d p(ux(rng), uy(rng), 0.0);
            const auto q = field->Query(p);
            const auto centre = field->CentreValue(p), corridor = field->CorridorValue(p);
            ASSERT_EQ(q.has_value(), centre.has_value()) << p.transpose();
            ASSERT_EQ(q.has_value(), corridor.has_value()) << p.transpose();
            if (!q) {
                ++misses;
                continue;
            }
            ++hits;
            EXPECT_EQ(std::memcmp(&*centre, &q->centre.value, sizeof(double)), 0) << p.transpose();
            EXPECT_EQ(std::memcmp(&*corridor, &q->corridor.value, sizeof(double)), 0)
                << p.transpose();
        }
    }
    EXPECT_GT(hits, 1000);
    EXPECT_GT(misses, 500);
}

TEST(RoadCorridor, NegativeTileSizeIsRejected) {
    RoadFieldConfig cfg = Config(-1.0);
    EXPECT_NE(cfg.Validate().find("field.tile_m"), std::string::npos);
    cfg.tile_m = 0.0;
    EXPECT_EQ(cfg.Validate(), "");
}

}  // namespace
}  // namespace driftcorr
