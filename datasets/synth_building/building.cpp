// The definitions of what building.h declares.
#include "building.h"

#include <cmath>

namespace driftcorr::synth {

double BuildingLayout::StairZ(int f, double x) const {
    const double t = (x - stair.x0) / (stair.x1 - stair.x0);
    return floor_z_m[f] + t * (floor_z_m[f + 1] - floor_z_m[f]);
}

BuildingLayout MakeBuildingLayout() {
    BuildingLayout b;
    constexpr double kWall = 0.3, kRoom = 7.5;
    b.slabs.push_back({kWall, 13.5, 60.0 - kWall, 16.5});  // corridor along x
    for (int n = 0; n < 6; ++n) {                          // six rooms a side, x in [0, 45]
        const double x0 = kRoom * n + kWall, x1 = kRoom * (n + 1), xd = kRoom * n + 3.25;
        b.slabs.push_back({x0, kWall, x1, 13.5 - kWall});         // south room
        b.slabs.push_back({x0, 16.5 + kWall, x1, 30.0 - kWall});  // north room
        b.slabs.push_back({xd, 13.5 - kWall, xd + 1.0, 13.5});    // south door
        b.slabs.push_back({xd, 16.5, xd + 1.0, 16.5 + kWall});    // north door
    }
    b.slabs.push_back({45.0 + kWall, 10.5, 60.0 - kWall, 13.5});  // stair passage (open)
    b.slabs.push_back({45.0 + kWall, 9.0, 47.0, 10.5});           // lower landing
    b.slabs.push_back({55.0, 9.0, 57.0, 10.5});                   // upper landing
    b.slabs.push_back({45.0 + kWall, 16.5, 60.0 - kWall, 17.5});  // lift lobby (open)
    b.stair = {47.0, 9.0, 55.0, 10.5};                            // 8 m run for a 4 m rise
    b.lift = {50.0, 17.5, 52.0, 19.5};                            // 2 m x 2 m cabin
    return b;
}

std::vector<Eigen::Vector3d> SampleSurface(const BuildingLayout& b, double spacing_m) {
    const int ni = int(std::lround(60.0 / spacing_m)), nj = int(std::lround(30.0 / spacing_m));
    auto x_of = [&](int i) { return spacing_m * (i + 0.5); };
    std::vector<Eigen::Vector3d> points;
    for (double z : b.floor_z_m) {
        for (int j = 0; j < nj; ++j) {
            for (int i = 0; i < ni; ++i) {
                for (const Rect& r : b.slabs) {
                    if (!r.Contains(x_of(i), x_of(j))) continue;
                    points.emplace_back(x_of(i), x_of(j), z);
                    break;
                }
            }
        }
    }
    for (int f = 0; f + 1 < int(b.floor_z_m.size()); ++f) {
        for (int j = 0; j < nj; ++j) {
            for (int i = 0; i < ni; ++i) {
                if (b.stair.Contains(x_of(i), x_of(j)))
                    points.emplace_back(x_of(i), x_of(j), b.StairZ(f, x_of(i)));
            }
        }
    }
    const double z_lo = b.floor_z_m.front(), z_hi = b.floor_z_m.back();
    const int levels = int(std::lround((z_hi - z_lo) / b.lift_level_step_m));
    for (int l = 0; l <= levels; ++l) {
        for (int j = 0; j < nj; ++j) {
            for (int i = 0; i < ni; ++i) {
                if (b.lift.Contains(x_of(i), x_of(j)))
                    points.emplace_back(x_of(i), x_of(j), z_lo + l * b.lift_level_step_m);
            }
        }
    }
    return points;
}

}  // namespace driftcorr::synth
