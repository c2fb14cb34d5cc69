#pragma once
// Readers and writers of walkable-surface maps: point clouds (PCD, PLY; via PCL) and OctoMap
// occupancy trees (.bt, .ot). Part of the separate target driftcorr_surface_io: PCL and OctoMap
// are linked PRIVATE there and no type of theirs appears here, only Eigen and std types.
// All coordinates are metres in the map's local frame (for a scenario: East-North-Up around the
// anchor, z in the map's height datum); the readers do no transformation.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace driftcorr {

/// The points of a PCD file (ASCII, binary or binary_compressed) as the surface a person walks
/// on. Only the x, y, z fields are read. Throws driftcorr::InputError naming the file when it
/// cannot be read or parsed, has no x/y/z fields, has no point, or has a point with a NaN or
/// infinite coordinate (the message gives how many and the first index).
std::vector<Eigen::Vector3d> ReadSurfacePointsPcd(const std::string& path);

/// The vertices of a PLY file (ASCII or binary), with the same rules and errors as
/// ReadSurfacePointsPcd.
std::vector<Eigen::Vector3d> ReadSurfacePointsPly(const std::string& path);

/// Dispatch on the extension: .pcd, .ply, .bt or .ot (case-insensitive). Throws InputError for
/// another extension.
std::vector<Eigen::Vector3d> ReadSurfacePoints(const std::string& path);

/// The floor of an OctoMap occupancy tree (.bt: OcTree::readBinary, .ot: AbstractOcTree::read,
/// which must hold an OcTree). Floor rule: an occupied leaf voxel (at the finest resolution; a
/// pruned, coarser occupied leaf counts by its top layer of finest voxels) whose voxel directly
/// above is NOT occupied, i.e. free or unknown (a scan rarely observes the free space right above
/// the floor, so unknown must count; a voxel stacked under another occupied one is inside a slab
/// or wall and is not floor). Returns the top-face centres of the floor voxels: voxel centre +
/// half a voxel in z, the height a person stands at. Throws InputError naming the file when it
/// cannot be read or parsed as an OcTree, or has no floor voxel.
std::vector<Eigen::Vector3d> ReadFloorVoxelsOctomap(const std::string& path);

/// The centres of every occupied voxel of an OctoMap (a pruned occupied leaf expanded to its
/// finest voxels): a raw map of walls, floors, ceilings and furniture for
/// ExtractWalkableSurface (walkable_surface.h). Throws InputError naming the file when it cannot
/// be read, has no occupied voxel, or would expand to more than 30 M voxels. `resolution_m`, when
/// given, receives the map's voxel size.
std::vector<Eigen::Vector3d> ReadOccupiedVoxelsOctomap(const std::string& path,
                                                       double* resolution_m = nullptr);

/// A raw 3D map's points by extension: .pcd and .ply every point (as ReadSurfacePointsPcd /
/// Ply), .bt and .ot the occupied voxels' centres (ReadOccupiedVoxelsOctomap). `voxel_m`, when
/// given, receives an OctoMap's voxel size (0 for a point cloud).
std::vector<Eigen::Vector3d> ReadRawPoints(const std::string& path, double* voxel_m = nullptr);

/// Writers (used by the synthetic building generator and the tests). Each writes through a
/// temporary file renamed when complete (atomic_file.h); throws std::runtime_error naming the file
/// when it cannot be written. Points are stored as 32-bit floats (keep coordinates local: a float
/// has about 0.5 m resolution at UTM northings).
void WriteSurfacePointsPcd(const std::string& path, const std::vector<Eigen::Vector3d>& points);
void WriteSurfacePointsPly(const std::string& path, const std::vector<Eigen::Vector3d>& points);

/// Writes an OctoMap of resolution resolution_m in which, for every surface point, the voxel just
/// below it (containing the point minus half a voxel in z) is occupied, so that its top face is at
/// the surface height up to the voxel quantisation; all other space is unknown. The format follows
/// the extension as ReadFloorVoxelsOctomap reads it: ".ot" (either case) the full format
/// (occupancy log-odds per node), any other the binary one (.bt, occupancy bits only).
/// Precondition: resolution_m > 0.
void WriteOctomapFromPoints(const std::string& path, const std::vector<Eigen::Vector3d>& points,
                            double resolution_m);

}  // namespace driftcorr

namespace driftcorr {

/// The readers and writers above as one table, for a program that loads this library only when
/// a map needs it (PCL and OctoMap bring about a hundred shared libraries whose loading would
/// otherwise cost every run of the program: driftcorr/pipeline/surface_io_loader.h).
struct SurfaceIoApi {
    std::vector<Eigen::Vector3d> (*read_surface_points)(const std::string& path);
    std::vector<Eigen::Vector3d> (*read_raw_points)(const std::string& path, double* voxel_m);
    void (*write_surface_points_pcd)(const std::string& path,
                                     const std::vector<Eigen::Vector3d>& points);
    void (*write_surface_points_ply)(const std::string& path,
                                     const std::vector<Eigen::Vector3d>& points);
};

}  // namespace driftcorr

/// The table, under an unmangled name that dlsym finds.
extern "C" const driftcorr::SurfaceIoApi* driftcorr_surface_io_api();
