// The definitions of what driftcorr/mapping/geodesy.h declares.
#include "driftcorr/mapping/geodesy.h"

#include <dlfcn.h>
#include <proj.h>

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <cctype>
#include <cmath>
#include <regex>
#include <stdexcept>
#include <string>
#include <type_traits>

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

// PROJ, with the thirty-odd libraries it links (curl, GnuTLS, Kerberos, LDAP, libtiff...), is
// opened with dlopen the first time a projected CRS is used, not loaded into every process: it
// adds about 5 ms to each start, and only a CRS anchor or --crs needs it. Its header gives the
// types and the functions' signatures; the list below names each function called, once
// (X(name) stands for proj_<name>).
// clang-format off
#define DRIFTCORR_PROJ_FUNCTIONS(X)                                                  \
    X(context_create) X(context_destroy) X(log_level) X(create_crs_to_crs)           \
    X(normalize_for_visualization) X(create) X(get_type) X(destroy)                  \
    X(crs_get_coordinate_system) X(cs_get_axis_count) X(cs_get_axis_info) X(trans)
// clang-format on

struct ProjApi {
#define DRIFTCORR_PROJ_MEMBER(name) decltype(&proj_##name) name = nullptr;
    DRIFTCORR_PROJ_FUNCTIONS(DRIFTCORR_PROJ_MEMBER)
#undef DRIFTCORR_PROJ_MEMBER
};

ProjApi LoadProj() {
    void* lib = dlopen(DRIFTCORR_PROJ_SONAME, RTLD_NOW | RTLD_LOCAL);
    if (lib == nullptr) {
        const char* why = dlerror();
        throw std::runtime_error(std::string("cannot load ") + DRIFTCORR_PROJ_SONAME +
                                 " (PROJ, for projected CRSs): " + (why ? why : "dlopen failed"));
    }
    ProjApi api;
    auto bind = [lib](auto& fn, const char* name) {
        fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(dlsym(lib, name));
        if (fn == nullptr) {
            dlclose(lib);
            throw std::runtime_error(std::string(DRIFTCORR_PROJ_SONAME) + " has no " + name);
        }
    };
#define DRIFTCORR_PROJ_BIND(name) bind(api.name, "proj_" #name);
    DRIFTCORR_PROJ_FUNCTIONS(DRIFTCORR_PROJ_BIND)
#undef DRIFTCORR_PROJ_BIND
    return api;
}

const ProjApi& Proj() {
    static const ProjApi api = LoadProj();  // once; a failure is retried on the next call
    return api;
}

#undef DRIFTCORR_PROJ_FUNCTIONS

/// True when every axis of the CRS's coordinate system is in metres (conversion factor 1).
bool AxesInMetres(PJ_CONTEXT* ctx, const PJ* crs) {
    const ProjApi& proj = Proj();
    PJ* cs = proj.crs_get_coordinate_system(ctx, crs);
    if (!cs) return false;
    const int axis_count = proj.cs_get_axis_count(ctx, cs);
    bool metres = axis_count > 0;
    for (int i = 0; i < axis_count && metres; ++i) {
        double unit_conv_factor = 0.0;
        metres = proj.cs_get_axis_info(ctx, cs, i, nullptr, nullptr, nullptr, &unit_conv_factor,
                                       nullptr, nullptr, nullptr) &&
                 unit_conv_factor == 1.0;
    }
    proj.destroy(cs);
    return metres;
}

/// The coordinate (a, b, 0, 0), as proj_coord makes it.
PJ_COORD Coord(double a, double b) {
    PJ_COORD c;
    c.v[0] = a, c.v[1] = b, c.v[2] = 0.0, c.v[3] = 0.0;
    return c;
}

}  // namespace

struct CrsProjection::Impl {
    PJ_CONTEXT* ctx = nullptr;
    PJ* pj = nullptr;  // normalised for visualisation: (lon, lat) <-> (easting, northing)
    ~Impl() {
        if (pj) Proj().destroy(pj);
        if (ctx) Proj().context_destroy(ctx);
    }
};

CrsProjection::CrsProjection(const std::string& crs) : impl_(std::make_unique<Impl>()) {
    name_ = NormaliseCrsName(crs);
    if (name_.empty() || name_ == "OGC:CRS84") {
        throw std::invalid_argument("CRS '" + crs +
                                    "' is not a projected CRS of the form EPSG:<code>");
    }
    const ProjApi& proj = Proj();
    impl_->ctx = proj.context_create();
    proj.log_level(impl_->ctx, PJ_LOG_NONE);
    PJ* raw = proj.create_crs_to_crs(impl_->ctx, "EPSG:4326", name_.c_str(), nullptr);
    if (!raw) throw std::invalid_argument("unknown CRS '" + crs + "' (PROJ cannot create it)");
    impl_->pj = proj.normalize_for_visualization(impl_->ctx, raw);
    proj.destroy(raw);
    if (!impl_->pj) throw std::invalid_argument("CRS '" + crs + "' cannot be normalised by PROJ");
    // A geographic CRS would hand back degrees and a projected one in feet would hand back feet:
    // check the target CRS type and its axis units explicitly.
    PJ* target = proj.create(impl_->ctx, name_.c_str());
    const bool projected = target && proj.get_type(target) == PJ_TYPE_PROJECTED_CRS;
    const bool metres = projected && AxesInMetres(impl_->ctx, target);
    if (target) proj.destroy(target);
    if (!projected) throw std::invalid_argument("CRS '" + crs + "' is not a projected CRS");
    if (!metres) throw std::invalid_argument("CRS '" + crs + "' does not use metre units");
}
CrsProjection::~CrsProjection() = default;
CrsProjection::CrsProjection(CrsProjection&&) noexcept = default;
CrsProjection& CrsProjection::operator=(CrsProjection&&) noexcept = default;

Eigen::Vector2d CrsProjection::FromGeo(const GeoPoint& geo) const {
    const PJ_COORD out = Proj().trans(impl_->pj, PJ_FWD, Coord(geo.lon_deg, geo.lat_deg));
    return {out.xy.x, out.xy.y};
}

GeoPoint CrsProjection::ToGeo(const Eigen::Vector2d& en) const {
    const PJ_COORD out = Proj().trans(impl_->pj, PJ_INV, Coord(en.x(), en.y()));
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

double GeodesicDistanceM(const GeoPoint& a, const GeoPoint& b) {
    double s12 = 0.0;
    GeographicLib::Geodesic::WGS84().Inverse(a.lat_deg, a.lon_deg, b.lat_deg, b.lon_deg, s12);
    return s12;
}

}  // namespace driftcorr
