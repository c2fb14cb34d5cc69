// The indoor map side: GeoJSON reader, floor-plan classifier, the 3D traversable field against
// hand-computable geometry, and the real hcu_eight layers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/floor_plan.h"
#include "driftcorr/mapping/geojson_reader.h"
#include "driftcorr/mapping/indoor_field.h"

namespace {

using namespace driftcorr;
namespace fs = std::filesystem;

const char* kCrs32632 =
    R"("crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}})";

class TmpDir : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::path(DRIFTCORR_TEST_TMPDIR) / ("indoor_" + std::to_string(::getpid()));
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string Write(const std::string& name, const std::string& text) const {
        const fs::path p = dir_ / name;
        std::ofstream(p) << text;
        return p.string();
    }
    fs::path dir_;
};

std::string Collection(const std::string& crs_member, const std::string& features) {
    std::string out = "{\"type\": \"FeatureCollection\",\n";
    if (!crs_member.empty()) out += crs_member + ",\n";
    return out + "\"features\": [\n" + features + "\n]}\n";
}

std::string Square(double x0, double y0, double x1, double y1) {
    std::ostringstream o;
    o.precision(12);
    o << "[[" << x0 << "," << y0 << "],[" << x1 << "," << y0 << "],[" << x1 << "," << y1 << "],["
      << x0 << "," << y1 << "],[" << x0 << "," << y0 << "]]";
    return o.str();
}

std::string PolygonFeature(const std::string& type, const std::string& rings) {
    return R"({"type": "Feature", "properties": {"Type": )" + type +
           R"(}, "geometry": {"type": "Polygon", "coordinates": [)" + rings + "]}}";
}

// ---------------------------------------------------------------- GeoJSON reader

using GeoJsonReaderTest = TmpDir;

TEST_F(GeoJsonReaderTest, ReadsLinesPolygonsHolesAndCountsSkips) {
    const std::string features =
        R"({"type": "Feature", "properties": {"name": null}, "geometry": {"type": "LineString",
            "coordinates": [[500000, 5900000], [500010, 5900000, 3.5]]}},
           {"type": "Feature", "properties": null, "geometry": {"type": "MultiLineString",
            "coordinates": [[[0, 0], [1, 1]], [[2, 2], [3, 3]]]}},
           {"type": "Feature", "properties": {"Type": "Room"}, "geometry": null},
           {"type": "Feature", "properties": {"Type": "Room"}, "geometry": {"type": "Point",
            "coordinates": [1, 2]}},
           {"type": "Feature", "properties": {"Type": "Room"}, "geometry": {"type": "MultiPolygon",
            "coordinates": [[)" +
        Square(0, 0, 10, 10) + "," + Square(4, 4, 6, 6) + "], [" + Square(20, 0, 30, 10) + R"(]]}},
           )" +
        PolygonFeature("null", Square(0, 0, 1, 1)) + ",\n" +
        R"({"type": "Feature", "properties": {}, "geometry": {"type": "Polygon",
            "coordinates": [[[0, 0], [1, 1]]]}})";
    const std::string path = Write("layer.geojson", Collection(kCrs32632, features));
    const GeoJsonLayer layer = ReadGeoJson(path);
    EXPECT_EQ(layer.crs, "EPSG:32632");
    EXPECT_EQ(layer.report.features, 7u);
    ASSERT_EQ(layer.lines.size(), 3u);
    EXPECT_DOUBLE_EQ(layer.lines[0].points[1].x(), 500010.0);
    ASSERT_EQ(layer.polygons.size(), 3u);
    EXPECT_EQ(layer.polygons[0].holes.size(), 1u);
    EXPECT_EQ(*layer.polygons[0].type, "Room");
    EXPECT_EQ(layer.polygons[1].outer[1].x(), 30.0);
    EXPECT_FALSE(layer.polygons[2].type.has_value());  // "Type": null
    EXPECT_EQ(layer.report.skipped.at("null geometry"), 1u);
    EXPECT_EQ(layer.report.skipped.at("unsupported geometry Point"), 1u);
    EXPECT_EQ(layer.report.skipped.at("degenerate geometry"), 1u);
    EXPECT_EQ(layer.report.SkippedCount(), 3u);
    EXPECT_NE(layer.report.Summary().find("null geometry: 1"), std::string::npos);
}

