// The definitions of what driftcorr/mapping/surface_io.h declares.
#include "driftcorr/mapping/surface_io.h"

extern "C" const driftcorr::SurfaceIoApi* driftcorr_surface_io_api() {
    static const driftcorr::SurfaceIoApi api{
        &driftcorr::ReadSurfacePoints, &driftcorr::ReadRawPoints, &driftcorr::WriteSurfacePointsPcd,
        &driftcorr::WriteSurfacePointsPly};
    return &api;
}
