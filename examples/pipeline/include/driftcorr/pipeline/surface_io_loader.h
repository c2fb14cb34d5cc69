#pragma once
// The point-cloud and OctoMap readers and writers (driftcorr_surface_io), loaded on first use.
// Linking them would load PCL, VTK and OctoMap (about a hundred shared libraries) into every run,
// road drives included: about 30 ms of start-up on a KITTI drive. With shared libraries the
// library is opened with dlopen the first time a map needs it; a static build links it.
#include "driftcorr/mapping/surface_io.h"

namespace driftcorr::pipeline {

/// The surface readers and writers. Throws std::runtime_error naming the library and the
/// loader's reason when it cannot be loaded (a broken installation). Thread-safe.
const SurfaceIoApi& SurfaceIo();

}  // namespace driftcorr::pipeline