// A coordinate that is not a number is an error in the file naming the feature, not a geometry
// dropped in silence (a corridor missing from the map would then be blamed on the anchor).
TEST_F(GeoJsonReaderTest, ANonNumericCoordinateIsBadInputNamingTheFeature) {
    const std::string features =
        PolygonFeature("\"Corridor\"", Square(0, 0, 10, 10)) + ",\n" +
        R"({"type": "Feature", "properties": {"Type": "Corridor"}, "geometry": {"type": "Polygon",
            "coordinates": [[[0, 0], ["10", 0], [10, 10], [0, 0]]]}})";
    const std::string path = Write("non_numeric.geojson", Collection(kCrs32632, features));
    try {
        (void)ReadGeoJson(path);
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("features[1].geometry.coordinates"), std::string::npos) << what;
        EXPECT_NE(what.find("not a number (\"10\")"), std::string::npos) << what;
    }
}

TEST_F(GeoJsonReaderTest, BadInputNamesTheFile) {
    auto expect_error = [](const std::string& path, const std::string& fragment) {
        try {
            ReadGeoJson(path);
            ADD_FAILURE() << "no error for " << path;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(path), std::string::npos) << what;
            EXPECT_NE(what.find(fragment), std::string::npos) << what;
        }
    };
    const std::string feature = PolygonFeature("\"Room\"", Square(0, 0, 1, 1));
    expect_error(Write("nocrs.geojson", Collection("", feature)), "no `crs` member");
    expect_error(
        Write("badcrs.geojson",
              Collection(R"("crs": {"type": "name", "properties": {"name": "LOCAL:1"}})", feature)),
        "unknown CRS 'LOCAL:1'");
    expect_error(
        Write("syntax.geojson", "{\"type\": \"FeatureCollection\",\n\"features\": [\n{,}]}"),
        "invalid JSON");
    expect_error(Write("feature.geojson", "{\"type\": \"Feature\"}"),
                 "not a GeoJSON FeatureCollection");
    expect_error((dir_ / "missing.geojson").string(), "cannot open");
    try {
        ReadGeoJson(Write("syntax2.geojson", "{\n\n  \"type\": ]"));
    } catch (const InputError& e) {
        EXPECT_EQ(e.line(), 3) << e.what();
    }
}

// ---------------------------------------------------------------- classifier

TEST(FloorClassifier, Table) {
    struct Case {
        const char* type;
        FloorClass cls;
    };
    const Case cases[] = {{"Room", FloorClass::kWalkable},
                          {"Rooms", FloorClass::kWalkable},
                          {"Corridor", FloorClass::kWalkable},
                          {"Gallery", FloorClass::kWalkable},
                          {"Balcony", FloorClass::kWalkable},
                          {"Stairs", FloorClass::kStairs},
                          {"Staircase", FloorClass::kStairs},
                          {"Stairscase", FloorClass::kStairs},
                          {"Lift", FloorClass::kLift},
                          {"Elevator", FloorClass::kLift},
                          {"Door", FloorClass::kDoor},
                          {"B_Door", FloorClass::kDoor},
                          {"D", FloorClass::kDoor},
                          {"Wall", FloorClass::kWall},
                          {"Wa", FloorClass::kWall},
                          {"Fassade", FloorClass::kWall},
                          {"furniture", FloorClass::kIgnore},
                          {"Furniture", FloorClass::kIgnore},
                          {"Furnitures", FloorClass::kIgnore},
                          {"NaNs", FloorClass::kIgnore},
                          {" corridor ", FloorClass::kWalkable}};
    for (const Case& c : cases) {
        const std::string t = c.type;
        bool known = false;
        EXPECT_EQ(ClassifyFloorType(&t, &known), c.cls) << t;
        EXPECT_TRUE(known) << t;
    }
    bool known = true;
    const std::string odd = "Toilet";
    EXPECT_EQ(ClassifyFloorType(&odd, &known), FloorClass::kIgnore);
    EXPECT_FALSE(known);
    known = true;
    EXPECT_EQ(ClassifyFloorType(nullptr, &known), FloorClass::kIgnore);
    EXPECT_FALSE(known);
}

