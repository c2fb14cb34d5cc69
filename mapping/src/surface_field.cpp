// The definitions of what driftcorr/mapping/surface_field.h declares.
#include "driftcorr/mapping/surface_field.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <future>
#include <stdexcept>

#include "driftcorr/mapping/grid.h"
#include "voxel_corridor.h"

namespace driftcorr {
namespace {

using Mask = std::vector<std::uint8_t>;

// The grid over the points' box; throws when it would exceed the memory cap.
GridSpec MakeSpec(const Eigen::AlignedBox3d& box, const SurfaceFieldConfig& c) {
    return internal::VoxelGridSpec(
        box, {c.resolution_m, c.resolution_z_m, c.margin_m, c.vertical_margin_m, c.max_memory_mb},
        "surface");
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

std::optional<ParamProblem> SurfaceFieldConfig::FindProblem() const {
    if (auto problem = CheckRows(kSurfaceFieldParams, *this)) return problem;
    return internal::ThinLayerProblem(vertical_tolerance_m, resolution_z_m);
}

std::string SurfaceFieldConfig::Validate() const {
    return ToMessage(kSurfaceFieldParams.section, FindProblem());
}

TraversableField BuildSurfaceField(const std::vector<Eigen::Vector3d>& surface_points_enu,
                                   const SurfaceFieldConfig& config, SurfaceFieldStats* stats) {
    if (const std::string err = config.Validate(); !err.empty()) throw std::invalid_argument(err);
    if (surface_points_enu.empty()) throw std::invalid_argument("the surface map has no point");
    const Eigen::AlignedBox3d box = LiftedBounds(surface_points_enu, config.device_height_m);
    const GridSpec s = MakeSpec(box, config);
    const double res = s.resolution_m, dz = s.dz(), tol = config.vertical_tolerance_m;

    // The traversable set (columns within tol of each point) and the centre seeds.
    Mask inside, seeds;
    AssignLarge(inside, s.size(), std::uint8_t(0));
    AssignLarge(seeds, s.size(), std::uint8_t(0));
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
    // The two transforms side by side when a second thread is allowed.
    std::future<std::vector<float>> to_corridor =
        std::async(SecondThreadLaunch(config.threads),
                   [&s, &inside, trunc] { return internal::CorridorField(s, inside, trunc); });
    // Clamped to trunc below: beyond it the distances need not be exact.
    std::vector<float> centre = EuclideanDistanceTransform(s, seeds, trunc);
    Mask().swap(seeds);
    std::vector<float> corridor = to_corridor.get();
    Mask().swap(inside);
    const float clearance = float(config.wall_clearance_m);
    for (std::size_t i = 0; i < centre.size(); ++i) {
        const float wall_term = clearance > 0.0f ? clearance + corridor[i] : 0.0f;
        centre[i] = std::min(trunc, std::max({0.0f, centre[i], wall_term}));
    }
    return TraversableField(InterpolatedField(s, std::move(centre)),
                            InterpolatedField(s, std::move(corridor)), config.truncation_m);
}

}  // namespace driftcorr
