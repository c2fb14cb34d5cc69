// Speed of the parts that matter: distance-field build (cells/s), the whole correction (poses/s).
// Run: build/tests/bench_driftcorr [--benchmark_filter=...]. The correction benchmarks read the
// real KITTI scenarios from ../shared/datasets and are skipped (with a message) when absent.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "driftcorr/pipeline/pipeline.h"

namespace {

using namespace driftcorr;

// A street grid of n x n streets, 100 m apart, plus a curved road: a hand-made network.
RoadNetwork GridNetwork(int n) {
    RoadNetwork net;
    for (int k = 0; k < n; ++k) {
        RoadPolyline a{k, "residential", 4.5, {{0.0, 100.0 * k}, {100.0 * (n - 1), 100.0 * k}}};
        RoadPolyline b{1000 + k, "residential", 4.5, {{100.0 * k, 0.0}, {100.0 * k, 100.0 * (n - 1)}}};
        net.roads.push_back(a);
        net.roads.push_back(b);
    }
    RoadPolyline arc{5000, "secondary", 6.0, {}};
    for (int i = 0; i <= 100; ++i) {
        const double t = M_PI * i / 100.0;
        arc.points_en.emplace_back(50.0 * n + 40.0 * n * std::cos(t), 50.0 * n + 40.0 * n * std::sin(t));
    }
    net.roads.push_back(arc);
    return net;
}

void BM_RoadFieldBuild(benchmark::State& state) {
    const RoadNetwork net = GridNetwork(static_cast<int>(state.range(0)));
    RoadFieldConfig cfg;
    cfg.margin_m = 50.0;
    std::size_t cells = 0;
    for (auto _ : state) {
        TraversableField field = RasteriseRoads(net, net.Bounds(), cfg);
        cells = field.spec().size();
        benchmark::DoNotOptimize(field);
    }
    state.counters["cells"] = double(cells);
    state.counters["cells_per_s"] =
        benchmark::Counter(double(cells) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RoadFieldBuild)->Arg(6)->Arg(11)->Unit(benchmark::kMillisecond);

void BM_CorrectKitti(benchmark::State& state, const std::string& folder) {
    const std::string dir = std::string(DRIFTCORR_SHARED_DATASETS) + "/" + folder;
    if (!std::filesystem::exists(dir + "/scenario.yaml")) {
        state.SkipWithError(("real data not present: " + dir).c_str());
        return;
    }
    std::size_t poses = 0;
    double solve_s = 0.0;
    for (auto _ : state) {
        pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
        poses = run.estimate.size();
        solve_s += run.timings.solve_s;
        benchmark::DoNotOptimize(run);
    }
    state.counters["poses"] = double(poses);
    state.counters["correction_poses_per_s"] = double(poses) * state.iterations() / solve_s;
}
BENCHMARK_CAPTURE(BM_CorrectKitti, kitti00_cvo, std::string("kitti00_cvo_stereo_geometric"))
    ->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK_CAPTURE(BM_CorrectKitti, kitti00_orb2, std::string("kitti00_orb2_longruidong"))
    ->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
