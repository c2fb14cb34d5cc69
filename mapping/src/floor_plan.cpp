// The definitions of what driftcorr/mapping/floor_plan.h declares.
#include "driftcorr/mapping/floor_plan.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/geojson_reader.h"

namespace driftcorr {
namespace {

// The `Type` table. Counts are the polygons of the hcu_eight plans (EG / 1OG / 4OG) that carry
// the value, with their total area, to justify each entry:
//   walkable (a person can stand there):
//     Room 71/53/194 (1713/1301/2432 m2), Rooms 1/0/0 (typo of Room, 17 m2),
//     Corridor 9/9/4 (2524/3451/1417 m2; all 220 ground-truth steps of hcu_eight lie in 4OG
//     corridors), Balcony 0/0/1 (336 m2, an open walkway along the facade),
//     Gallery 0/0/1 (196 m2, a gallery over the atrium is a walkway).
//   door (walkable, and cut back into the walls they sit in, so rooms connect):
//     Door 98/81/227, B_Door 0/0/59 (balcony doors), D 1/0/0 (typo of Door).
//   stairs (join floors): Stairs 15/15/11, Staircase 3/0/0, Stairscase 1/3/5 (typo).
//   lift (join floors): Lift 1/2/0, Elevator 0/0/1.
//   wall (cut out): Wall 34/58/142, Wa 0/0/1 (a truncated Wall, 0.3 m2), Fassade 1/1/0 (facade,
//     i.e. the outer wall).
//   ignore (neither walkable nor cut out):
//     furniture/Furniture/Furnitures 14+3/11+1/0: furniture stands inside rooms that are already
//     walkable; cutting it out would close gaps the plan does not model (chairs move), and a
//     person never stands in it, so it adds nothing either.
//     NaNs 0/0/2 (268 and 201 m2 in the 4OG) and a missing/null Type (1/0/0 polygons; the other
//     null-Type features have no geometry): untyped areas may be voids (the atrium) as well as
//     floor, so they are not walkable; they are counted as unknown values in the report.
struct Entry {
    const char* type;
    FloorClass cls;
};
constexpr Entry kTable[] = {
    {"Room", FloorClass::kWalkable},     {"Rooms", FloorClass::kWalkable},
    {"Corridor", FloorClass::kWalkable}, {"Balcony", FloorClass::kWalkable},
    {"Gallery", FloorClass::kWalkable},  {"Door", FloorClass::kDoor},
    {"B_Door", FloorClass::kDoor},       {"D", FloorClass::kDoor},
    {"Stairs", FloorClass::kStairs},     {"Staircase", FloorClass::kStairs},
    {"Stairscase", FloorClass::kStairs}, {"Lift", FloorClass::kLift},
    {"Elevator", FloorClass::kLift},     {"Wall", FloorClass::kWall},
    {"Wa", FloorClass::kWall},           {"Fassade", FloorClass::kWall},
    {"Furniture", FloorClass::kIgnore},  {"Furnitures", FloorClass::kIgnore},
    {"NaNs", FloorClass::kIgnore},
};

std::string Canonical(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (!std::isspace(static_cast<unsigned char>(c))) {
            out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        }
    }
    return out;
}

FloorPolygon ToFloorPolygon(const GeoJsonPolygon& p,
                            const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& to_en) {
    FloorPolygon out;
    for (const auto& q : p.outer) out.outer_en.push_back(to_en(q));
    for (const auto& hole : p.holes) {
        out.holes_en.emplace_back();
        for (const auto& q : hole) out.holes_en.back().push_back(to_en(q));
    }
    return out;
}

// The layer CRS -> local East-North map for one layer; throws InputError naming the file.
std::function<Eigen::Vector2d(const Eigen::Vector2d&)> LayerToEn(const GeoJsonLayer& layer,
                                                                 const IndoorFrame& frame) {
    if (!frame.anchor_crs.empty() && layer.crs == NormaliseCrsName(frame.anchor_crs)) {
        return frame.anchor_crs_to_en;
    }
    std::shared_ptr<CrsProjection> layer_proj, anchor_proj;
    try {
        if (layer.crs != "OGC:CRS84") layer_proj = std::make_shared<CrsProjection>(layer.crs);
        if (!frame.anchor_crs.empty()) {
            anchor_proj = std::make_shared<CrsProjection>(frame.anchor_crs);
        }
    } catch (const std::invalid_argument& e) {
        throw InputError(layer.path, 0, "crs", e.what());
    }
    return [layer_proj, anchor_proj, frame](const Eigen::Vector2d& p) {
        const GeoPoint g = layer_proj ? layer_proj->ToGeo(p) : GeoPoint{p.y(), p.x(), 0.0};
        return anchor_proj ? frame.anchor_crs_to_en(anchor_proj->FromGeo(g)) : frame.geo_to_en(g);
    };
}

void CheckDegrees(const GeoJsonLayer& layer) {
    if (layer.crs != "OGC:CRS84") return;
    auto bad = [](const Eigen::Vector2d& p) {
        return std::abs(p.x()) > 180 || std::abs(p.y()) > 90;
    };
    bool any = false;
    for (const auto& l : layer.lines) any |= std::any_of(l.points.begin(), l.points.end(), bad);
    for (const auto& p : layer.polygons) any |= std::any_of(p.outer.begin(), p.outer.end(), bad);
    if (any) {
        throw InputError(layer.path, 0, "crs",
                         "the layer declares CRS84 (lon/lat degrees) but its coordinates are not "
                         "degrees; is the `crs` member wrong?");
    }
}

IndoorFloor& FloorAt(IndoorMap& map, double z) {
    for (auto& f : map.floors) {
        if (std::abs(f.floor_z_m - z) < 1e-6) return f;
    }
    map.floors.emplace_back();
    map.floors.back().floor_z_m = z;
    return map.floors.back();
}

// The first ring of `p` (outer, then holes) that crosses itself, and where; throws InputError
// naming the file and the feature.
void CheckSimple(const GeoJsonLayer& layer, const GeoJsonPolygon& p) {
    std::vector<const std::vector<Eigen::Vector2d>*> rings = {&p.outer};
    for (const auto& hole : p.holes) rings.push_back(&hole);
    for (const auto* ring : rings) {
        const std::optional<Eigen::Vector2d> x = RingSelfCrossing(*ring);
        if (!x) continue;
        std::ostringstream where;
        where.precision(10);
        where << "(" << x->x() << ", " << x->y() << ")";
        throw InputError(layer.path, 0, "features[" + std::to_string(p.feature_index) + "]",
                         "the polygon" + (p.type ? " of Type " + *p.type : std::string()) +
                             " crosses itself at " + where.str() +
                             " (layer coordinates): its inside is not defined; fix its outline");
    }
}

void AddFloorPlan(const GeoJsonLayer& layer,
                  const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& to_en,
                  IndoorFloor& floor, IndoorLayerReport& report) {
    std::size_t walkable = 0;
    for (const auto& p : layer.polygons) {
        bool known = true;
        const FloorClass cls = ClassifyFloorType(p.type ? &*p.type : nullptr, &known);
        ++report.classes[ToString(cls)];
        if (!known) ++report.unknown_types[p.type ? *p.type : "<missing>"];
        std::vector<FloorPolygon>* dst = nullptr;
        switch (cls) {
            case FloorClass::kWalkable:
                dst = &floor.walkable;
                break;
            case FloorClass::kDoor:
                dst = &floor.doors;
                break;
            case FloorClass::kStairs:
                dst = &floor.stairs;
                break;
            case FloorClass::kLift:
                dst = &floor.lifts;
                break;
            case FloorClass::kWall:
                dst = &floor.walls;
                break;
            case FloorClass::kIgnore:
                break;
        }
        if (cls != FloorClass::kWall && cls != FloorClass::kIgnore) ++walkable;
        if (!dst) continue;
        CheckSimple(layer, p);
        dst->push_back(ToFloorPolygon(p, to_en));
    }
    if (walkable == 0) {
        throw InputError(layer.path, 0, "",
                         "the floor plan has no walkable polygon (Room, Corridor, Door, Stairs, "
                         "Lift, ...; " +
                             std::to_string(layer.polygons.size()) + " polygons read, " +
                             layer.report.Summary() + ")");
    }
}

}  // namespace