// ---------------------------------------------------------------- the field

FloorPolygon Rect(double x0, double y0, double x1, double y1) {
    return {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, {}};
}

IndoorFieldConfig TestConfig() {
    IndoorFieldConfig c;
    c.resolution_m = 0.1;
    c.resolution_z_m = 0.25;
    c.vertical_tolerance_m = 0.25;  // the layer: the surface +/- one voxel
    c.margin_m = 2.0;
    c.vertical_margin_m = 2.5;
    c.truncation_m = 6.0;
    return c;
}

double Corridor(const TraversableField& f, double x, double y, double z) {
    const auto q = f.Query({x, y, z});
    EXPECT_TRUE(q.has_value()) << x << " " << y << " " << z;
    return q ? q->corridor.value : NAN;
}

TEST(IndoorField, SingleFloorRoom) {
    IndoorFloor floor;
    floor.walkable.push_back(Rect(0, 0, 10, 10));
    IndoorFieldStats stats;
    const TraversableField f = BuildIndoorField({floor}, TestConfig(), &stats);
    EXPECT_FALSE(f.planar());
    // Scanline convention: samples on a vertical edge are inside, on a horizontal one the lower
    // edge is and the upper is not: 101 columns x 100 rows of 0.1 m cells.
    EXPECT_NEAR(stats.walkable_area_m2[0], 101 * 100 * 0.01, 1e-6);
    // Inside: minus the distance to the nearest wall edge (within the half-cell convention).
    for (double x : {1.0, 2.0, 3.0, 4.0}) {
        EXPECT_NEAR(Corridor(f, x, 5.0, 0.0), -x, 0.1) << x;
    }
    const auto q = f.Query({1.0, 5.0, 0.0});
    ASSERT_TRUE(q);
    EXPECT_NEAR(q->corridor.gradient.x(), -1.0, 0.02);
    EXPECT_NEAR(q->corridor.gradient.y(), 0.0, 0.02);
    // Outside horizontally: the distance to the room.
    EXPECT_NEAR(Corridor(f, -1.0, 5.0, 0.0), 1.0, 0.1);
    // Above the floor the corridor (and the centre: distance to the floor) grows with height.
    double last = -1e9;
    for (double z : {0.0, 0.25, 0.5, 1.0, 1.5, 2.0}) {
        const double v = Corridor(f, 5.0, 5.0, z);
        EXPECT_GT(v, last) << z;
        last = v;
    }
    // 0.75 m above the layer's top voxel (z = 0.25), minus the half-cell convention.
    EXPECT_NEAR(Corridor(f, 5.0, 5.0, 1.0), 0.7, 0.02);
    EXPECT_NEAR(f.Query({5.0, 5.0, 1.0})->centre.value, 1.0, 0.05);  // to the surface
    EXPECT_NEAR(f.Query({5.0, 5.0, 1.0})->corridor.gradient.z(), 1.0, 0.05);
    EXPECT_LT(f.Query({5.0, 5.0, 0.0})->centre.value, 0.1);
}

