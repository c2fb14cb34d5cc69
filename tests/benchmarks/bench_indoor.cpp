// Speed of the indoor field build: a synthetic 100 m x 100 m building of three floors (rooms on
// both sides of corridors, walls, doors, a staircase and a lift) at 0.1 m horizontal resolution.
// Run: taskset -c 0 build/tests/bench_indoor   (one core; the counter voxels_per_s is the rate).
#include <benchmark/benchmark.h>

#include "driftcorr/mapping/indoor_field.h"

namespace {

using namespace driftcorr;

FloorPolygon Rect(double x0, double y0, double x1, double y1) {
    return {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, {}};
}

// Rooms 10 m x 8 m in rows north and south of three east-west corridors (3 m wide), one
// north-south corridor; 0.2 m walls around every room, a 1 m door from each room to its corridor.
IndoorFloor SyntheticFloor(double z) {
    IndoorFloor f;
    f.floor_z_m = z;
    f.walls.push_back(Rect(-0.3, -0.3, 100.3, 0.0));  // facade
    f.walls.push_back(Rect(-0.3, 100.0, 100.3, 100.3));
    f.walls.push_back(Rect(-0.3, 0.0, 0.0, 100.0));
    f.walls.push_back(Rect(100.0, 0.0, 100.3, 100.0));
    f.walkable.push_back(Rect(48.5, 0.0, 51.5, 100.0));  // north-south corridor
    f.walkways_en.push_back({{50.0, 0.5}, {50.0, 99.5}});
    for (double yc : {16.5, 50.0, 83.5}) {
        f.walkable.push_back(Rect(0.0, yc - 1.5, 100.0, yc + 1.5));
        f.walkways_en.push_back({{0.5, yc}, {99.5, yc}});
        for (double x0 = 0.0; x0 < 100.0; x0 += 10.0) {
            if (x0 == 40.0 || x0 == 50.0) continue;  // the north-south corridor
            for (int side : {-1, 1}) {
                const double y_in = yc + side * 1.5, y_out = yc + side * 9.5;
                const double y0 = std::min(y_in, y_out), y1 = std::max(y_in, y_out);
                f.walkable.push_back(Rect(x0, y0, x0 + 10.0, y1));
                f.walls.push_back(Rect(x0, y0, x0 + 0.2, y1));
                f.walls.push_back(Rect(x0 + 9.8, y0, x0 + 10.0, y1));
                f.walls.push_back(Rect(x0, y_in - 0.1, x0 + 10.0, y_in + 0.1));
                f.doors.push_back(Rect(x0 + 4.5, y_in - 0.2, x0 + 5.5, y_in + 0.2));
            }
        }
    }
    f.stairs.push_back(Rect(92.0, 46.0, 98.0, 48.5));
    f.lifts.push_back(Rect(2.0, 51.5, 4.5, 54.0));
    return f;
}

void BM_IndoorFieldBuild(benchmark::State& state) {
    const std::vector<IndoorFloor> floors = {SyntheticFloor(0.0), SyntheticFloor(4.0),
                                             SyntheticFloor(8.0)};
    IndoorFieldConfig cfg;
    cfg.resolution_m = 0.1;
    cfg.resolution_z_m = double(state.range(0)) / 100.0;
    std::size_t voxels = 0;
    for (auto _ : state) {
        IndoorFieldStats stats;
        TraversableField field = BuildIndoorField(floors, cfg, &stats);
        voxels = stats.voxels;
        benchmark::DoNotOptimize(field);
    }
    state.counters["voxels"] = double(voxels);
    state.counters["voxels_per_s"] =
        benchmark::Counter(double(voxels) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_IndoorFieldBuild)->Arg(50)->Arg(25)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
