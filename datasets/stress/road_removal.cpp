// The definitions of what road_removal.h declares.
#include "road_removal.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <limits>

namespace driftcorr::stress {

AnchorPlane::AnchorPlane(const io::AnchorSpec& anchor) {
    if (anchor.IsGeographic()) {
        ltp_.emplace(GeoPoint{*anchor.lat_deg, *anchor.lon_deg, anchor.alt_m.value_or(0.0)});
    } else {
        crs_.emplace(*anchor.crs);
        crs_origin_ = Eigen::Vector2d(*anchor.easting_m, *anchor.northing_m);
    }
}

Eigen::Vector2d AnchorPlane::ToEn(const GeoPoint& geo) const {
    if (ltp_) return ltp_->ToEnu(geo).head<2>();
    return crs_->FromGeo(geo) - crs_origin_;
}

namespace {

double SegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                       const Eigen::Vector2d& b) {
    const Eigen::Vector2d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + s * ab - p).norm();
}

bool NearPolyline(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& line,
                  double radius_m) {
    for (std::size_t k = 1; k < line.size(); ++k) {
        if (SegmentDistance(p, line[k - 1], line[k]) <= radius_m) return true;
    }
    return false;
}

}  // namespace

std::vector<WayAlong> GroundTruthAlongWays(const std::vector<OsmWay>& ways,
                                           const std::vector<std::vector<Eigen::Vector2d>>& ways_en,
                                           const std::vector<Eigen::Vector2d>& gt_en,
                                           double radius_m) {
    std::vector<WayAlong> along;
    std::vector<char> near(gt_en.size());
    for (std::size_t w = 0; w < ways.size(); ++w) {
        Eigen::AlignedBox2d box;
        for (const Eigen::Vector2d& p : ways_en[w]) box.extend(p);
        box.min().array() -= radius_m;
        box.max().array() += radius_m;
        for (std::size_t k = 0; k < gt_en.size(); ++k) {
            near[k] = box.contains(gt_en[k]) && NearPolyline(gt_en[k], ways_en[w], radius_m);
        }
        WayAlong a{ways[w].id, ways[w].highway, 0.0};
        for (std::size_t k = 1; k < gt_en.size(); ++k) {
            if (near[k] && near[k - 1]) a.along_m += (gt_en[k] - gt_en[k - 1]).norm();
        }
        along.push_back(a);
    }
    return along;
}

std::optional<WayAlong> LongestAlong(const std::vector<WayAlong>& along) {
    std::optional<WayAlong> best;
    for (const WayAlong& a : along) {
        if (!(a.along_m > 0.0)) continue;
        if (!best || a.along_m > best->along_m || (a.along_m == best->along_m && a.id < best->id)) {
            best = a;
        }
    }
    return best;
}

namespace {

/// The value of attribute `name` inside the start tag text [begin, end), or "".
std::string AttributeValue(const std::string& xml, std::size_t begin, std::size_t end,
                           const std::string& name) {
    for (std::size_t pos = begin; pos < end; ++pos) {
        pos = xml.find(name, pos);
        if (pos == std::string::npos || pos >= end) return "";
        if (!std::isspace(static_cast<unsigned char>(xml[pos - 1]))) continue;
        std::size_t q = pos + name.size();
        while (q < end && std::isspace(static_cast<unsigned char>(xml[q]))) ++q;
        if (q >= end || xml[q] != '=') continue;
        ++q;
        while (q < end && std::isspace(static_cast<unsigned char>(xml[q]))) ++q;
        if (q >= end || (xml[q] != '"' && xml[q] != '\'')) continue;
        const std::size_t close = xml.find(xml[q], q + 1);
        if (close == std::string::npos || close >= end) return "";
        return xml.substr(q + 1, close - q - 1);
    }
    return "";
}

struct ElementSpan {
    std::size_t begin = 0, end = 0;  ///< [begin, end) of the element text
};

/// Every <way ...>...</way> or <way .../> element whose id attribute is `id`.
std::vector<ElementSpan> FindWays(const std::string& xml, const std::string& id) {
    std::vector<ElementSpan> found;
    for (std::size_t pos = xml.find("<way"); pos != std::string::npos;
         pos = xml.find("<way", pos + 1)) {
        const char next = pos + 4 < xml.size() ? xml[pos + 4] : '\0';
        if (!std::isspace(static_cast<unsigned char>(next)) && next != '>' && next != '/') continue;
        const std::size_t tag_end = xml.find('>', pos);
        if (tag_end == std::string::npos) break;
        if (AttributeValue(xml, pos, tag_end, "id") != id) continue;
        std::size_t end = tag_end + 1;
        if (xml[tag_end - 1] != '/') {
            const std::size_t close = xml.find("</way>", tag_end);
            if (close == std::string::npos) break;
            end = close + 6;
        }
        found.push_back({pos, end});
    }
    return found;
}

}  // namespace

std::optional<std::string> RemoveOsmWay(const std::string& osm_xml, std::int64_t way_id) {
    const std::vector<ElementSpan> found = FindWays(osm_xml, std::to_string(way_id));
    if (found.size() != 1) return std::nullopt;
    std::size_t begin = found[0].begin, end = found[0].end;
    // Take the element's own lines with it: the indentation before it and the line break after.
    std::size_t line_begin = begin;
    while (line_begin > 0 && (osm_xml[line_begin - 1] == ' ' || osm_xml[line_begin - 1] == '\t')) {
        --line_begin;
    }
    std::size_t line_end = end;
    while (line_end < osm_xml.size() && (osm_xml[line_end] == ' ' || osm_xml[line_end] == '\t')) {
        ++line_end;
    }
    if (line_end < osm_xml.size() && osm_xml[line_end] == '\r') ++line_end;
    const bool own_lines = (line_begin == 0 || osm_xml[line_begin - 1] == '\n') &&
                           (line_end == osm_xml.size() || osm_xml[line_end] == '\n');
    if (own_lines) {
        begin = line_begin;
        end = std::min(osm_xml.size(), line_end + 1);
    }
    return osm_xml.substr(0, begin) + osm_xml.substr(end);
}

}  // namespace driftcorr::stress
