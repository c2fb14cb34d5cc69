#pragma once
// Internal helper shared by the voxel field builders (indoor_field.cpp, surface_field.cpp): the
// corridor field of a 3D traversable set. Not installed; not part of the public API.
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "driftcorr/core/params.h"
#include "driftcorr/mapping/grid.h"

namespace driftcorr::internal {

/// Signed distance to the traversable set `inside` (one byte per voxel of `s`), truncated at
/// +/- trunc: outside, the 3D distance to the set minus half a cell; inside, minus the
/// horizontal distance to the nearest outside voxel of the same slice, plus half a cell (how far
/// from the walls). The zero level lies between the last inside and the first outside voxel.
/// The size settings both voxel fields share (IndoorFieldConfig, SurfaceFieldConfig).
struct VoxelGridSize {
    double resolution_m, resolution_z_m, margin_m, vertical_margin_m, max_memory_mb;
};

/// The grid over `box` grown by margin_m horizontally and by at least two layers (and
/// vertical_margin_m) vertically, at least 4 x 4 cells; with `layers` (first, last), only
/// those of its layers (clamped to the grid; at least one). Throws
/// std::invalid_argument when the grid would need more than max_memory_mb, saying which
/// horizontal resolution would fit; `what` names the field in that message ("indoor",
/// "surface").
GridSpec VoxelGridSpec(const Eigen::AlignedBox3d& box, const VoxelGridSize& c, const char* what,
                       const std::optional<std::pair<int, int>>& layers = std::nullopt);

/// The rule both voxel fields share: vertical_tolerance_m >= resolution_z_m, with why.
std::optional<ParamProblem> ThinLayerProblem(double vertical_tolerance_m, double resolution_z_m);

std::vector<float> CorridorField(const GridSpec& s, const std::vector<std::uint8_t>& inside,
                                 float trunc);

}  // namespace driftcorr::internal
