#pragma once
// Where a person can stand, from a raw 3D map of a building (a point cloud of a mapping run, or
// the occupied voxels of an OctoMap: floors, walls, ceilings, furniture, noise): the walkable
// surface that BuildSurfaceField (surface_field.h) consumes. Needs no PCL; the points come from
// any reader (surface_io.h: ReadRawPoints).
//
// The cloud is binned into voxels of resolution_m. A voxel is a standing place when it is
// occupied, the voxel above it is not, and the space above its top face is free of occupied
// voxels for headroom_m (a floor under a ceiling, a stair tread under the flight above; not a
// ceiling under the slab above it, not the top of a wall, a cabinet or a shelf), or holds nothing
// at all, unless there is headroom_m of free space under it too (a ceiling or roof seen from
// below, the scan having nothing above it: a single storey, the top floor). Standing places
// of neighbouring columns (8-neighbourhood) whose heights differ by at most step_m belong to one
// region: a floor, a floor with its stairs (a flight is a sequence of treads a riser apart), a
// table top. Regions smaller than min_region_m2 are dropped (furniture, shelves, noise); so are
// regions not connected to the largest one by steps or by a declared lift (the outside of a roof,
// an isolated top of a large cabinet), which are reported. Before that, gaps of the scan up to
// fill_gap_m (holes, a doorway lost to a hole) are closed where nothing stands in the way. A lift
// is a vertical connection a scan does not show (the cabin stands at one level): each declared
// shaft becomes walkable surface at every lift_level_step_m between the lowest and the highest
// region it touches.
#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace driftcorr {

/// A declared lift shaft: its horizontal footprint [m, map frame].
struct LiftShaft {
    double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
};

struct WalkableSurfaceConfig {
    double resolution_m = 0.1;   ///< voxel side, horizontal and vertical [m]
    double headroom_m = 1.8;     ///< free height a person needs above where they stand [m]
    double step_m = 0.25;        ///< largest height step within a region (a stair riser) [m]
    double min_region_m2 = 4.0;  ///< smaller regions are dropped [m^2]
    /// Gaps of the scan up to this long (holes in a floor, a doorway lost to a hole) are closed
    /// between places at most step_m apart in height, across columns free of occupied voxels
    /// from step_m below to headroom_m above (never through a wall or under furniture); 0: off [m]
    double fill_gap_m = 2.0;
    std::vector<LiftShaft> lifts;
    double lift_level_step_m = 0.25;  ///< height spacing of a lift shaft's surface points [m]
    /// A lift shaft touches the regions within this horizontal distance of its footprint [m].
    double lift_reach_m = 1.0;
    double max_memory_mb = 1024.0;  ///< refuse voxel grids larger than this [MB]

    /// Empty if valid, else "<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// One connected walkable region.
struct WalkableRegion {
    double area_m2 = 0.0;
    double z_min_m = 0.0, z_max_m = 0.0;  ///< heights of its standing places
    bool kept = false;
    std::string why_dropped;  ///< empty when kept
};

struct WalkableSurface {
    /// One point per standing place: the voxel column's centre and the mean height of the
    /// cloud's points in its top voxel; then the declared lifts' points.
    std::vector<Eigen::Vector3d> points;
    std::vector<int> region;  ///< per point: its index in `regions` (-1 for a lift point)
    /// Every region of at least one standing place, kept ones and dropped ones, largest first.
    std::vector<WalkableRegion> regions;
    std::size_t input_points = 0, occupied_voxels = 0, standing_places = 0, lift_points = 0;
    std::size_t filled_places = 0;  ///< standing places added by closing gaps (fill_gap_m)
    double area_m2 = 0.0;           ///< kept area (lifts not counted)
};

/// Throws std::invalid_argument when the config is invalid, the cloud is empty or has a
/// non-finite point, or the voxel grid would exceed max_memory_mb (the message names the extent
/// and the resolution). An empty result (no region kept) is not an error here; the caller names
/// the file and reports the largest region found.
WalkableSurface ExtractWalkableSurface(const std::vector<Eigen::Vector3d>& cloud,
                                       const WalkableSurfaceConfig& config);

/// A message when the cloud's extent cannot be a building in metres (over 5 km: millimetres or
/// centimetres; under 1 m), else nullopt. (A cloud whose z axis points down cannot be told from
/// its geometry alone: a building turned upside down is a building whose ceilings are floors.
/// A scenario tells it: its walk then leaves the walkable surface.)
std::optional<std::string> CheckCloudExtent(const std::vector<Eigen::Vector3d>& cloud);

/// Precision and recall of an extracted surface against a true one, on the columns of
/// resolution_m: an extracted point is right when a true point lies in its column within
/// tolerance_m in height; a true point is found when an extracted one does.
struct SurfaceAgreement {
    double precision = 0.0, recall = 0.0;
    std::size_t extracted = 0, truth = 0;
};
SurfaceAgreement CompareSurfaces(const std::vector<Eigen::Vector3d>& extracted,
                                 const std::vector<Eigen::Vector3d>& truth, double resolution_m,
                                 double tolerance_m);

}  // namespace driftcorr
