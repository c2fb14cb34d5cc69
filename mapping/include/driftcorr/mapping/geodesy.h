#pragma once
// Geodesy at the edge of the project: WGS84 <-> local East-North-Up tangent plane (GeographicLib)
// and projected CRS <-> WGS84 (PROJ). No third-party type appears in this header.
#include <Eigen/Core>
#include <memory>
#include <string>

namespace driftcorr {

struct GeoPoint {
    double lat_deg = 0.0;
    double lon_deg = 0.0;
    double alt_m = 0.0;
};

/// The WGS84 ellipsoid's geodesic distance between two points [m] (heights ignored).
double GeodesicDistanceM(const GeoPoint& a, const GeoPoint& b);

/// The WGS84 local tangent plane (East-North-Up, true north) at an origin.
class LocalTangentPlane {
public:
    explicit LocalTangentPlane(const GeoPoint& origin);
    ~LocalTangentPlane();
    LocalTangentPlane(LocalTangentPlane&&) noexcept;
    LocalTangentPlane& operator=(LocalTangentPlane&&) noexcept;

    /// WGS84 -> ENU [m] relative to the origin.
    Eigen::Vector3d ToEnu(const GeoPoint& geo) const;
    /// ENU [m] -> WGS84.
    GeoPoint ToGeo(const Eigen::Vector3d& enu) const;
    const GeoPoint& origin() const { return origin_; }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    GeoPoint origin_;
};

/// A projected CRS such as "EPSG:32632" (easting, northing in metres), through PROJ.
class CrsProjection {
public:
    /// Throws std::invalid_argument naming the CRS when PROJ does not know it or it is not a
    /// projected CRS with metre units.
    explicit CrsProjection(const std::string& crs);
    ~CrsProjection();
    CrsProjection(CrsProjection&&) noexcept;
    CrsProjection& operator=(CrsProjection&&) noexcept;

    /// WGS84 -> (easting, northing) [m].
    Eigen::Vector2d FromGeo(const GeoPoint& geo) const;
    /// (easting, northing) [m] -> WGS84 (alt_m = 0).
    GeoPoint ToGeo(const Eigen::Vector2d& en) const;
    const std::string& name() const { return name_; }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::string name_;
};

/// Normalises CRS spellings to "EPSG:<code>": "EPSG:32632", "epsg:32632",
/// "urn:ogc:def:crs:EPSG::32632", "urn:ogc:def:crs:EPSG:6.6:32632". "urn:ogc:def:crs:OGC:1.3:CRS84"
/// and "OGC:CRS84" become "OGC:CRS84". Returns an empty string for anything else.
std::string NormaliseCrsName(const std::string& crs);

}  // namespace driftcorr