std::optional<Eigen::Vector2d> RingSelfCrossing(const std::vector<Eigen::Vector2d>& ring) {
    std::size_t m = ring.size();
    if (m > 1 && ring.front() == ring.back()) --m;
    if (m < 4) return std::nullopt;
    struct Edge {
        std::size_t i;
        double x0, x1;
    };
    std::vector<Edge> edges(m);
    for (std::size_t i = 0; i < m; ++i) {
        const Eigen::Vector2d& a = ring[i];
        const Eigen::Vector2d& b = ring[(i + 1) % m];
        edges[i] = {i, std::min(a.x(), b.x()), std::max(a.x(), b.x())};
    }
    std::sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) { return a.x0 < b.x0; });
    auto orient = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
        const double v = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
        return (v > 0.0) - (v < 0.0);
    };
    for (std::size_t u = 0; u < m; ++u) {
        const std::size_t i = edges[u].i;
        const Eigen::Vector2d &a = ring[i], &b = ring[(i + 1) % m];
        for (std::size_t w = u + 1; w < m && edges[w].x0 <= edges[u].x1; ++w) {
            const std::size_t j = edges[w].i;
            const std::size_t d = i > j ? i - j : j - i;
            if (d == 1 || d == m - 1) continue;  // neighbours share a vertex
            const Eigen::Vector2d &c = ring[j], &e = ring[(j + 1) % m];
            if (std::max(c.y(), e.y()) < std::min(a.y(), b.y()) ||
                std::min(c.y(), e.y()) > std::max(a.y(), b.y())) {
                continue;
            }
            if (orient(a, b, c) * orient(a, b, e) < 0 && orient(c, e, a) * orient(c, e, b) < 0) {
                const Eigen::Vector2d r = b - a, s = e - c;
                const double t =
                    ((c - a).x() * s.y() - (c - a).y() * s.x()) / (r.x() * s.y() - r.y() * s.x());
                return Eigen::Vector2d(a + t * r);
            }
        }
    }
    return std::nullopt;
}

