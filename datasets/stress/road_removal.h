#pragma once
// The road_removed variant: which OSM highway way the ground truth drives along the longest, and
// the OSM text without that way.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/io/scenario.h"
#include "driftcorr/mapping/geodesy.h"
#include "driftcorr/mapping/osm_reader.h"

namespace driftcorr::stress {

/// WGS84 -> the anchor's East-North plane [m] (docs/FORMAT.md): the local tangent plane at a
/// lat_deg/lon_deg anchor, or the CRS grid minus (easting_m, northing_m) for a crs anchor.
class AnchorPlane {
public:
    /// Throws std::invalid_argument naming the CRS when PROJ does not know it.
    explicit AnchorPlane(const io::AnchorSpec& anchor);
    Eigen::Vector2d ToEn(const GeoPoint& geo) const;

private:
    std::optional<LocalTangentPlane> ltp_;
    std::optional<CrsProjection> crs_;
    Eigen::Vector2d crs_origin_ = Eigen::Vector2d::Zero();
};

/// How far the ground truth drives along one way.
struct WayAlong {
    std::int64_t id = 0;
    std::string highway;
    double along_m = 0.0;  ///< summed length of GT steps whose both ends lie within the radius
};

/// For every way (polylines in the East-North plane, as `ways_en`), the length of the ground
/// truth (`gt_en`, East-North) driven within `radius_m` of it: the sum of |p_k - p_(k-1)| over
/// the steps whose two poses are both within radius_m of the way's polyline.
std::vector<WayAlong> GroundTruthAlongWays(const std::vector<OsmWay>& ways,
                                           const std::vector<std::vector<Eigen::Vector2d>>& ways_en,
                                           const std::vector<Eigen::Vector2d>& gt_en,
                                           double radius_m);

/// The way with the largest along_m (ties: the smallest id); nullopt when every along_m is 0.
std::optional<WayAlong> LongestAlong(const std::vector<WayAlong>& along);

/// `osm_xml` without the top-level <way id="way_id"> element (the element and, when it stands on
/// lines of its own, those lines). Nodes and everything else are kept byte for byte. nullopt
/// unless exactly one such element exists.
std::optional<std::string> RemoveOsmWay(const std::string& osm_xml, std::int64_t way_id);

}  // namespace driftcorr::stress
