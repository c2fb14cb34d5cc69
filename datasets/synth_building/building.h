#pragma once
// The synthetic building of driftcorr_make_building_scenario: three floors (0, 4, 8 m) of
// 60 m x 30 m, each a corridor with rooms on both sides (1 m doors), a straight staircase
// between neighbouring floors and a lift shaft; and the walkable surface sampled as points.
// Everything is axis-aligned and in the local East-North-Up frame of the scenario [m].
#include <Eigen/Core>
#include <vector>

namespace driftcorr::synth {

struct Rect {
    double x0, y0, x1, y1;
    bool Contains(double x, double y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
};

/// The layout, the same on every floor. Walls are the gaps between the rectangles (0.3 m).
struct BuildingLayout {
    std::vector<double> floor_z_m = {0.0, 4.0, 8.0};
    std::vector<Rect> slabs;  ///< corridor, rooms, doors, stair passage and landings, lift lobby
    /// The flight from floor f to f + 1 rises along +x over `stair` from floor_z_m[f] at x0 to
    /// floor_z_m[f + 1] at x1; flights are stacked, no slab covers their footprint.
    Rect stair;
    Rect lift;  ///< the shaft; its cabin floor is sampled every lift_level_step_m
    double lift_level_step_m = 0.25;

    double StairZ(int f, double x) const;  ///< height of flight f (from floor f) at x
};

BuildingLayout MakeBuildingLayout();

/// Walkable surface points on the lattice (spacing_m * (i + 0.5), spacing_m * (j + 0.5)): every
/// slab on every floor, every flight, and the lift cabin floor at every lift level from the
/// lowest to the highest floor (the cabin floor sweeps the shaft, so the whole shaft is walkable
/// surface). Deterministic order: floors, then flights, then lift levels, row by row.
std::vector<Eigen::Vector3d> SampleSurface(const BuildingLayout& b, double spacing_m);

}  // namespace driftcorr::synth
