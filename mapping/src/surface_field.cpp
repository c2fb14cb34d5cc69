#include "driftcorr/mapping/surface_field.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <iomanip>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "driftcorr/mapping/grid.h"
#include "voxel_corridor.h"

namespace driftcorr {
namespace {

using Mask = std::vector<std::uint8_t>;

// The grid over the points' box; throws when it would exceed the memory cap.
GridSpec MakeSpec(const Eigen::AlignedBox3d& box, const SurfaceFieldConfig& c) {
    GridSpec s;
    s.resolution_m = c.resolution_m;
    s.resolution_z_m = c.resolution_z_m;
    const int kz = std::max(2, int(std::ceil(c.vertical_margin_m / c.resolution_z_m)));
    s.origin_m = Eigen::Vector3d(box.min().x() - c.margin_m, box.min().y() - c.margin_m,
                                 box.min().z() - kz * c.resolution_z_m);
    s.nx = std::max(4, int(std::ceil((box.sizes().x() + 2.0 * c.margin_m) / c.resolution_m)) + 1);
    s.ny = std::max(4, int(std::ceil((box.sizes().y() + 2.0 * c.margin_m) / c.resolution_m)) + 1);
    s.nz = int(std::ceil(box.sizes().z() / c.resolution_z_m - 1e-9)) + 2 * kz + 1;
    // Peak bytes per voxel: centre and corridor (4 + 4), the EDT's buffer (4), two masks.
    const double mb = double(s.size()) * 14.0 / (1024.0 * 1024.0);
    if (mb > c.max_memory_mb) {
        const double fit = c.resolution_m * std::sqrt(mb / c.max_memory_mb) * 1.01;
        std::ostringstream msg;
        msg << "surface distance field of " << s.nx << " x " << s.ny << " x " << s.nz
            << " voxels at " << c.resolution_m << " m (vertical " << c.resolution_z_m
            << " m) needs about " << std::setprecision(2) << mb << std::setprecision(6) << " MB, more than max_memory_mb = " << c.max_memory_mb
            << "; a horizontal resolution of " << std::ceil(fit * 100.0) / 100.0
            << " m or coarser would fit (or coarsen resolution_z_m, shrink margin_m)";
        throw std::invalid_argument(msg.str());
    }
    return s;
}

Eigen::AlignedBox3d LiftedBounds(const std::vector<Eigen::Vector3d>& points, double lift_m) {
    Eigen::AlignedBox3d box;
    for (std::size_t n = 0; n < points.size(); ++n) {
        if (!points[n].allFinite()) {
            throw std::invalid_argument("surface point " + std::to_string(n) +
                                        " has a NaN or infinite coordinate");
        }
        box.extend(points[n] + Eigen::Vector3d(0.0, 0.0, lift_m));
    }
    return box;
}

}  // namespace

std::string SurfaceFieldConfig::Validate() const {
    if (!(wall_clearance_m >= 0.0) || !std::isfinite(wall_clearance_m)) return "wall_clearance_m: must be >= 0";
    if (!(resolution_m > 0.0)) return "surface.resolution_m: must be > 0";
    if (!(resolution_z_m > 0.0)) return "surface.resolution_z_m: must be > 0";
    if (!std::isfinite(device_height_m)) return "surface.device_height_m: must be finite";
    if (!(vertical_tolerance_m >= resolution_z_m)) {
        return "surface.vertical_tolerance_m: must be >= resolution_z_m (a thinner layer is one "
               "voxel thick and the B-spline would mix the outside samples above and below into "
               "the value at the surface)";
    }
    if (!(margin_m >= 0.0)) return "surface.margin_m: must be >= 0";
    if (!(vertical_margin_m >= 0.0)) return "surface.vertical_margin_m: must be >= 0";
    if (!(truncation_m > 0.0)) return "surface.truncation_m: must be > 0";
    if (!(max_memory_mb > 0.0)) return "surface.max_memory_mb: must be > 0";
    return "";
}

TraversableField BuildSurfaceField(const std::vector<Eigen::Vector3d>& surface_points_enu,
                                   const SurfaceFieldConfig& config, SurfaceFieldStats* stats) {
    if (const std::string err = config.Validate(); !err.empty()) throw std::invalid_argument(err);
    if (surface_points_enu.empty()) throw std::invalid_argument("the surface map has no point");
    const Eigen::AlignedBox3d box = LiftedBounds(surface_points_enu, config.device_height_m);
    const GridSpec s = MakeSpec(box, config);
    const double res = s.resolution_m, dz = s.dz(), tol = config.vertical_tolerance_m;

    // The traversable set (columns within tol of each point) and the centre seeds.
    Mask inside(s.size(), 0), seeds(s.size(), 0);
    for (const Eigen::Vector3d& p : surface_points_enu) {
        const double z = p.z() + config.device_height_m;
        const int i = std::clamp(int(std::lround((p.x() - s.origin_m.x()) / res)), 0, s.nx - 1);
        const int j = std::clamp(int(std::lround((p.y() - s.origin_m.y()) / res)), 0, s.ny - 1);
        const double g = (z - s.origin_m.z()) / dz;
        const int k_s = std::clamp(int(std::lround(g)), 0, s.nz - 1);
        const int k_lo =
            std::clamp(std::min(k_s, int(std::ceil(g - tol / dz - 1e-9))), 0, s.nz - 1);
        const int k_hi =
            std::clamp(std::max(k_s, int(std::floor(g + tol / dz + 1e-9))), 0, s.nz - 1);
        seeds[s.Index(i, j, k_s)] = 1;
        for (int k = k_lo; k <= k_hi; ++k) inside[s.Index(i, j, k)] = 1;
    }
    if (stats) {
        stats->points = surface_points_enu.size();
        stats->voxels = s.size();
        stats->surface_voxels = std::size_t(std::count(seeds.begin(), seeds.end(), 1));
        stats->traversable_voxels = std::size_t(std::count(inside.begin(), inside.end(), 1));
    }
    const float trunc = float(config.truncation_m);
    std::vector<float> corridor = internal::CorridorField(s, inside, trunc);
    Mask().swap(inside);
    std::vector<float> centre = EuclideanDistanceTransform(s, seeds);
    Mask().swap(seeds);
    const float clearance = float(config.wall_clearance_m);
    for (std::size_t i = 0; i < centre.size(); ++i) {
        const float wall_term = clearance > 0.0f ? clearance + corridor[i] : 0.0f;
        centre[i] = std::min(trunc, std::max({0.0f, centre[i], wall_term}));
    }
    return TraversableField(InterpolatedField(s, std::move(centre)),
                            InterpolatedField(s, std::move(corridor)), config.truncation_m);
}

}  // namespace driftcorr
