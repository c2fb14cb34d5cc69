#pragma once
// Internal helper shared by the voxel field builders (indoor_field.cpp, surface_field.cpp): the
// corridor field of a 3D traversable set. Not installed; not part of the public API.
#include <cstdint>
#include <vector>

#include "driftcorr/mapping/grid.h"

namespace driftcorr::internal {

/// Signed distance to the traversable set `inside` (one byte per voxel of `s`), truncated at
/// +/- trunc: outside, the 3D distance to the set minus half a cell; inside, minus the
/// horizontal distance to the nearest outside voxel of the same slice, plus half a cell (how far
/// from the walls). The zero level lies between the last inside and the first outside voxel.
std::vector<float> CorridorField(const GridSpec& s, const std::vector<std::uint8_t>& inside,
                                 float trunc);

}  // namespace driftcorr::internal
