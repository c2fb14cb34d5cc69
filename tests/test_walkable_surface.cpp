// The walkable surface of a raw 3D map (mapping/src/walkable_surface.cpp): small hand-built
// buildings whose standing surfaces are known, with the clutter a scan holds (walls, ceilings,
// tables, cabinets, a roof).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "driftcorr/mapping/walkable_surface.h"

namespace driftcorr {
namespace {

using Points = std::vector<Eigen::Vector3d>;
constexpr double kSpacing = 0.05;  // scan point spacing [m]

// A horizontal rectangle of points at height z.
void Slab(Points& out, double x0, double y0, double x1, double y1, double z) {
    for (double y = y0 + 0.5 * kSpacing; y < y1; y += kSpacing) {
        for (double x = x0 + 0.5 * kSpacing; x < x1; x += kSpacing) out.emplace_back(x, y, z);
    }
}

// A box's surfaces: top and four sides from z0 to z1.
void Box(Points& out, double x0, double y0, double x1, double y1, double z0, double z1) {
    Slab(out, x0, y0, x1, y1, z1);
    for (double z = z0; z <= z1; z += kSpacing) {
        for (double x = x0; x <= x1; x += kSpacing)
            out.emplace_back(x, y0, z), out.emplace_back(x, y1, z);
        for (double y = y0; y <= y1; y += kSpacing)
            out.emplace_back(x0, y, z), out.emplace_back(x1, y, z);
    }
}

// One storey of a 10 m x 8 m room from x0 at floor height z: floor, walls to a ceiling 2.8 m
// up (with a 2.1 m high door at y 1-2.5 m in the west or east wall when asked), the ceiling, a
// table (top 0.75 m up, 1.2 x 0.8 m) and a cabinet (1.9 m tall, 1.0 x 0.5 m). `truth` gets the
// floor cells a person can stand on (not under the table or the cabinet).
struct Doors {
    bool west = false, east = false;
};
void Storey(Points& cloud, Points* truth, double z, double x0 = 0.0, Doors doors = {}) {
    const double x1 = x0 + 10.0;
    Slab(cloud, x0, 0.0, x1, 8.0, z);
    auto door = [&](bool open, double y, double h) {
        return open && y > 1.0 && y < 2.5 && h < z + 2.1;
    };
    for (double h = z; h <= z + 2.8; h += kSpacing) {
        for (double x = x0; x <= x1; x += kSpacing) {
            cloud.emplace_back(x, -0.05, h), cloud.emplace_back(x, 8.05, h);
        }
        for (double y = 0.0; y <= 8.0; y += kSpacing) {
            if (!door(doors.west, y, h)) cloud.emplace_back(x0 - 0.05, y, h);
            if (!door(doors.east, y, h)) cloud.emplace_back(x1 + 0.05, y, h);
        }
    }
    Slab(cloud, x0, 0.0, x1, 8.0, z + 2.8);
    Slab(cloud, x0 + 2.0, 2.0, x0 + 3.2, 2.8, z + 0.75);   // table top
    Box(cloud, x0 + 7.0, 6.0, x0 + 8.0, 6.5, z, z + 1.9);  // cabinet
    if (!truth) return;
    for (double y = 0.05; y < 8.0; y += 0.1) {
        for (double x = x0 + 0.05; x < x1; x += 0.1) {
            const bool under_table = x > x0 + 2.0 && x < x0 + 3.2 && y > 2.0 && y < 2.8;
            const bool under_cabinet = x > x0 + 7.0 && x < x0 + 8.0 && y > 6.0 && y < 6.5;
            if (!under_table && !under_cabinet) truth->emplace_back(x, y, z);
        }
    }
}

TEST(WalkableSurface, OneRoomKeepsTheFloorAndDropsCeilingAndFurniture) {
    Points cloud, truth;
    Storey(cloud, &truth, 0.0);
    const WalkableSurface s = ExtractWalkableSurface(cloud, WalkableSurfaceConfig{});
    const SurfaceAgreement a = CompareSurfaces(s.points, truth, 0.1, 0.15);
    EXPECT_GE(a.precision, 0.99);
    EXPECT_GE(a.recall, 0.97);
    EXPECT_NEAR(s.area_m2, 80.0, 3.0);
    for (const Eigen::Vector3d& p : s.points) EXPECT_NEAR(p.z(), 0.0, 0.05);
    // The ceiling (nothing above, free space under it) and the table top were found and dropped.
    bool ceiling = false, table = false;
    for (const WalkableRegion& r : s.regions) {
        if (r.kept) continue;
        ceiling =
            ceiling || (r.area_m2 > 50.0 && r.why_dropped.find("ceiling") != std::string::npos);
        table = table || (std::abs(r.z_min_m - 0.8) < 0.1 && r.area_m2 < 1.5);
    }
    EXPECT_TRUE(ceiling);
    EXPECT_TRUE(table);
}

// A storey at 0 m (x 0-10) and one at 4 m (x 18-28) joined through doors by a flight of 0.2 m
// risers and 0.4 m treads (x 10-18, y 1-2.5): one region with both floors and the treads; the
// roofs above both storeys (nothing above them, free space under them) are dropped.
TEST(WalkableSurface, StairsJoinTwoFloorsIntoOneRegion) {
    Points cloud, truth;
    Storey(cloud, &truth, 0.0, 0.0, {false, true});
    Storey(cloud, &truth, 4.0, 18.0, {true, false});
    for (int step = 0; step < 19; ++step) {
        const double x0 = 10.0 + 0.4 * step, z = 0.2 * (step + 1);
        Slab(cloud, x0, 1.0, x0 + 0.4, 2.5, z);  // tread
        for (double h = z - 0.2; h < z; h += kSpacing) {
            for (double y = 1.0; y < 2.5; y += kSpacing) cloud.emplace_back(x0, y, h);  // riser
        }
        for (double x = x0; x < x0 + 0.4; x += 0.1) {
            for (double y = 1.05; y < 2.5; y += 0.1) truth.emplace_back(x + 0.05, y, z);
        }
    }
    Slab(cloud, 17.6, 1.0, 18.0, 2.5, 4.0);  // the top landing
    const WalkableSurface s = ExtractWalkableSurface(cloud, WalkableSurfaceConfig{});
    ASSERT_FALSE(s.regions.empty());
    const WalkableRegion& main = s.regions.front();
    EXPECT_TRUE(main.kept);
    EXPECT_NEAR(main.z_min_m, 0.0, 0.15);
    EXPECT_NEAR(main.z_max_m, 4.0, 0.15);
    const SurfaceAgreement a = CompareSurfaces(s.points, truth, 0.1, 0.15);
    EXPECT_GE(a.precision, 0.98);
    EXPECT_GE(a.recall, 0.97);
    std::size_t roofs = 0;
    for (const WalkableRegion& r : s.regions) {
        const bool roof =
            r.area_m2 > 50.0 && ((r.z_min_m > 2.5 && r.z_max_m < 3.0) || r.z_min_m > 6.5);
        if (!roof) continue;
        ++roofs;
        EXPECT_FALSE(r.kept);
        EXPECT_NE(r.why_dropped.find("ceiling"), std::string::npos) << r.why_dropped;
    }
    EXPECT_EQ(roofs, 2u);
}

// Two storeys with no stairs: the upper one is not reachable and is dropped, until a lift is
// declared next to both; the shaft is then walkable at every lift level between them.
TEST(WalkableSurface, DeclaredLiftJoinsFloors) {
    Points cloud;
    Storey(cloud, nullptr, 0.0);
    Storey(cloud, nullptr, 4.0);
    WalkableSurfaceConfig cfg;
    const WalkableSurface without = ExtractWalkableSurface(cloud, cfg);
    EXPECT_NEAR(without.area_m2, 78.5, 3.0) << "one floor";
    cfg.lifts.push_back({10.2, 3.0, 12.2, 5.0});
    const WalkableSurface with = ExtractWalkableSurface(cloud, cfg);
    EXPECT_NEAR(with.area_m2, 157.0, 6.0) << "both floors";
    std::size_t lift = 0;
    double z_lo = 1e9, z_hi = -1e9;
    for (std::size_t n = 0; n < with.points.size(); ++n) {
        if (with.region[n] >= 0) continue;
        ++lift;
        z_lo = std::min(z_lo, with.points[n].z()), z_hi = std::max(z_hi, with.points[n].z());
        EXPECT_GE(with.points[n].x(), 10.2);
        EXPECT_LE(with.points[n].x(), 12.2);
    }
    EXPECT_EQ(lift, with.lift_points);
    EXPECT_EQ(lift, 17u * 400u);  // 17 levels 0.25 m apart over 4 m, 20 x 20 cells
    EXPECT_NEAR(z_lo, 0.0, 0.15);
    EXPECT_NEAR(z_hi, 4.0, 0.15);
}

// A hole of 0.8 m radius in the scan of the floor is closed (the surface under it is found
// again, at the floor's height); with fill_gap_m 0 it stays open. The table is not filled under.
TEST(WalkableSurface, GapsOfTheScanAreClosedWhereNothingStandsInTheWay) {
    Points cloud, truth, holed;
    Storey(cloud, &truth, 0.0);
    for (const Eigen::Vector3d& p : cloud) {
        if (std::abs(p.z()) < 0.01 && (p.head<2>() - Eigen::Vector2d(5.0, 4.0)).norm() < 0.8)
            continue;
        holed.push_back(p);
    }
    WalkableSurfaceConfig cfg;
    const WalkableSurface closed = ExtractWalkableSurface(holed, cfg);
    cfg.fill_gap_m = 0.0;
    const WalkableSurface open = ExtractWalkableSurface(holed, cfg);
    const SurfaceAgreement a = CompareSurfaces(closed.points, truth, 0.1, 0.15);
    const SurfaceAgreement b = CompareSurfaces(open.points, truth, 0.1, 0.15);
    EXPECT_GE(a.precision, 0.99);
    EXPECT_GE(a.recall, 0.97);
    EXPECT_LT(b.recall, a.recall - 0.02) << "the hole is about 2 m^2 of 78";
    EXPECT_GT(closed.filled_places, 150u);
    EXPECT_EQ(open.filled_places, 0u);
    for (const Eigen::Vector3d& p : closed.points) {
        EXPECT_NEAR(p.z(), 0.0, 0.05);
        const bool under_table = p.x() > 2.05 && p.x() < 3.15 && p.y() > 2.05 && p.y() < 2.75;
        EXPECT_FALSE(under_table) << p.transpose();
    }
}

TEST(WalkableSurface, NoHorizontalSurfaceGivesNothing) {
    Points wall;
    for (double z = 0.0; z < 3.0; z += kSpacing) {
        for (double x = 0.0; x < 10.0; x += kSpacing) wall.emplace_back(x, 0.0, z);
    }
    const WalkableSurface s = ExtractWalkableSurface(wall, WalkableSurfaceConfig{});
    EXPECT_EQ(s.area_m2, 0.0);
    EXPECT_TRUE(s.points.empty());
    ASSERT_FALSE(s.regions.empty());
    EXPECT_LT(s.regions.front().area_m2, 1.5) << "the wall's top edge";
}

TEST(WalkableSurface, NoiseAndDropoutKeepTheFloor) {
    Points cloud, truth, noisy;
    Storey(cloud, &truth, 0.0);
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.01);
    std::uniform_real_distribution<double> keep(0.0, 1.0);
    for (const Eigen::Vector3d& p : cloud) {
        if (keep(rng) < 0.1) continue;
        noisy.push_back(p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    }
    const WalkableSurface s = ExtractWalkableSurface(noisy, WalkableSurfaceConfig{});
    const SurfaceAgreement a = CompareSurfaces(s.points, truth, 0.1, 0.15);
    EXPECT_GE(a.precision, 0.98);
    EXPECT_GE(a.recall, 0.95);
}

TEST(WalkableSurface, UnitsAndBadInput) {
    Points cloud;
    Storey(cloud, nullptr, 0.0);
    EXPECT_FALSE(CheckCloudExtent(cloud).has_value());
    Points millimetres = cloud;
    for (Eigen::Vector3d& p : millimetres) p *= 1000.0;
    const auto m = CheckCloudExtent(millimetres);
    ASSERT_TRUE(m.has_value());
    EXPECT_NE(m->find("millimetres"), std::string::npos) << *m;
    EXPECT_THROW(ExtractWalkableSurface({}, WalkableSurfaceConfig{}), std::invalid_argument);
    EXPECT_THROW(ExtractWalkableSurface({Eigen::Vector3d(0.0, NAN, 0.0)}, WalkableSurfaceConfig{}),
                 std::invalid_argument);
    WalkableSurfaceConfig tiny;
    tiny.max_memory_mb = 0.001;
    EXPECT_THROW(ExtractWalkableSurface(cloud, tiny), std::invalid_argument);
    WalkableSurfaceConfig bad;
    bad.resolution_m = 0.0;
    EXPECT_FALSE(bad.Validate().empty());
}

TEST(WalkableSurface, CompareSurfacesCountsColumnsAndHeights) {
    const Points truth = {{0.05, 0.05, 0.0}, {0.15, 0.05, 0.0}, {0.25, 0.05, 4.0}};
    const Points extracted = {{0.05, 0.05, 0.1}, {0.25, 0.05, 0.0}};
    const SurfaceAgreement a = CompareSurfaces(extracted, truth, 0.1, 0.15);
    EXPECT_DOUBLE_EQ(a.precision, 0.5);  // the second is on the wrong floor
    EXPECT_DOUBLE_EQ(a.recall, 1.0 / 3.0);
}

}  // namespace
}  // namespace driftcorr