TEST(IndoorField, LiftAndStairsJoinFloorsNothingElseDoes) {
    IndoorFloor ground, upper;
    ground.walkable.push_back(Rect(0, 0, 20, 10));
    upper.floor_z_m = 4.0;
    upper.walkable.push_back(Rect(0, 0, 20, 10));
    ground.lifts.push_back(Rect(4, 4, 6, 6));
    upper.stairs.push_back(Rect(14, 2, 18, 4));  // drawn on the upper plan only
    IndoorFieldStats stats;
    const TraversableField f = BuildIndoorField({upper, ground}, TestConfig(), &stats);
    EXPECT_GT(stats.connector_voxels, 0u);
    // In the lift shaft and the stairwell between floors: inside, minus the distance to the
    // column's wall.
    EXPECT_NEAR(Corridor(f, 5.0, 5.0, 2.0), -1.0, 0.1);
    EXPECT_NEAR(Corridor(f, 16.0, 3.0, 2.0), -1.0, 0.1);
    // Between floors elsewhere: outside, by the distance to the nearest floor or column.
    // 1.25 m above the lower layer (surface +/- 0.25 m), minus half a cell.
    EXPECT_NEAR(Corridor(f, 10.0, 8.0, 1.5), 1.2, 0.02);
    EXPECT_GT(Corridor(f, 10.0, 8.0, 2.0), 1.5);  // half-way: the kink is rounded by the spline
    EXPECT_NEAR(Corridor(f, 7.0, 5.0, 2.0), 0.95, 0.05);  // 1 m from the lift shaft
    EXPECT_NEAR(Corridor(f, 5.0, 5.0, 4.0), -5.0, 0.1);   // upper floor: 5 m to its edge
    // Two floors without a connector are not joined.
    IndoorFloor a, b;
    a.walkable.push_back(Rect(0, 0, 10, 10));
    b.walkable.push_back(Rect(0, 0, 10, 10));
    b.floor_z_m = 4.0;
    const TraversableField g = BuildIndoorField({a, b}, TestConfig());
    EXPECT_NEAR(Corridor(g, 5.0, 5.0, 1.5), 1.2, 0.02);
    EXPECT_GT(Corridor(g, 5.0, 5.0, 2.0), 1.5);
}

// With the heights a walk can reach, the field holds fewer layers and gives the same values
// (value, gradient, Hessian) at those heights as the whole building's field; far from them it
// reads outside the map.
TEST(IndoorField, HeightsKeepTheLayersThatServeThem) {
    std::vector<IndoorFloor> floors(4);
    for (int n = 0; n < 4; ++n) floors[n].floor_z_m = 4.0 * n;
    floors[0].walkable.push_back(Rect(0, 0, 30, 12));
    floors[1].walkable.push_back(Rect(0, 0, 30, 12));  // under the 2nd floor's gap too
    floors[2].walkable.push_back(Rect(0, 0, 12, 12));
    floors[2].walkable.push_back(Rect(20, 0, 30, 12));
    floors[2].walkways_en.push_back({{1.0, 6.0}, {11.0, 6.0}});
    floors[3].walkable.push_back(Rect(0, 0, 30, 12));
    floors[0].lifts.push_back(Rect(2, 2, 4, 4));     // a shaft through every floor
    floors[1].stairs.push_back(Rect(24, 2, 28, 5));  // joins the ground and the 2nd floor
    const IndoorFieldConfig c = TestConfig();
    // The number of points at `heights` where both fields give the same values (all of them).
    auto same_at = [&c](const std::vector<IndoorFloor>& fs, const HeightRange& heights) {
        IndoorFieldStats whole_stats, kept_stats;
        const TraversableField whole = BuildIndoorField(fs, c, &whole_stats);
        const TraversableField kept = BuildIndoorField(fs, c, &kept_stats, heights);
        EXPECT_LT(kept_stats.voxels, whole_stats.voxels * 3 / 4);
        std::mt19937 rng(7);
        std::uniform_real_distribution<double> ux(-1.0, 31.0), uy(-1.0, 13.0),
            uz(heights.lo_m, heights.hi_m);
        int compared = 0;
        for (int n = 0; n < 4000; ++n) {
            const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
            const auto a = whole.Query(p), b = kept.Query(p);
            EXPECT_EQ(a.has_value(), b.has_value()) << p.transpose();
            if (!a || !b) continue;
            bool same = true;
            for (const auto& [x, y] :
                 {std::pair(a->centre, b->centre), std::pair(a->corridor, b->corridor)}) {
                same = same && std::abs(x.value - y.value) < 1e-9 &&
                       (x.gradient - y.gradient).norm() < 1e-9 &&
                       (x.hessian - y.hessian).norm() < 1e-8;
            }
            EXPECT_TRUE(same) << p.transpose();
            compared += same;
        }
        return compared;
    };
    EXPECT_GT(same_at(floors, {7.6, 8.3}), 3000);
    // One floor: the kept layers are those the interpolation reads about the heights.
    EXPECT_GT(same_at({floors[0]}, {-0.2, 0.2}), 3000);
    const TraversableField whole = BuildIndoorField(floors, c);
    const TraversableField kept = BuildIndoorField(floors, c, nullptr, HeightRange{7.6, 8.3});
    // Over the 2nd floor's gap the 1st floor lies within the truncation (3.35-4.05 m below
    // the heights): the kept layers reach down to it.
    EXPECT_GT(Corridor(whole, 16.0, 6.0, 7.6), 2.5);
    EXPECT_LT(Corridor(whole, 16.0, 6.0, 7.6), 4.0);
    // The ground floor is beyond the truncation: not held.
    EXPECT_TRUE(whole.Query({16.0, 6.0, 0.0}).has_value());
    EXPECT_FALSE(kept.Query({16.0, 6.0, 0.0}).has_value());
    EXPECT_THROW(BuildIndoorField(floors, c, nullptr, HeightRange{8.0, 7.0}),
                 std::invalid_argument);
}

