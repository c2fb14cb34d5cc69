// Tests of the OpenStreetMap PBF reader (mapping/src/osm_pbf_reader.cpp): the PBF and the XML of
// one extract give the same ways and the same road network; a truncated or foreign file is bad
// input naming the file. PBF files are written here with libosmium's own writer.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <osmium/builder/attr.hpp>
#include <osmium/builder/osm_object_builder.hpp>
#include <osmium/io/pbf_input.hpp>
#include <osmium/io/pbf_output.hpp>
#include <osmium/io/xml_input.hpp>
#include <string>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/geodesy.h"
#include "driftcorr/mapping/osm_reader.h"
#include "driftcorr/mapping/road_network.h"

namespace driftcorr {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "osm_pbf";
    fs::create_directories(dir);
    return dir;
}

std::string WriteText(const std::string& name, const std::string& content) {
    const fs::path path = TempDir() / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << content;
    out.close();
    EXPECT_TRUE(out) << "could not write " << path;
    return path.string();
}

std::string ReadBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The same small extract as XML and as osmium objects: three nodes of a residential way (listed
// out of id order), a pedestrian area, a way with a missing node, a way that is no highway.
const char* kExtractXml = R"(<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="test">
  <node id="1" version="1" lat="48.1000000" lon="8.1000000"/>
  <node id="2" version="1" lat="48.2000000" lon="8.2000000"/>
  <node id="3" version="1" lat="48.3000001" lon="8.2999999"/>
  <node id="4" version="1" lat="-48.4000000" lon="-8.4000000"/>
  <way id="10" version="1">
    <nd ref="3"/><nd ref="1"/><nd ref="2"/>
    <tag k="highway" v="residential"/><tag k="width" v="7.5"/><tag k="lanes" v="2"/>
  </way>
  <way id="11" version="1">
    <nd ref="1"/><nd ref="4"/>
    <tag k="highway" v="pedestrian"/><tag k="width" v="7 m"/><tag k="area" v="yes"/>
  </way>
  <way id="12" version="1">
    <nd ref="2"/><nd ref="99"/>
    <tag k="highway" v="service"/>
  </way>
  <way id="13" version="1">
    <nd ref="1"/><nd ref="2"/>
    <tag k="building" v="yes"/>
  </way>
</osm>
)";

std::string WriteExtractPbf(const std::string& name) {
    using namespace osmium::builder::attr;  // NOLINT: the builder's attribute vocabulary
    osmium::memory::Buffer buffer{4096, osmium::memory::Buffer::auto_grow::yes};
    osmium::builder::add_node(buffer, _id(1), _version(1), _location(8.1, 48.1));
    osmium::builder::add_node(buffer, _id(2), _version(1), _location(8.2, 48.2));
    osmium::builder::add_node(buffer, _id(3), _version(1), _location(8.2999999, 48.3000001));
    osmium::builder::add_node(buffer, _id(4), _version(1), _location(-8.4, -48.4));
    osmium::builder::add_way(buffer, _id(10), _version(1), _nodes({3, 1, 2}),
                             _tag("highway", "residential"), _tag("width", "7.5"),
                             _tag("lanes", "2"));
    osmium::builder::add_way(buffer, _id(11), _version(1), _nodes({1, 4}),
                             _tag("highway", "pedestrian"), _tag("width", "7 m"),
                             _tag("area", "yes"));
    osmium::builder::add_way(buffer, _id(12), _version(1), _nodes({2, 99}),
                             _tag("highway", "service"));
    osmium::builder::add_way(buffer, _id(13), _version(1), _nodes({1, 2}), _tag("building", "yes"));
    const std::string path = (TempDir() / name).string();
    osmium::io::Writer writer{path, osmium::io::Header{}, osmium::io::overwrite::allow};
    writer(std::move(buffer));
    writer.close();
    return path;
}

// OSM PBF stores coordinates in units of 1e-7 degrees, as the XML writes them; the two parse into
// doubles that may differ in the last bit.
constexpr double kCoordinateTolDeg = 1e-9;

void ExpectSameRoads(const OsmRoads& a, const OsmRoads& b) {
    EXPECT_EQ(a.report.nodes_total, b.report.nodes_total);
    EXPECT_EQ(a.report.ways_total, b.report.ways_total);
    EXPECT_EQ(a.report.ways_highway, b.report.ways_highway);
    EXPECT_EQ(a.report.missing_node_refs, b.report.missing_node_refs);
    EXPECT_EQ(a.report.ways_too_short, b.report.ways_too_short);
    ASSERT_EQ(a.ways.size(), b.ways.size());
    for (std::size_t i = 0; i < a.ways.size(); ++i) {
        const OsmWay& wa = a.ways[i];
        const OsmWay& wb = b.ways[i];
        ASSERT_EQ(wa.id, wb.id) << "way #" << i;
        EXPECT_EQ(wa.highway, wb.highway) << "way " << wa.id;
        EXPECT_EQ(wa.width_m, wb.width_m) << "way " << wa.id;
        EXPECT_EQ(wa.lanes, wb.lanes) << "way " << wa.id;
        EXPECT_EQ(wa.is_area, wb.is_area) << "way " << wa.id;
        ASSERT_EQ(wa.nodes.size(), wb.nodes.size()) << "way " << wa.id;
        for (std::size_t k = 0; k < wa.nodes.size(); ++k) {
            ASSERT_NEAR(wa.nodes[k].lat_deg, wb.nodes[k].lat_deg, kCoordinateTolDeg);
            ASSERT_NEAR(wa.nodes[k].lon_deg, wb.nodes[k].lon_deg, kCoordinateTolDeg);
        }
    }
}

