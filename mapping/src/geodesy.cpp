#include "driftcorr/mapping/geodesy.h"

#include <GeographicLib/LocalCartesian.hpp>
#include <proj.h>

#include <cctype>
#include <cmath>
#include <regex>
#include <stdexcept>

namespace driftcorr {

struct LocalTangentPlane::Impl {
    GeographicLib::LocalCartesian lc;
};

LocalTangentPlane::LocalTangentPlane(const GeoPoint& origin)
    : impl_(std::make_unique<Impl>(
          Impl{GeographicLib::LocalCartesian(origin.lat_deg, origin.lon_deg, origin.alt_m)})),
      origin_(origin) {}
LocalTangentPlane::~LocalTangentPlane() = default;
LocalTangentPlane::LocalTangentPlane(LocalTangentPlane&&) noexcept = default;
LocalTangentPlane& LocalTangentPlane::operator=(LocalTangentPlane&&) noexcept = default;

Eigen::Vector3d LocalTangentPlane::ToEnu(const GeoPoint& geo) const {
    Eigen::Vector3d enu;
    impl_->lc.Forward(geo.lat_deg, geo.lon_deg, geo.alt_m, enu.x(), enu.y(), enu.z());
    return enu;
}

GeoPoint LocalTangentPlane::ToGeo(const Eigen::Vector3d& enu) const {
    GeoPoint geo;
    impl_->lc.Reverse(enu.x(), enu.y(), enu.z(), geo.lat_deg, geo.lon_deg, geo.alt_m);
    return geo;
}

namespace {

/// True when every axis of the CRS's coordinate system is in metres (conversion factor 1).
bool AxesInMetres(PJ_CONTEXT* ctx, const PJ* crs) {
    PJ* cs = proj_crs_get_coordinate_system(ctx, crs);
    if (!cs) return false;
    const int axis_count = proj_cs_get_axis_count(ctx, cs);
    bool metres = axis_count > 0;
    for (int i = 0; i < axis_count && metres; ++i) {
        double unit_conv_factor = 0.0;
        metres = proj_cs_get_axis_info(ctx, cs, i, nullptr, nullptr, nullptr, &unit_conv_factor,
                                       nullptr, nullptr, nullptr) &&
                 unit_conv_factor == 1.0;
    }
    proj_destroy(cs);
    return metres;
}

}  // namespace

struct CrsProjection::Impl {
    PJ_CONTEXT* ctx = nullptr;
    PJ* pj = nullptr;  // normalised for visualisation: (lon, lat) <-> (easting, northing)
    ~Impl() {
        if (pj) proj_destroy(pj);
        if (ctx) proj_context_destroy(ctx);
    }
};

CrsProjection::CrsProjection(const std::string& crs) : impl_(std::make_unique<Impl>()) {
    name_ = NormaliseCrsName(crs);
    if (name_.empty() || name_ == "OGC:CRS84") {
        throw std::invalid_argument("CRS '" + crs +
                                    "' is not a projected CRS of the form EPSG:<code>");
    }
    impl_->ctx = proj_context_create();
    proj_log_level(impl_->ctx, PJ_LOG_NONE);
    PJ* raw = proj_create_crs_to_crs(impl_->ctx, "EPSG:4326", name_.c_str(), nullptr);
    if (!raw) throw std::invalid_argument("unknown CRS '" + crs + "' (PROJ cannot create it)");
    impl_->pj = proj_normalize_for_visualization(impl_->ctx, raw);
    proj_destroy(raw);
    if (!impl_->pj) throw std::invalid_argument("CRS '" + crs + "' cannot be normalised by PROJ");
    // A geographic CRS would hand back degrees and a projected one in feet would hand back feet:
    // check the target CRS type and its axis units explicitly.
    PJ* target = proj_create(impl_->ctx, name_.c_str());
    const bool projected = target && proj_get_type(target) == PJ_TYPE_PROJECTED_CRS;
    const bool metres = projected && AxesInMetres(impl_->ctx, target);
    if (target) proj_destroy(target);
    if (!projected) throw std::invalid_argument("CRS '" + crs + "' is not a projected CRS");
    if (!metres) throw std::invalid_argument("CRS '" + crs + "' does not use metre units");
}
CrsProjection::~CrsProjection() = default;
CrsProjection::CrsProjection(CrsProjection&&) noexcept = default;
CrsProjection& CrsProjection::operator=(CrsProjection&&) noexcept = default;

Eigen::Vector2d CrsProjection::FromGeo(const GeoPoint& geo) const {
    PJ_COORD c = proj_coord(geo.lon_deg, geo.lat_deg, 0, 0);
    PJ_COORD out = proj_trans(impl_->pj, PJ_FWD, c);
    return {out.xy.x, out.xy.y};
}

GeoPoint CrsProjection::ToGeo(const Eigen::Vector2d& en) const {
    PJ_COORD c = proj_coord(en.x(), en.y(), 0, 0);
    PJ_COORD out = proj_trans(impl_->pj, PJ_INV, c);
    GeoPoint geo;
    geo.lon_deg = out.lp.lam;
    geo.lat_deg = out.lp.phi;
    return geo;
}

std::string NormaliseCrsName(const std::string& crs) {
    std::string s;
    for (char c : crs) s += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    static const std::regex kEpsg(R"(^\s*(?:EPSG:|URN:OGC:DEF:CRS:EPSG:[0-9.]*:)(\d+)\s*$)");
    static const std::regex kCrs84(R"(^\s*(?:URN:OGC:DEF:CRS:OGC:[0-9.]*:|OGC:)CRS84\s*$)");
    std::smatch m;
    if (std::regex_match(s, m, kEpsg)) return "EPSG:" + m[1].str();
    if (std::regex_match(s, kCrs84)) return "OGC:CRS84";
    return "";
}

}  // namespace driftcorr