TEST(IndoorField, WallsAreCutOutAndDoorsCutBack) {
    IndoorFloor floor;
    floor.walkable.push_back(Rect(0, 0, 10, 10));
    floor.walls.push_back(Rect(4.9, 0, 5.1, 10));
    const TraversableField f = BuildIndoorField({floor}, TestConfig());
    EXPECT_GT(Corridor(f, 5.0, 5.0, 0.0), 0.0);
    EXPECT_NEAR(Corridor(f, 3.0, 5.0, 0.0), -1.9, 0.1);  // the wall is nearer than x = 0
    floor.doors.push_back(Rect(4.8, 4.0, 5.2, 6.0));
    const TraversableField g = BuildIndoorField({floor}, TestConfig());
    EXPECT_LT(Corridor(g, 5.0, 5.0, 0.0), -0.5);
    EXPECT_GT(Corridor(g, 5.0, 2.0, 0.0), 0.0);
}

TEST(IndoorField, WalkwayCentreLine) {
    IndoorFloor floor;
    floor.floor_z_m = 2.0;
    floor.walkways_en.push_back({{0.0, 5.0}, {10.0, 5.0}});
    IndoorFieldConfig c = TestConfig();
    c.device_height_m = 1.0;  // the surface is at z = 3
    c.margin_m = 4.0;
    const TraversableField f = BuildIndoorField({floor}, c);
    EXPECT_NEAR(f.Query({5.0, 6.0, 3.0})->centre.value, 1.0, 0.02);
    EXPECT_NEAR(f.Query({5.0, 6.0, 3.0})->centre.gradient.y(), 1.0, 0.05);
    EXPECT_NEAR(f.Query({5.0, 5.6, 3.6})->centre.value, std::hypot(0.6, 0.6), 0.05);
    EXPECT_NEAR(f.Query({5.0, 8.0, 3.0})->centre.value, 3.0, 0.1);  // EDT beyond the band
    EXPECT_LT(Corridor(f, 5.0, 5.2, 3.0), 0.0);                     // walkway half-width 0.5 m
    EXPECT_NEAR(Corridor(f, 5.0, 7.0, 3.0), 1.5, 0.1);
    EXPECT_NEAR(Corridor(f, 5.0, 5.0, 4.0), 0.7, 0.05);  // 0.75 m above the layer's top
}

