// The definitions of what voxel_corridor.h declares.
#include "voxel_corridor.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace driftcorr::internal {

std::optional<ParamProblem> ThinLayerProblem(double vertical_tolerance_m, double resolution_z_m) {
    if (vertical_tolerance_m >= resolution_z_m) return std::nullopt;
    ParamProblem problem = RelationProblem("vertical_tolerance_m", vertical_tolerance_m,
                                           ">=", "resolution_z_m", resolution_z_m);
    problem.message +=
        ": a thinner layer is one voxel thick and the B-spline would mix the outside samples "
        "above and below into the value at the surface";
    return problem;
}
namespace {

using Mask = std::vector<std::uint8_t>;

// Minus the horizontal distance from each inside voxel of slice `k` to the nearest outside
// voxel (plus half a cell), written into `corridor`. The EDT runs on the bounding box of the
// inside voxels grown by one cell: the nearest outside voxel of an inside one is never beyond it
// (clamping a far outside voxel onto the box gives a nearer one, still outside).
void InsideSlice(const GridSpec& s, const Mask& inside, int k, float cap,
                 std::vector<float>& corridor) {
    const std::size_t base = s.Index(0, 0, k);
    int i0 = s.nx, i1 = -1, j0 = s.ny, j1 = -1;
    for (int j = 0; j < s.ny; ++j) {
        const std::uint8_t* row = &inside[base + std::size_t(j) * s.nx];
        for (int i = 0; i < s.nx; ++i) {
            if (!row[i]) continue;
            i0 = std::min(i0, i), i1 = std::max(i1, i), j0 = std::min(j0, j), j1 = std::max(j1, j);
        }
    }
    if (i1 < 0) return;
    i0 = std::max(0, i0 - 1), j0 = std::max(0, j0 - 1);
    i1 = std::min(s.nx - 1, i1 + 1), j1 = std::min(s.ny - 1, j1 + 1);
    GridSpec sub;
    sub.resolution_m = s.resolution_m;
    sub.nx = i1 - i0 + 1;
    sub.ny = j1 - j0 + 1;
    Mask outside(sub.size());
    for (int j = 0; j < sub.ny; ++j) {
        for (int i = 0; i < sub.nx; ++i)
            outside[sub.Index(i, j)] = !inside[s.Index(i0 + i, j0 + j, k)];
    }
    const std::vector<float> d = EuclideanDistanceTransform(sub, outside, cap);
    const float half = 0.5f * float(s.resolution_m);
    for (int j = 0; j < sub.ny; ++j) {
        for (int i = 0; i < sub.nx; ++i) {
            const std::size_t idx = s.Index(i0 + i, j0 + j, k);
            if (inside[idx]) corridor[idx] = -(std::min(d[sub.Index(i, j)], 1e6f) - half);
        }
    }
}

}  // namespace

std::vector<float> CorridorField(const GridSpec& s, const Mask& inside, float trunc) {
    // Clamped to +-trunc below, after half a cell comes off: distances beyond trunc and a cell
    // need not be exact (EuclideanDistanceTransform's cap).
    const float cap = trunc + float(s.resolution_m);
    std::vector<float> corridor = EuclideanDistanceTransform(s, inside, cap);
    const float half = 0.5f * float(s.resolution_m);
    for (float& v : corridor) v = v - half;  // outside; inside voxels are overwritten below
    const std::size_t plane = std::size_t(s.nx) * s.ny;
    for (int k = 0; k < s.nz; ++k) {
        const std::size_t base = s.Index(0, 0, k);
        const bool same = k > 0 && std::memcmp(&inside[base], &inside[base - plane], plane) == 0;
        if (same) {  // stair and lift columns repeat one slice many times
            for (std::size_t i = 0; i < plane; ++i) {
                if (inside[base + i]) corridor[base + i] = corridor[base - plane + i];
            }
        } else {
            InsideSlice(s, inside, k, cap, corridor);
        }
    }
    for (float& v : corridor) v = std::clamp(v, -trunc, trunc);
    return corridor;
}

GridSpec VoxelGridSpec(const Eigen::AlignedBox3d& box, const VoxelGridSize& c, const char* what,
                       const std::optional<std::pair<int, int>>& layers) {
    GridSpec s;
    s.resolution_m = c.resolution_m;
    s.resolution_z_m = c.resolution_z_m;
    const int kz = std::max(2, int(std::ceil(c.vertical_margin_m / c.resolution_z_m)));
    s.origin_m = Eigen::Vector3d(box.min().x() - c.margin_m, box.min().y() - c.margin_m,
                                 box.min().z() - kz * c.resolution_z_m);
    s.nx = std::max(4, int(std::ceil((box.sizes().x() + 2.0 * c.margin_m) / c.resolution_m)) + 1);
    s.ny = std::max(4, int(std::ceil((box.sizes().y() + 2.0 * c.margin_m) / c.resolution_m)) + 1);
    s.nz = int(std::ceil(box.sizes().z() / c.resolution_z_m - 1e-9)) + 2 * kz + 1;
    if (layers) {
        const int k0 = std::clamp(layers->first, 0, s.nz - 1);
        const int k1 = std::clamp(layers->second, k0, s.nz - 1);
        s.origin_m.z() += k0 * c.resolution_z_m;
        s.nz = k1 - k0 + 1;
    }
    // Peak bytes per voxel: centre and corridor (4 + 4), the EDT's buffer (4), two masks.
    const double mb = double(s.size()) * 14.0 / (1024.0 * 1024.0);
    if (mb > c.max_memory_mb) {
        const double fit = c.resolution_m * std::sqrt(mb / c.max_memory_mb) * 1.01;
        std::ostringstream msg;
        msg << what << " distance field of " << s.nx << " x " << s.ny << " x " << s.nz
            << " voxels at " << c.resolution_m << " m (vertical " << c.resolution_z_m
            << " m) needs about " << std::setprecision(2) << mb << std::setprecision(6)
            << " MB, more than max_memory_mb = " << c.max_memory_mb
            << "; a horizontal resolution of " << std::ceil(fit * 100.0) / 100.0
            << " m or coarser would fit (or coarsen resolution_z_m, shrink margin_m)";
        throw std::invalid_argument(msg.str());
    }
    return s;
}

}  // namespace driftcorr::internal
