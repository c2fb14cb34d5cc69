#pragma once
// A raw point cloud of the synthetic building, as a mapping run (lidar or visual-inertial scan)
// would give it: floors with holes, walls, ceilings, stair treads, risers and undersides, the
// lift shaft with its cabin at one level, and furniture; with dropout and noise. Its true
// walkable surface is SampleSurface (building.h) without the floor under the furniture
// (PlaceFurniture); the lift shaft is walkable once a user declares the lift (the cabin sweeps
// it). Local East-North-Up frame [m].
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "building.h"

namespace driftcorr::synth {

struct RawScanConfig {
    /// Spacing of the samples on every surface (floor lattice, along and up walls, ...) [m],
    /// in (0.01, 0.5].
    double spacing_m = 0.05;
    /// Gaussian noise added to each coordinate of each point, 1 sigma [m], in [0, 0.1].
    double noise_sigma_m = 0.01;
    /// Probability that a point is dropped (independently per point), in [0, 1).
    double dropout = 0.05;
    /// Share of the slab floor points removed in random discs of radius 0.3-1.0 m, in [0, 0.5].
    double hole_share = 0.03;
    /// Seed of the furniture placement, the holes, the dropout and the noise (separate streams).
    std::uint64_t seed = 1;
    /// Height of the ceilings above each floor [m], in [2.2, 10]; less than the floor spacing.
    double ceiling_height_m = 3.0;
    /// Height of the roof [m]: the ceiling of the top floor, and the top of the lift shaft and
    /// of the stairwell. Precondition: more than 2.2 m above the top floor.
    double roof_z_m = 11.0;

    /// Empty when valid, else the name of the first bad field and why.
    std::string Validate() const;
};

constexpr double kTableTopHeight_m = 0.75;  ///< table top above its floor
constexpr double kCabinetHeight_m = 1.9;    ///< cabinet top above its floor

/// The furniture of one room on one floor (axis-aligned footprints in the floor's x, y).
struct RoomFurniture {
    int floor = 0;  ///< index into BuildingLayout::floor_z_m
    Rect room;      ///< the room's slab
    Rect table;     ///< 1.2 m x 0.8 m, either way round; top at kTableTopHeight_m
    Rect cabinet;   ///< 1.0 m x 0.5 m, its back 2 cm off a wall; kCabinetHeight_m tall
};

/// One table and one cabinet in every room on every floor. A room is a slab at least 5 m wide
/// both ways (the corridor and the stair passage are 3 m wide); its doors are the slabs that
/// touch it. Both footprints are at least 1.5 m from every door and 0.6 m from each other; the
/// table is at least 0.4 m from the walls. Positions drawn from `config.seed`. Order: floors,
/// then rooms in the order of `b.slabs`. Precondition: config.Validate() is empty.
std::vector<RoomFurniture> PlaceFurniture(const BuildingLayout& b, const RawScanConfig& config);

/// The raw scan, in this order before dropout: slab floors (holes cut, no floor under the
/// cabinets), ceilings, the lift cabin floor, walls, stairs, furniture. On the lattice
/// (spacing_m * (i + 0.5), spacing_m * (j + 0.5)) over the footprint [0, 60] x [0, 30]:
/// - floors: every slab cell on every floor;
/// - ceilings: every slab cell at floor + ceiling_height_m; on the top floor the roof at
///   roof_z_m over the slab, stair and lift cells;
/// - walls: vertical faces on the boundary between a slab cell and a cell of no slab, stair or
///   lift (the walls are solid; their inside is empty), from each floor to its ceiling; the
///   stairwell wall and the lift shaft from the lowest floor to the roof, the shaft's lobby side
///   open only at the ground floor up to 2.1 m (the cabin is there; the other landing doors
///   are closed). Faces lie exactly on the slab, stair or lift rectangle's edge;
/// - stairs: per flight, round(rise / 0.18 m) risers over the stair's run, treads and risers
///   centred on the clean flight's line (tread k centred at x0 + k * run / n at floor + k * rise
///   / n, half treads at both ends), the underside 0.25 m below that line (above the lowest
///   floor), and the flight's side face where it borders a slab (open side);
/// - the lift cabin floor at the lowest floor only;
/// - furniture (PlaceFurniture): table top and four legs (vertical lines 5 cm in from the
///   corners), cabinet top and its four sides.
/// Then discs are removed from the slab floor points until hole_share of them are gone, each
/// point is dropped with probability dropout, and Gaussian noise is added to the rest.
/// Deterministic for a config. Precondition: config.Validate() is empty, the floors ascend with
/// gaps above ceiling_height_m, roof_z_m > top floor + 2.2 m.
std::vector<Eigen::Vector3d> SampleRawBuilding(const BuildingLayout& b,
                                               const RawScanConfig& config);

}  // namespace driftcorr::synth