TEST(IndoorField, GradientMatchesCentralDifferences) {
    IndoorFloor ground, upper;
    ground.walkable.push_back(Rect(0, 0, 12, 8));
    ground.walls.push_back(Rect(5.9, 0, 6.1, 8));
    ground.doors.push_back(Rect(5.8, 3, 6.2, 4));
    ground.lifts.push_back(Rect(1, 1, 3, 3));
    ground.walkways_en.push_back({{1.0, 4.0}, {11.0, 4.0}, {11.0, 7.0}});
    upper.floor_z_m = 3.5;
    upper.walkable.push_back({{{0, 0}, {12, 0}, {6, 8}}, {{{5, 2}, {7, 2}, {6, 4}}}});
    IndoorFieldConfig c = TestConfig();
    c.resolution_m = 0.2;
    const TraversableField f = BuildIndoorField({ground, upper}, c);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> ux(-1.0, 13.0), uy(-1.0, 9.0), uz(-1.0, 4.5);
    const double h = 1e-5;
    for (int n = 0; n < 200; ++n) {
        const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
        const auto q = f.Query(p);
        ASSERT_TRUE(q) << p.transpose();
        for (int axis = 0; axis < 3; ++axis) {
            const Eigen::Vector3d e = Eigen::Vector3d::Unit(axis) * h;
            const auto a = f.Query(p + e), b = f.Query(p - e);
            const double dc = (a->centre.value - b->centre.value) / (2 * h);
            const double dk = (a->corridor.value - b->corridor.value) / (2 * h);
            EXPECT_NEAR(q->centre.gradient[axis], dc, 1e-3 * (1 + std::abs(dc))) << p.transpose();
            EXPECT_NEAR(q->corridor.gradient[axis], dk, 1e-3 * (1 + std::abs(dk))) << p.transpose();
        }
    }
}

TEST(IndoorField, MemoryCapNamesAResolution) {
    IndoorFloor floor;
    floor.walkable.push_back(Rect(0, 0, 100, 100));
    IndoorFieldConfig c = TestConfig();
    c.max_memory_mb = 10.0;
    try {
        BuildIndoorField({floor}, c);
        FAIL() << "no error";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("resolution"), std::string::npos) << e.what();
    }
}

TEST(IndoorField, ConfigValidateNamesTheField) {
    IndoorFieldConfig c;
    EXPECT_EQ(c.Validate(), "");
    c.resolution_z_m = 0.0;
    EXPECT_NE(c.Validate().find("resolution_z_m"), std::string::npos);
    EXPECT_THROW(BuildIndoorField({IndoorFloor{}}, c), std::invalid_argument);
    EXPECT_THROW(BuildIndoorField({IndoorFloor{}}, IndoorFieldConfig{}), std::invalid_argument);
}

// ---------------------------------------------------------------- loader

using IndoorLoaderTest = TmpDir;