const char* ToString(FloorClass c) {
    switch (c) {
        case FloorClass::kWalkable:
            return "walkable";
        case FloorClass::kStairs:
            return "stairs";
        case FloorClass::kLift:
            return "lift";
        case FloorClass::kDoor:
            return "door";
        case FloorClass::kWall:
            return "wall";
        case FloorClass::kIgnore:
            return "ignore";
    }
    return "ignore";
}

FloorClass ClassifyFloorType(const std::string* type, bool* known) {
    if (known) *known = false;
    if (!type) return FloorClass::kIgnore;
    for (const Entry& e : kTable) {
        if (*type == e.type) {
            if (known) *known = true;
            return e.cls;
        }
    }
    const std::string c = Canonical(*type);
    for (const Entry& e : kTable) {
        if (c == Canonical(e.type)) {
            if (known) *known = true;
            return e.cls;
        }
    }
    return FloorClass::kIgnore;
}

std::string IndoorLayerReport::Summary() const {
    std::ostringstream out;
    out << path << " (" << crs << "): " << features << " features, " << lines << " lines, "
        << polygons << " polygons";
    auto list = [&out](const char* what, const std::map<std::string, std::size_t>& m) {
        if (m.empty()) return;
        out << "; " << what << ":";
        for (const auto& [k, v] : m) out << " " << k << " " << v;
    };
    list("skipped", skipped);
    list("caveats", caveats);
    list("classes", classes);
    list("unknown types (ignored)", unknown_types);
    return out.str();
}

IndoorMap LoadIndoorMap(const std::vector<IndoorLayerSpec>& layers, const IndoorFrame& frame) {
    IndoorMap map;
    for (const IndoorLayerSpec& spec : layers) {
        const GeoJsonLayer layer = ReadGeoJson(spec.path);
        CheckDegrees(layer);
        const auto to_en = LayerToEn(layer, frame);
        IndoorLayerReport report;
        report.path = spec.path;
        report.crs = layer.crs;
        report.features = layer.report.features;
        report.lines = layer.lines.size();
        report.polygons = layer.polygons.size();
        report.skipped = layer.report.skipped;
        report.caveats = layer.report.caveats;
        IndoorFloor& floor = FloorAt(map, spec.floor_z_m);
        if (spec.role == IndoorLayerRole::kWalkways) {
            if (!layer.polygons.empty())
                report.skipped["polygon in a walkway layer"] += layer.polygons.size();
            for (const auto& l : layer.lines) {
                floor.walkways_en.emplace_back();
                for (const auto& p : l.points) floor.walkways_en.back().push_back(to_en(p));
            }
        } else {
            if (!layer.lines.empty()) report.skipped["line in a floor plan"] += layer.lines.size();
            AddFloorPlan(layer, to_en, floor, report);
        }
        map.layers.push_back(std::move(report));
    }
    std::sort(map.floors.begin(), map.floors.end(),
              [](const IndoorFloor& a, const IndoorFloor& b) { return a.floor_z_m < b.floor_z_m; });
    return map;
}

}  // namespace driftcorr
