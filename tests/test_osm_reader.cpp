// Tests of the OpenStreetMap reader (mapping/src/osm_reader.cpp) and the geodesy adapters
// (mapping/src/geodesy.cpp). Every reader test writes its own tiny .osm file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/geodesy.h"
#include "driftcorr/mapping/osm_reader.h"

namespace driftcorr {
namespace {

namespace fs = std::filesystem;

/// Writes `content` to DRIFTCORR_TEST_TMPDIR/osm_reader/<name> and returns the path.
std::string WriteTempFile(const std::string& name, const std::string& content) {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "osm_reader";
    fs::create_directories(dir);
    const fs::path path = dir / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << content;
    out.close();
    EXPECT_TRUE(out) << "could not write " << path;
    return path.string();
}

/// Wraps body lines in the usual OSM header; the <osm> element starts on line 2.
std::string Osm(const std::string& body) {
    return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<osm version=\"0.6\">\n" + body +
           "</osm>\n";
}

/// Expects ReadOsmRoads(path) to throw an InputError and returns it for further checks.
InputError ExpectInputError(const std::string& path) {
    try {
        ReadOsmRoads(path);
    } catch (const InputError& e) {
        return e;
    }
    ADD_FAILURE() << "ReadOsmRoads(" << path << ") did not throw InputError";
    return InputError(path, 0, "", "no error");
}

const OsmWay* FindWay(const OsmRoads& roads, std::int64_t id) {
    for (const OsmWay& way : roads.ways) {
        if (way.id == id) return &way;
    }
    return nullptr;
}

// ---------------------------------------------------------------------------------------------
// ReadOsmRoads: content

TEST(OsmReader, ParsesHighwayWaysTagsAndNodeOrder) {
    const std::string path = WriteTempFile("ways_and_tags.osm", Osm(R"(
  <bounds minlat="48.0" minlon="8.0" maxlat="49.0" maxlon="9.0"/>
  <node id="1" lat="48.10" lon="8.10"/>
  <node id="2" lat="48.20" lon="8.20"/>
  <node id="3" lat="48.30" lon="8.30"/>
  <node id="-4" lat="-48.40" lon="-8.40"/>
  <way id="10">
    <nd ref="3"/><nd ref="1"/><nd ref="2"/>
    <tag k="highway" v="residential"/>
    <tag k="width" v="7.5"/>
    <tag k="lanes" v="2"/>
  </way>
  <way id="11">
    <nd ref="1"/><nd ref="-4"/>
    <tag k="name" v="Marktplatz"/>
    <tag k="highway" v="pedestrian"/>
    <tag k="width" v="7 m"/>
    <tag k="area" v="yes"/>
  </way>
  <way id="12">
    <nd ref="1"/><nd ref="2"/><nd ref="3"/><nd ref="1"/>
    <tag k="building" v="yes"/>
  </way>
  <relation id="20">
    <member type="way" ref="12" role="outer"/>
    <tag k="highway" v="secondary"/>
  </relation>
)"));
    const OsmRoads roads = ReadOsmRoads(path);

    ASSERT_EQ(roads.ways.size(), 2u);
    EXPECT_EQ(roads.report.nodes_total, 4u);
    EXPECT_EQ(roads.report.ways_total, 3u);
    EXPECT_EQ(roads.report.ways_highway, 2u);
    EXPECT_EQ(roads.report.missing_node_refs, 0u);
    EXPECT_EQ(roads.report.ways_too_short, 0u);

    const OsmWay* residential = FindWay(roads, 10);
    ASSERT_NE(residential, nullptr);
    EXPECT_EQ(residential->highway, "residential");
    EXPECT_DOUBLE_EQ(residential->width_m, 7.5);
    EXPECT_EQ(residential->lanes, 2);
    EXPECT_FALSE(residential->is_area);
    ASSERT_EQ(residential->nodes.size(), 3u);  // way order 3, 1, 2, not id order
    EXPECT_DOUBLE_EQ(residential->nodes[0].lat_deg, 48.30);
    EXPECT_DOUBLE_EQ(residential->nodes[0].lon_deg, 8.30);
    EXPECT_DOUBLE_EQ(residential->nodes[1].lat_deg, 48.10);
    EXPECT_DOUBLE_EQ(residential->nodes[2].lat_deg, 48.20);
    EXPECT_DOUBLE_EQ(residential->nodes[2].lon_deg, 8.20);
    EXPECT_DOUBLE_EQ(residential->nodes[2].alt_m, 0.0);

    const OsmWay* square = FindWay(roads, 11);
    ASSERT_NE(square, nullptr);
    EXPECT_EQ(square->highway, "pedestrian");
    EXPECT_DOUBLE_EQ(square->width_m, 7.0);
    EXPECT_EQ(square->lanes, 0);
    EXPECT_TRUE(square->is_area);
    ASSERT_EQ(square->nodes.size(), 2u);
    EXPECT_DOUBLE_EQ(square->nodes[1].lat_deg, -48.40);  // negative ids and coordinates
    EXPECT_DOUBLE_EQ(square->nodes[1].lon_deg, -8.40);
}

TEST(OsmReader, WidthAndLanesAcceptOnlyTheDocumentedForms) {
    struct Case {
        const char* width;
        double width_m;
        const char* lanes;
        int lanes_expected;
    };
    const Case cases[] = {
        {"7.5", 7.5, "2", 2},    {"7 m", 7.0, "1", 1},      {"12m", 12.0, " 3 ", 3},
        {"7 ft", 0.0, "2;3", 0}, {"narrow", 0.0, "two", 0}, {"7,5", 0.0, "-1", 0},
        {"-3", 0.0, "2.5", 0},   {"", 0.0, "", 0},
    };
    std::ostringstream body;
    body << "  <node id=\"1\" lat=\"1\" lon=\"1\"/>\n  <node id=\"2\" lat=\"2\" lon=\"2\"/>\n";
    for (std::size_t i = 0; i < std::size(cases); ++i) {
        body << "  <way id=\"" << 100 + i << "\"><nd ref=\"1\"/><nd ref=\"2\"/>"
             << "<tag k=\"highway\" v=\"service\"/><tag k=\"width\" v=\"" << cases[i].width
             << "\"/><tag k=\"lanes\" v=\"" << cases[i].lanes << "\"/></way>\n";
    }
    const OsmRoads roads = ReadOsmRoads(WriteTempFile("width_lanes.osm", Osm(body.str())));
    ASSERT_EQ(roads.ways.size(), std::size(cases));
    for (std::size_t i = 0; i < std::size(cases); ++i) {
        const OsmWay* way = FindWay(roads, 100 + static_cast<std::int64_t>(i));
        ASSERT_NE(way, nullptr);
        EXPECT_DOUBLE_EQ(way->width_m, cases[i].width_m) << "width=\"" << cases[i].width << "\"";
        EXPECT_EQ(way->lanes, cases[i].lanes_expected) << "lanes=\"" << cases[i].lanes << "\"";
    }
}

TEST(OsmReader, NodeTaggedHighwayFeaturesAreNotWays) {
    const std::string path = WriteTempFile("node_features.osm", Osm(R"(
  <node id="1" lat="48.1" lon="8.1">
    <tag k="highway" v="street_lamp"/>
  </node>
  <node id="2" lat="48.2" lon="8.2">
    <tag k="highway" v="traffic_signals"/>
  </node>
  <node id="3" lat="48.3" lon="8.3"><tag k="highway" v="crossing"/></node>
  <way id="10"><nd ref="1"/><nd ref="2"/><nd ref="3"/><tag k="highway" v="tertiary"/></way>
)"));
    const OsmRoads roads = ReadOsmRoads(path);
    ASSERT_EQ(roads.ways.size(), 1u);
    EXPECT_EQ(roads.ways[0].id, 10);
    EXPECT_EQ(roads.ways[0].highway, "tertiary");
    EXPECT_EQ(roads.ways[0].nodes.size(), 3u);
    EXPECT_EQ(roads.report.nodes_total, 3u);
}

TEST(OsmReader, MissingNodeRefsSplitTheWayAndShortPiecesAreDropped) {
    const std::string path = WriteTempFile("missing_refs.osm", Osm(R"(
  <node id="1" lat="48.1" lon="8.1"/>
  <node id="2" lat="48.2" lon="8.2"/>
  <node id="3" lat="48.3" lon="8.3"/>
  <node id="4" lat="48.4" lon="8.4"/>
  <way id="10"><nd ref="1"/><nd ref="2"/><nd ref="99"/><nd ref="3"/><nd ref="4"/><tag k="highway" v="primary"/></way>
  <way id="11"><nd ref="1"/><nd ref="98"/><tag k="highway" v="primary"/></way>
  <way id="12"><nd ref="97"/><nd ref="96"/><tag k="building" v="yes"/></way>
  <way id="13"><nd ref="1"/><nd ref="95"/><nd ref="4"/><tag k="highway" v="primary"/></way>
)"));
    const OsmRoads roads = ReadOsmRoads(path);
    // Way 10 becomes 1-2 and 3-4: no road is drawn from 2 to 3, where the file has no node.
    ASSERT_EQ(roads.ways.size(), 2u);
    EXPECT_EQ(roads.ways[0].id, 10);
    EXPECT_EQ(roads.ways[1].id, 10);
    ASSERT_EQ(roads.ways[0].nodes.size(), 2u);
    ASSERT_EQ(roads.ways[1].nodes.size(), 2u);
    EXPECT_DOUBLE_EQ(roads.ways[0].nodes[1].lat_deg, 48.2);
    EXPECT_DOUBLE_EQ(roads.ways[1].nodes[0].lat_deg, 48.3);
    EXPECT_EQ(roads.report.ways_total, 4u);
    EXPECT_EQ(roads.report.ways_highway, 2u);
    EXPECT_EQ(roads.report.missing_node_refs, 3u);  // 99, 98, 95; refs of non-highway ways ignored
    EXPECT_EQ(roads.report.ways_split, 1u);
    EXPECT_EQ(roads.report.ways_too_short, 2u);  // 11 and 13 keep single nodes only
}

TEST(OsmReader, ResolvesNodesListedAfterTheirWays) {
    const std::string path = WriteTempFile("forward_refs.osm", Osm(R"(
  <way id="10"><nd ref="1"/><nd ref="2"/><tag k="highway" v="track"/></way>
  <node id="1" lat="48.1" lon="8.1"/>
  <node id="2" lat="48.2" lon="8.2"/>
)"));
    const OsmRoads roads = ReadOsmRoads(path);
    ASSERT_EQ(roads.ways.size(), 1u);
    EXPECT_EQ(roads.ways[0].nodes.size(), 2u);
    EXPECT_EQ(roads.report.missing_node_refs, 0u);
}

TEST(OsmReader, FileWithoutHighwaysGivesEmptyWays) {
    const std::string path = WriteTempFile("no_highway.osm", Osm(R"(
  <node id="1" lat="48.1" lon="8.1"><tag k="highway" v="street_lamp"/></node>
  <node id="2" lat="48.2" lon="8.2"/>
  <way id="10"><nd ref="1"/><nd ref="2"/><tag k="waterway" v="stream"/></way>
)"));
    const OsmRoads roads = ReadOsmRoads(path);
    EXPECT_TRUE(roads.ways.empty());
    EXPECT_EQ(roads.report.ways_total, 1u);
    EXPECT_EQ(roads.report.ways_highway, 0u);
}

TEST(OsmReader, ParsesFilesLargerThanOneReadBlock) {
    // ~300 KB, so elements straddle the 64 KiB read-block boundaries.
    constexpr int kNodes = 4000;
    constexpr int kWays = 999;  // nodes (4i, 4i+1, 4i+2, 4i+3) per way
    std::ostringstream body;
    body.precision(10);
    for (int i = 0; i < kNodes; ++i) {
        body << "  <node id=\"" << i << "\" lat=\"" << 48.9 + 1e-5 * i << "\" lon=\""
             << 8.3 + 2e-5 * i << "\" version=\"3\" user=\"someone\"/>\n";
    }
    for (int w = 0; w < kWays; ++w) {
        body << "  <way id=\"" << 100000 + w << "\">\n";
        for (int k = 0; k < 4; ++k) body << "    <nd ref=\"" << 4 * w + k << "\"/>\n";
        body << "    <tag k=\"highway\" v=\"residential\"/>\n  </way>\n";
    }
    const std::string content = Osm(body.str());
    ASSERT_GT(content.size(), 4u * 64u * 1024u);
    const OsmRoads roads = ReadOsmRoads(WriteTempFile("large.osm", content));
    ASSERT_EQ(roads.ways.size(), static_cast<std::size_t>(kWays));
    EXPECT_EQ(roads.report.nodes_total, static_cast<std::size_t>(kNodes));
    const OsmWay& last = roads.ways.back();
    EXPECT_EQ(last.id, 100000 + kWays - 1);
    ASSERT_EQ(last.nodes.size(), 4u);
    EXPECT_NEAR(last.nodes[3].lat_deg, 48.9 + 1e-5 * (4 * (kWays - 1) + 3), 1e-9);
    EXPECT_NEAR(last.nodes[3].lon_deg, 8.3 + 2e-5 * (4 * (kWays - 1) + 3), 1e-9);
}

// ---------------------------------------------------------------------------------------------
// ReadOsmRoads: errors (tier 2, InputError naming file and line)

TEST(OsmReader, MalformedXmlNamesFileAndLine) {
    const std::string path = WriteTempFile("malformed.osm",
                                           "<?xml version=\"1.0\"?>\n"  // line 1
                                           "<osm version=\"0.6\">\n"    // line 2
                                           "  <node id=\"1\" lat=\"48.1\" lon=\"8.1\"/>\n"
                                           "  <way id=\"10\">\n"   // line 4
                                           "    <nd ref=\"1\">\n"  // line 5: not closed
                                           "  </way>\n"            // line 6: mismatch
                                           "</osm>\n");
    const InputError error = ExpectInputError(path);
    EXPECT_EQ(error.file(), path);
    EXPECT_EQ(error.line(), 6);
    const std::string what = error.what();
    EXPECT_NE(what.find(path + ":6"), std::string::npos) << what;
    EXPECT_NE(what.find("mismatched tag"), std::string::npos) << what;
}

TEST(OsmReader, TruncatedFileIsMalformed) {
    const std::string path = WriteTempFile(
        "truncated.osm", "<?xml version=\"1.0\"?>\n<osm version=\"0.6\">\n  <node id=\"1\" la");
    const InputError error = ExpectInputError(path);
    EXPECT_EQ(error.line(), 3);
    EXPECT_NE(std::string(error.what()).find(path), std::string::npos);
}

TEST(OsmReader, EmptyFileIsMalformed) {
    const InputError error = ExpectInputError(WriteTempFile("empty.osm", ""));
    EXPECT_NE(std::string(error.what()).find("malformed XML"), std::string::npos) << error.what();
}

TEST(OsmReader, BadNodeCoordinatesNameLineAndKey) {
    struct Case {
        const char* attributes;
        const char* key;
    };
    const Case cases[] = {
        {R"(lat="91.0" lon="8.1")", "lat"},
        {R"(lat="-90.5" lon="8.1")", "lat"},
        {R"(lat="abc" lon="8.1")", "lat"},
        {R"(lat="48.1x" lon="8.1")", "lat"},
        {R"(lat="nan" lon="8.1")", "lat"},
        {R"(lat="inf" lon="8.1")", "lat"},
        {R"(lon="8.1")", "lat"},
        {R"(lat="48.1" lon="180.01")", "lon"},
        {R"(lat="48.1" lon="")", "lon"},
        {R"(lat="48.1")", "lon"},
    };
    int index = 0;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.attributes);
        const std::string good_node = "  <node id=\"1\" lat=\"48.1\" lon=\"8.1\"/>\n";  // line 3
        const std::string bad_node = "  <node id=\"2\" " + std::string(c.attributes) + "/>\n";
        const std::string path = WriteTempFile("bad_coord_" + std::to_string(index++) + ".osm",
                                               Osm(good_node + bad_node));  // bad node: line 4
        const InputError error = ExpectInputError(path);
        EXPECT_EQ(error.line(), 4);
        EXPECT_EQ(error.key(), c.key);
        const std::string what = error.what();
        EXPECT_NE(what.find(path + ":4"), std::string::npos) << what;
        EXPECT_NE(what.find("node 2"), std::string::npos) << what;
    }
}

TEST(OsmReader, CoordinatesOnTheLimitsAreValid) {
    const std::string path = WriteTempFile("limits.osm", Osm(R"(
  <node id="1" lat="90" lon="180"/>
  <node id="2" lat="-90.0" lon="-180.0"/>
  <way id="10"><nd ref="1"/><nd ref="2"/><tag k="highway" v="path"/></way>
)"));
    const OsmRoads roads = ReadOsmRoads(path);
    ASSERT_EQ(roads.ways.size(), 1u);
    EXPECT_DOUBLE_EQ(roads.ways[0].nodes[1].lon_deg, -180.0);
}

TEST(OsmReader, MissingFileThrows) {
    const std::string path =
        (fs::path(DRIFTCORR_TEST_TMPDIR) / "osm_reader" / "does_not_exist.osm").string();
    const InputError error = ExpectInputError(path);
    EXPECT_EQ(error.file(), path);
    EXPECT_NE(std::string(error.what()).find("cannot open"), std::string::npos) << error.what();
}

TEST(OsmReader, DirectoryIsNotReadable) {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "osm_reader" / "a_directory.osm";
    fs::create_directories(dir);
    const InputError error = ExpectInputError(dir.string());
    EXPECT_EQ(error.file(), dir.string());
}

TEST(OsmReader, RootElementMustBeOsm) {
    const std::string path =
        WriteTempFile("wrong_root.osm", "<?xml version=\"1.0\"?>\n<gpx version=\"1.1\">\n</gpx>\n");
    const InputError error = ExpectInputError(path);
    EXPECT_EQ(error.line(), 2);
    EXPECT_NE(std::string(error.what()).find("<osm>"), std::string::npos) << error.what();
}

TEST(OsmReader, NonIntegerNodeRefIsAnError) {
    const std::string path = WriteTempFile("bad_ref.osm", Osm(R"(
  <way id="10"><nd ref="1"/><nd ref="one"/><tag k="highway" v="path"/></way>
)"));
    const InputError error = ExpectInputError(path);
    EXPECT_EQ(error.line(), 4);  // the raw string starts with a newline: line 3 is blank
    EXPECT_EQ(error.key(), "ref");
}

// ---------------------------------------------------------------------------------------------
// ReadOsmRoads on a real extract (KITTI 00, Karlsruhe)

TEST(OsmReader, ReadsKitti00Map) {
    const fs::path path =
        fs::path(DRIFTCORR_SHARED_DATASETS) / "kitti00_cvo_stereo_geometric" / "map.osm";
    if (!fs::exists(path)) GTEST_SKIP() << "dataset not present: " << path;

    const OsmRoads roads = ReadOsmRoads(path.string());
    EXPECT_GT(roads.ways.size(), 100u);
    EXPECT_EQ(roads.report.ways_highway, roads.ways.size());
    std::set<std::string> classes;
    for (const OsmWay& way : roads.ways) {
        classes.insert(way.highway);
        ASSERT_GE(way.nodes.size(), 2u) << "way " << way.id;
        for (const GeoPoint& p : way.nodes) {
            ASSERT_NEAR(p.lat_deg, 48.98, 0.05) << "way " << way.id;
            ASSERT_NEAR(p.lon_deg, 8.39, 0.05) << "way " << way.id;
        }
    }
    for (const char* expected : {"residential", "tertiary", "secondary"}) {
        EXPECT_EQ(classes.count(expected), 1u) << "no highway=" << expected;
    }
    // Point features tagged on nodes must not appear as ways.
    EXPECT_EQ(classes.count("street_lamp"), 0u);
    EXPECT_EQ(classes.count("traffic_signals"), 0u);
}

// ---------------------------------------------------------------------------------------------
// Geodesy adapters

TEST(LocalTangentPlane, RoundTripIsExact) {
    const LocalTangentPlane ltp(GeoPoint{48.98, 8.39, 115.0});
    const GeoPoint points[] = {
        {48.98, 8.39, 115.0}, {48.99, 8.40, 120.0}, {48.95, 8.35, 100.0}, {49.02, 8.31, 0.0}};
    for (const GeoPoint& p : points) {
        const GeoPoint back = ltp.ToGeo(ltp.ToEnu(p));
        EXPECT_NEAR(back.lat_deg, p.lat_deg, 1e-9);
        EXPECT_NEAR(back.lon_deg, p.lon_deg, 1e-9);
        EXPECT_NEAR(back.alt_m, p.alt_m, 1e-6);
    }
    EXPECT_NEAR(ltp.ToEnu(ltp.origin()).norm(), 0.0, 1e-9);
}

TEST(LocalTangentPlane, AxesAreEastNorthUp) {
    const LocalTangentPlane ltp(GeoPoint{49.0, 8.39, 0.0});
    // One milli-degree of latitude at 49 deg is about 111.2 m (meridian arc, WGS84).
    const Eigen::Vector3d north = ltp.ToEnu(GeoPoint{49.001, 8.39, 0.0});
    EXPECT_NEAR(north.y(), 111.2, 0.5);
    EXPECT_NEAR(north.x(), 0.0, 1e-6);
    EXPECT_NEAR(north.z(), 0.0, 0.01);  // earth curvature over 111 m: ~1 mm
    // One milli-degree of longitude is shorter by cos(49 deg): about 73.2 m east.
    const Eigen::Vector3d east = ltp.ToEnu(GeoPoint{49.0, 8.391, 0.0});
    EXPECT_NEAR(east.x(), 73.2, 0.5);
    EXPECT_NEAR(east.y(), 0.0, 0.01);
}

TEST(CrsProjection, Utm32KnownValueAndRoundTrip) {
    const CrsProjection utm("urn:ogc:def:crs:EPSG::32632");
    EXPECT_EQ(utm.name(), "EPSG:32632");
    // Reference from GeographicLib::UTMUPS::Forward(53.5, 10.0, zone 32), an independent
    // transverse Mercator implementation (cs2cs was not installed): 566331.528 E, 5928359.088 N.
    const Eigen::Vector2d en = utm.FromGeo(GeoPoint{53.5, 10.0, 0.0});
    EXPECT_NEAR(en.x(), 566331.528, 0.01);
    EXPECT_NEAR(en.y(), 5928359.088, 0.01);
    for (const GeoPoint& p :
         {GeoPoint{53.5, 10.0, 0.0}, GeoPoint{48.98, 8.39, 0.0}, GeoPoint{0.5, 6.1, 0.0}}) {
        const GeoPoint back = utm.ToGeo(utm.FromGeo(p));
        EXPECT_NEAR(back.lat_deg, p.lat_deg, 1e-9);
        EXPECT_NEAR(back.lon_deg, p.lon_deg, 1e-9);
        EXPECT_DOUBLE_EQ(back.alt_m, 0.0);
    }
    // The central meridian (9 deg E) maps to the false easting of 500 km.
    EXPECT_NEAR(utm.FromGeo(GeoPoint{50.0, 9.0, 0.0}).x(), 500000.0, 1e-6);
}

TEST(CrsProjection, OutputIsEastingNorthingWhateverTheAxisOrder) {
    // EPSG:2193 (NZTM) declares northing first; the adapter still returns (easting, northing).
    const CrsProjection nztm("EPSG:2193");
    const Eigen::Vector2d en = nztm.FromGeo(GeoPoint{-41.29, 174.78, 0.0});  // Wellington
    EXPECT_GT(en.x(), 1.70e6);
    EXPECT_LT(en.x(), 1.80e6);
    EXPECT_GT(en.y(), 5.40e6);
    EXPECT_LT(en.y(), 5.45e6);
    const GeoPoint back = nztm.ToGeo(en);
    EXPECT_NEAR(back.lat_deg, -41.29, 1e-9);
    EXPECT_NEAR(back.lon_deg, 174.78, 1e-9);
    EXPECT_NO_THROW(CrsProjection("EPSG:25832"));  // ETRS89 / UTM 32N
    EXPECT_NO_THROW(CrsProjection("EPSG:3857"));   // web Mercator
}

TEST(CrsProjection, RejectsWhatIsNotAMetricProjectedCrs) {
    EXPECT_THROW(CrsProjection("EPSG:4326"), std::invalid_argument);    // geographic
    EXPECT_THROW(CrsProjection("OGC:CRS84"), std::invalid_argument);    // geographic
    EXPECT_THROW(CrsProjection("EPSG:4978"), std::invalid_argument);    // geocentric
    EXPECT_THROW(CrsProjection("EPSG:2263"), std::invalid_argument);    // US survey feet
    EXPECT_THROW(CrsProjection("EPSG:999999"), std::invalid_argument);  // unknown code
    EXPECT_THROW(CrsProjection("not a crs"), std::invalid_argument);
    try {
        CrsProjection("bogus-crs");
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("bogus-crs"), std::string::npos) << e.what();
    }
}

TEST(NormaliseCrsName, AcceptsTheUsualSpellings) {
    EXPECT_EQ(NormaliseCrsName("urn:ogc:def:crs:EPSG::32632"), "EPSG:32632");
    EXPECT_EQ(NormaliseCrsName("urn:ogc:def:crs:EPSG:6.6:32632"), "EPSG:32632");
    EXPECT_EQ(NormaliseCrsName("EPSG:32632"), "EPSG:32632");
    EXPECT_EQ(NormaliseCrsName("epsg:32632"), "EPSG:32632");
    EXPECT_EQ(NormaliseCrsName(" EPSG:25832 "), "EPSG:25832");
    EXPECT_EQ(NormaliseCrsName("urn:ogc:def:crs:OGC:1.3:CRS84"), "OGC:CRS84");
    EXPECT_EQ(NormaliseCrsName("OGC:CRS84"), "OGC:CRS84");
}

TEST(NormaliseCrsName, RejectsJunk) {
    for (const char* junk : {"", "junk", "EPSG:", "EPSG:abc", "EPSG:32632x", "WGS84",
                             "urn:ogc:def:crs:EPSG::", "+proj=utm +zone=32"}) {
        EXPECT_EQ(NormaliseCrsName(junk), "") << "'" << junk << "'";
    }
}

}  // namespace
}  // namespace driftcorr