TEST_F(IndoorLoaderTest, GroupsByFloorAndReprojects) {
    const double e0 = 566578.7, n0 = 5932830.4;
    auto sq = [&](double x0, double y0, double x1, double y1) {
        return Square(e0 + x0, n0 + y0, e0 + x1, n0 + y1);
    };
    const std::string plan =
        Write("plan.geojson",
              Collection(kCrs32632, PolygonFeature("\"Room\"", sq(0, 0, 10, 10)) + ",\n" +
                                        PolygonFeature("\"Toilet\"", sq(0, 0, 1, 1)) + ",\n" +
                                        PolygonFeature("\"Wall\"", sq(5, 0, 5.2, 10))));
    // ETRS89 / UTM 32N: the same grid as WGS84 / UTM 32N within centimetres.
    std::ostringstream line;
    line.precision(12);
    line << R"({"type": "Feature", "properties": {}, "geometry": {"type": "LineString",
              "coordinates": [[)"
         << e0 + 1 << "," << n0 + 5 << "],[" << e0 + 9 << "," << n0 + 5 << "]]}}";
    const std::string route = Write(
        "route.geojson",
        Collection(R"("crs": {"type": "name", "properties": {"name": "EPSG:25832"}})", line.str()));
    IndoorFrame frame;
    frame.anchor_crs = "EPSG:32632";
    frame.anchor_crs_to_en = [&](const Eigen::Vector2d& en) {
        return Eigen::Vector2d(en.x() - e0, en.y() - n0);
    };
    const IndoorMap map = LoadIndoorMap({{plan, IndoorLayerRole::kFloorplan, 4.0},
                                         {route, IndoorLayerRole::kWalkways, 4.0},
                                         {plan, IndoorLayerRole::kFloorplan, 0.0}},
                                        frame);
    ASSERT_EQ(map.floors.size(), 2u);
    EXPECT_EQ(map.floors[0].floor_z_m, 0.0);
    const IndoorFloor& f = map.floors[1];
    ASSERT_EQ(f.walkable.size(), 1u);
    EXPECT_EQ(f.walls.size(), 1u);
    EXPECT_NEAR(f.walkable[0].outer_en[2].x(), 10.0, 1e-6);
    ASSERT_EQ(f.walkways_en.size(), 1u);
    EXPECT_NEAR(f.walkways_en[0][0].x(), 1.0, 0.5);
    EXPECT_NEAR(f.walkways_en[0][0].y(), 5.0, 0.5);
    EXPECT_EQ(map.layers[0].unknown_types.at("Toilet"), 1u);
    EXPECT_NE(map.layers[0].Summary().find("Toilet"), std::string::npos);

    const std::string walls =
        Write("walls.geojson", Collection(kCrs32632, PolygonFeature("\"Wall\"", sq(0, 0, 1, 1))));
    try {
        LoadIndoorMap({{walls, IndoorLayerRole::kFloorplan, 0.0}}, frame);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(walls), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("no walkable polygon"), std::string::npos);
    }
    const std::string unknown =
        Write("unknown.geojson",
              Collection(R"("crs": {"type": "name", "properties": {"name": "EPSG:999999"}})",
                         PolygonFeature("\"Room\"", sq(0, 0, 1, 1))));
    EXPECT_THROW(LoadIndoorMap({{unknown, IndoorLayerRole::kFloorplan, 0.0}}, frame), InputError);

    // A corridor whose outline crosses itself (a bow tie): bad input naming the feature and
    // where, not a map whose inside is whatever the rasteriser makes of it.
    std::ostringstream bow;
    bow.precision(12);
    bow << "[[" << e0 << "," << n0 << "],[" << e0 + 10 << "," << n0 + 10 << "],[" << e0 + 10 << ","
        << n0 << "],[" << e0 << "," << n0 + 10 << "],[" << e0 << "," << n0 << "]]";
    const std::string crossed =
        Write("crossed.geojson",
              Collection(kCrs32632, PolygonFeature("\"Room\"", sq(20, 0, 30, 10)) + ",\n" +
                                        PolygonFeature("\"Corridor\"", bow.str())));
    try {
        LoadIndoorMap({{crossed, IndoorLayerRole::kFloorplan, 0.0}}, frame);
        FAIL() << "no error";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("features[1]"), std::string::npos) << what;
        EXPECT_NE(what.find("Corridor crosses itself at (" + std::to_string(int(e0 + 5))),
                  std::string::npos)
            << what;
    }
}

TEST(RingSelfCrossing, FindsWhereTwoEdgesCross) {
    using V = Eigen::Vector2d;
    const std::vector<V> bow = {V(0, 0), V(2, 2), V(2, 0), V(0, 2), V(0, 0)};
    const std::optional<V> x = RingSelfCrossing(bow);
    ASSERT_TRUE(x.has_value());
    EXPECT_NEAR(x->x(), 1.0, 1e-12);
    EXPECT_NEAR(x->y(), 1.0, 1e-12);
    // Open ring (no repeated first point): the same.
    EXPECT_TRUE(RingSelfCrossing({V(0, 0), V(2, 2), V(2, 0), V(0, 2)}).has_value());
    // Simple rings, convex and not, closed or open; a vertex touching an edge is not a crossing.
    EXPECT_FALSE(RingSelfCrossing({V(0, 0), V(2, 0), V(2, 2), V(0, 2), V(0, 0)}).has_value());
    EXPECT_FALSE(RingSelfCrossing({V(0, 0), V(4, 0), V(4, 4), V(2, 1), V(0, 4)}).has_value());
    // A vertex on another edge, with a collinear overlap: no proper crossing either.
    EXPECT_FALSE(RingSelfCrossing({V(0, 0), V(4, 0), V(2, 0), V(2, 3)}).has_value());
    // Found whatever the edges' order along x: the third edge crosses the first at (1.6, 0).
    const std::optional<V> y = RingSelfCrossing({V(0, 0), V(4, 0), V(4, 4), V(1, -1)});
    ASSERT_TRUE(y.has_value());
    EXPECT_NEAR(y->x(), 1.6, 1e-12);
    EXPECT_NEAR(y->y(), 0.0, 1e-12);
}

