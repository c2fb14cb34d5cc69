// The definitions of what scenario_files.h declares.
#include "scenario_files.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "driftcorr/core/angles.h"
#include "driftcorr/mapping/atomic_file.h"
#include "synth_common.h"

namespace driftcorr::synth {

namespace {

std::string XmlEscape(const std::string& text) {
    std::string out;
    for (char c : text) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            case '\'':
                out += "&apos;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string OsmBounds(const std::vector<GeoPoint>& geo) {
    double min_lat = std::numeric_limits<double>::infinity(), max_lat = -min_lat;
    double min_lon = min_lat, max_lon = -min_lat;
    for (const GeoPoint& g : geo) {
        min_lat = std::min(min_lat, g.lat_deg), max_lat = std::max(max_lat, g.lat_deg);
        min_lon = std::min(min_lon, g.lon_deg), max_lon = std::max(max_lon, g.lon_deg);
    }
    return Format("  <bounds minlat=\"%.9f\" minlon=\"%.9f\" maxlat=\"%.9f\" maxlon=\"%.9f\"/>\n",
                  min_lat, min_lon, max_lat, max_lon);
}

std::string OsmNodes(const RoadNetwork& net, const std::vector<GeoPoint>& geo) {
    std::vector<std::string> node_tag(net.nodes.size());
    for (const TaggedNode& t : net.tagged_nodes) node_tag[t.node_index] = t.highway;
    std::string xml;
    for (std::size_t i = 0; i < net.nodes.size(); ++i) {
        const std::string attrs =
            Format("  <node id=\"%lld\" lat=\"%.9f\" lon=\"%.9f\"",
                   static_cast<long long>(net.nodes[i].id), geo[i].lat_deg, geo[i].lon_deg);
        if (node_tag[i].empty()) {
            xml += attrs + "/>\n";
        } else {
            xml += attrs + ">\n    <tag k=\"highway\" v=\"" + XmlEscape(node_tag[i]) +
                   "\"/>\n  </node>\n";
        }
    }
    return xml;
}

std::string OsmWays(const RoadNetwork& net) {
    std::string xml;
    for (const RoadWay& way : net.ways) {
        xml += Format("  <way id=\"%lld\">\n", static_cast<long long>(way.id));
        for (int index : way.node_indices) {
            xml += Format("    <nd ref=\"%lld\"/>\n", static_cast<long long>(net.nodes[index].id));
        }
        xml += "    <tag k=\"highway\" v=\"" + XmlEscape(way.highway) + "\"/>\n";
        xml += "    <tag k=\"name\" v=\"" + XmlEscape(way.name) + "\"/>\n";
        xml += "  </way>\n";
    }
    return xml;
}

}  // namespace

void WriteOsmFile(const std::string& path, const RoadNetwork& net, const LocalTangentPlane& plane) {
    std::vector<GeoPoint> geo;
    for (const RoadNode& node : net.nodes) {
        geo.push_back(plane.ToGeo(Eigen::Vector3d(node.p_en.x(), node.p_en.y(), 0.0)));
    }
    std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
    xml += "<osm version=\"0.6\" generator=\"driftcorr synth\">\n";
    xml +=
        "  <!-- Synthetic road network made by driftcorr_make_road_scenario; not OSM data. -->\n";
    xml += OsmBounds(geo) + OsmNodes(net, geo) + OsmWays(net) + "</osm>\n";
    WriteFileAtomically(path, xml);
}

void WriteTumFile(const std::string& path, const std::vector<DrivePose>& poses) {
    std::string text;
    for (const DrivePose& pose : poses) {
        const double half_yaw_rad = 0.5 * WrapAngle(pose.yaw_rad);
        text +=
            Format("%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", pose.t_s, pose.p_en.x(),
                   pose.p_en.y(), 0.0, 0.0, 0.0, std::sin(half_yaw_rad), std::cos(half_yaw_rad));
    }
    WriteFileAtomically(path, text);
}

void WriteScenarioYaml(const std::string& path, const GeoPoint& anchor,
                       const std::vector<std::string>& header_comment) {
    std::string yaml;
    for (const std::string& line : header_comment) yaml += "# " + line + "\n";
    yaml += "name: synthetic-road-grid\n";
    yaml += "mode: road2d\n";
    yaml += "estimate:\n  path: estimate.tum\n  format: tum\n";
    yaml += "ground_truth:\n  path: ground_truth.tum\n  format: tum\n";
    yaml += "frame: enu\n";
    yaml += "anchor:\n";
    yaml += Format("  lat_deg: %.10g\n  lon_deg: %.10g\n  alt_m: %.3f\n", anchor.lat_deg,
                   anchor.lon_deg, anchor.alt_m);
    yaml += "  yaw_deg: 0.0\n";
    yaml += "map:\n  - path: map.osm\n    format: osm\n";
    WriteFileAtomically(path, yaml);
}

}  // namespace driftcorr::synth