InputError ExpectInputError(const std::string& path) {
    try {
        ReadOsmRoads(path);
    } catch (const InputError& e) {
        return e;
    }
    ADD_FAILURE() << "ReadOsmRoads(" << path << ") did not throw InputError";
    return InputError(path, 0, "", "no error");
}

TEST(OsmPbf, SameWaysAsTheXmlOfTheSameExtract) {
    const OsmRoads xml = ReadOsmRoads(WriteText("extract.osm", kExtractXml));
    const OsmRoads pbf = ReadOsmRoads(WriteExtractPbf("extract.osm.pbf"));
    ASSERT_EQ(xml.ways.size(), 2u);  // 10 and 11; 12 has one resolvable node, 13 is no highway
    EXPECT_EQ(pbf.ways.front().id, 10);
    EXPECT_EQ(pbf.ways.front().width_m, 7.5);
    EXPECT_EQ(pbf.ways.front().lanes, 2);
    EXPECT_TRUE(pbf.ways.back().is_area);
    EXPECT_NEAR(pbf.ways.front().nodes.front().lat_deg, 48.3000001, kCoordinateTolDeg);
    ExpectSameRoads(xml, pbf);
}

TEST(OsmPbf, FormatIsTakenFromTheContentNotTheName) {
    const std::string pbf = WriteExtractPbf("extract_named_osm.pbf");
    const fs::path renamed = TempDir() / "extract_pbf_inside.osm";
    fs::copy_file(pbf, renamed, fs::copy_options::overwrite_existing);
    EXPECT_EQ(ReadOsmRoads(renamed.string()).ways.size(), 2u);
    EXPECT_EQ(ReadOsmRoads(WriteText("xml_inside.pbf", kExtractXml)).ways.size(), 2u);
}

TEST(OsmPbf, TruncatedFileIsBadInputNamingTheFile) {
    const std::string whole = ReadBytes(WriteExtractPbf("whole.osm.pbf"));
    ASSERT_GT(whole.size(), 40u);
    for (const std::size_t keep : {std::size_t(3), std::size_t(20), whole.size() - 10}) {
        const std::string path =
            WriteText("truncated_" + std::to_string(keep) + ".osm.pbf", whole.substr(0, keep));
        const InputError e = ExpectInputError(path);
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(std::string(e.what()).find("PBF"), std::string::npos) << e.what();
    }
}

TEST(OsmPbf, FileThatIsNotPbfIsBadInputNamingTheFile) {
    const std::string path = WriteText("kitti_poses.osm.pbf", "1 0 0 0 0 1 0 0 0 0 1 0\n");
    const InputError e = ExpectInputError(path);
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("neither OSM XML"), std::string::npos) << e.what();
}

TEST(OsmPbf, FolderIsBadInput) {
    const fs::path dir = TempDir() / "a_folder.osm.pbf";
    fs::create_directories(dir);
    EXPECT_EQ(ExpectInputError(dir.string()).file(), dir.string());
}

// A real extract (KITTI 00's map.osm) converted to PBF by libosmium's own XML reader and PBF
// writer: the ways and the road network built from them are the same as from the XML.
TEST(OsmPbf, Kitti00MapGivesTheSameRoadNetworkFromPbf) {
    const fs::path xml_path =
        fs::path(DRIFTCORR_SHARED_DATASETS) / "kitti00_cvo_stereo_geometric" / "map.osm";
    if (!fs::exists(xml_path)) GTEST_SKIP() << "dataset not present: " << xml_path;
    const std::string pbf_path = (TempDir() / "kitti00_map.osm.pbf").string();
    {
        osmium::io::Reader reader{xml_path.string()};
        osmium::io::Writer writer{pbf_path, reader.header(), osmium::io::overwrite::allow};
        while (osmium::memory::Buffer buffer = reader.read()) writer(std::move(buffer));
        writer.close();
        reader.close();
    }
    const OsmRoads xml = ReadOsmRoads(xml_path.string());
    const OsmRoads pbf = ReadOsmRoads(pbf_path);
    fs::remove(pbf_path);  // derived from the dataset: not kept
    ASSERT_GT(xml.ways.size(), 100u);
    ExpectSameRoads(xml, pbf);

    const LocalTangentPlane ltp(GeoPoint{48.9825452359, 8.3903661000, 0.0});
    const auto to_en = [&](const GeoPoint& g) { return Eigen::Vector2d(ltp.ToEnu(g).head<2>()); };
    const RoadNetwork net_xml = BuildRoadNetwork(xml, to_en, RoadClassConfig{});
    const RoadNetwork net_pbf = BuildRoadNetwork(pbf, to_en, RoadClassConfig{});
    ASSERT_EQ(net_xml.roads.size(), net_pbf.roads.size());
    EXPECT_EQ(net_xml.ways_excluded_by_class, net_pbf.ways_excluded_by_class);
    EXPECT_NEAR(net_xml.TotalLengthM(), net_pbf.TotalLengthM(), 1e-3);
    for (std::size_t i = 0; i < net_xml.roads.size(); ++i) {
        ASSERT_EQ(net_xml.roads[i].osm_id, net_pbf.roads[i].osm_id);
        ASSERT_EQ(net_xml.roads[i].half_width_m, net_pbf.roads[i].half_width_m);
        ASSERT_EQ(net_xml.roads[i].points_en.size(), net_pbf.roads[i].points_en.size());
        for (std::size_t k = 0; k < net_xml.roads[i].points_en.size(); ++k) {
            ASSERT_LT((net_xml.roads[i].points_en[k] - net_pbf.roads[i].points_en[k]).norm(),
                      1e-3);  // 1e-9 deg is 0.1 mm
        }
    }
}

}  // namespace
}  // namespace driftcorr