// ---------------------------------------------------------------- real data

TEST(IndoorHcu, LayersLoadAndGroundTruthLiesInTraversableSpace) {
    const fs::path dir = fs::path(DRIFTCORR_SHARED_DATASETS) / "hcu_eight";
    if (!fs::exists(dir / "scenario.yaml") || !fs::exists(dir / "Plan4OG.geojson")) {
        GTEST_SKIP() << "real data not present: " << dir;
    }
    std::ifstream yaml(dir / "scenario.yaml");
    const std::string text((std::istreambuf_iterator<char>(yaml)),
                           std::istreambuf_iterator<char>());
    auto number = [&](const std::string& key) {
        std::smatch m;
        EXPECT_TRUE(std::regex_search(text, m, std::regex(key + R"(:\s*([-0-9.]+))"))) << key;
        return std::stod(m[1].str());
    };
    const double e0 = number("easting_m"), n0 = number("northing_m"), z_m = number("z_m");
    IndoorFrame frame;
    frame.anchor_crs = "EPSG:32632";
    frame.anchor_crs_to_en = [&](const Eigen::Vector2d& en) {
        return Eigen::Vector2d(en.x() - e0, en.y() - n0);
    };
    std::vector<IndoorLayerSpec> layers;
    for (const auto& [name, z] :
         {std::pair<const char*, double>{"EG", 1.3}, {"1OG", 7.6}, {"4OG", 19.6}}) {
        layers.push_back({(dir / (std::string("Route") + name + ".geojson")).string(),
                          IndoorLayerRole::kWalkways, z});
        layers.push_back({(dir / (std::string("Plan") + name + ".geojson")).string(),
                          IndoorLayerRole::kFloorplan, z});
    }
    const IndoorMap map = LoadIndoorMap(layers, frame);
    ASSERT_EQ(map.layers.size(), 6u);
    ASSERT_EQ(map.floors.size(), 3u);
    std::size_t skipped = 0;
    for (const auto& l : map.layers) {
        for (const auto& [reason, count] : l.skipped) skipped += count;
        std::cout << l.Summary() << "\n";
    }
    EXPECT_GT(skipped, 0u);  // the plans carry features with null geometry
    IndoorFieldConfig c;
    c.resolution_m = 0.1;
    c.resolution_z_m = 0.5;
    IndoorFieldStats stats;
    const TraversableField field = BuildIndoorField(map.floors, c, &stats);
    EXPECT_NEAR(map.floors[2].floor_z_m, 19.6, 1e-9);
    EXPECT_GT(stats.walkable_area_m2[2], 1000.0);
    std::cout << "voxels " << stats.voxels << ", walkable area EG/1OG/4OG "
              << stats.walkable_area_m2[0] << " / " << stats.walkable_area_m2[1] << " / "
              << stats.walkable_area_m2[2] << " m2\n";

    std::ifstream gt(dir / "ground_truth.tum");
    std::string row;
    std::size_t n = 0, within = 0, inside = 0;
    double worst = -1e9;
    while (std::getline(gt, row)) {
        std::istringstream in(row);
        double t, x, y, z;
        if (!(in >> t >> x >> y >> z)) continue;
        const auto q = field.Query({x, y, z + z_m});
        ++n;
        if (!q) continue;
        within += q->corridor.value <= 1.5;
        inside += q->corridor.value <= 0.0;
        worst = std::max(worst, q->corridor.value);
    }
    ASSERT_GT(n, 200u);
    const double share = double(within) / n;
    std::cout << "hcu_eight ground truth within 1.5 m of the 4OG traversable set: " << within
              << " / " << n << " (" << 100.0 * share << " %); inside: " << inside
              << "; worst corridor " << worst << " m\n";
    RecordProperty("gt_within_1_5m_share", std::to_string(share));
    EXPECT_GT(share, 0.9);
}

}  // namespace
