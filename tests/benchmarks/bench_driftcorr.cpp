// Speed of the parts that matter: distance-field build (cells/s), the whole correction (poses/s,
// each stage, peak memory), one window solve by the Newton solver and by Ipopt, the per-pose
// covariance (linear in the number of poses).
// Run: build/tests/bench_driftcorr [--benchmark_filter=...]. The correction benchmarks read the
// real KITTI scenarios from ../shared/datasets and are skipped (with a message) when absent.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "driftcorr/core/observables.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/incremental_corrector.h"
#include "driftcorr/optim/ipopt_solver.h"
#include "driftcorr/optim/newton_solver.h"
#include "driftcorr/pipeline/pipeline.h"

namespace {

using namespace driftcorr;

// A street grid of n x n streets, 100 m apart, plus a curved road: a hand-made network.
RoadNetwork GridNetwork(int n) {
    RoadNetwork net;
    for (int k = 0; k < n; ++k) {
        RoadPolyline a{k, "residential", 4.5, {{0.0, 100.0 * k}, {100.0 * (n - 1), 100.0 * k}}};
        RoadPolyline b{
            1000 + k, "residential", 4.5, {{100.0 * k, 0.0}, {100.0 * k, 100.0 * (n - 1)}}};
        net.roads.push_back(a);
        net.roads.push_back(b);
    }
    RoadPolyline arc{5000, "secondary", 6.0, {}};
    for (int i = 0; i <= 100; ++i) {
        const double t = M_PI * i / 100.0;
        arc.points_en.emplace_back(50.0 * n + 40.0 * n * std::cos(t),
                                   50.0 * n + 40.0 * n * std::sin(t));
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
        cells = field.Samples();
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
    double load_s = 0.0, map_s = 0.0, solve_s = 0.0, incremental_s = 0.0, refine_s = 0.0;
    for (auto _ : state) {
        pipeline::CorrectionRun run = pipeline::RunCorrection(dir, pipeline::PipelineConfig{});
        poses = run.estimate.size();
        load_s += run.timings.load_s;
        map_s += run.timings.map_s;
        solve_s += run.timings.solve_s;
        incremental_s += run.result.incremental_s;
        refine_s += run.result.refine_s;
        benchmark::DoNotOptimize(run);
    }
    const double n = double(state.iterations());
    state.counters["poses"] = double(poses);
    state.counters["load_ms"] = 1e3 * load_s / n;
    state.counters["map_and_field_ms"] = 1e3 * map_s / n;
    state.counters["correction_ms"] = 1e3 * solve_s / n;
    state.counters["incremental_ms"] = 1e3 * incremental_s / n;
    state.counters["refine_ms"] = 1e3 * refine_s / n;
    state.counters["correction_poses_per_s"] = double(poses) * n / solve_s;
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    state.counters["peak_memory_mb"] = double(usage.ru_maxrss) / 1024.0;  // the process's so far
}
BENCHMARK_CAPTURE(BM_CorrectKitti, kitti00_cvo, std::string("kitti00_cvo_stereo_geometric"))
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
BENCHMARK_CAPTURE(BM_CorrectKitti, kitti00_orb2, std::string("kitti00_orb2_longruidong"))
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

// A car driving laps of a circular road (radius 160 m, 2 m steps at 10 Hz) on its centre line,
// and the road's field.
struct Lap {
    PlanarTrajectory truth;
    TraversableField field;
};

Lap CircleLap(std::size_t n) {
    const double radius_m = 160.0, step_m = 2.0;
    PlanarTrajectory lap;
    for (std::size_t i = 0; i < n; ++i) {
        const double a = step_m * double(i) / radius_m;
        lap.t_s.push_back(0.1 * double(i));
        lap.p_en.emplace_back(radius_m * std::sin(a), radius_m * (1.0 - std::cos(a)));
        lap.up_m.push_back(0.0);
        lap.yaw_rad.push_back(a);
    }
    RoadNetwork net;
    RoadPolyline road{1, "residential", 3.5, {}};
    for (int k = 0; k <= 400; ++k)
        road.points_en.push_back(lap.p_en[0] +
                                 radius_m * Eigen::Vector2d(std::sin(2.0 * M_PI * k / 400.0),
                                                            -std::cos(2.0 * M_PI * k / 400.0)) +
                                 Eigen::Vector2d(0.0, radius_m));
    net.roads.push_back(road);
    RoadFieldConfig field_cfg;
    field_cfg.margin_m = 30.0;
    return {lap, RasteriseRoads(net, net.Bounds(), field_cfg)};
}

TrajectoryState StateOf(const PlanarTrajectory& lap, const CorrectorConfig& cfg) {
    const std::size_t n = lap.size();
    TrajectoryState s;
    s.obs = ComputeObservations(lap);
    s.scale_segment = ScaleSegments(s.obs, cfg.model.scale_segment_m);
    s.scales.assign(s.scale_segment.back() + 1, 1.0);
    s.bias_segment = BiasSegments(s.obs, cfg.model.heading_bias_segment_s);
    if (!s.bias_segment.empty()) s.biases.assign(s.bias_segment.back() + 1, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        s.poses.push_back(
            PoseState{Eigen::Vector3d(lap.p_en[i].x(), lap.p_en[i].y(), 0.0), lap.yaw_rad[i]});
    }
    return s;
}

// One soft window of n poses, from a start 2 % too long and turned by 2 mrad per step (a drifting
// dead-reckoned chain) onto the lap's road: state.range(1) 0 the Newton solver, 1 Ipopt.
void BM_WindowSolve(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const bool ipopt = state.range(1) == 1;
    const Lap lap = CircleLap(n);
    const CorrectorConfig cfg;
    TrajectoryState start = StateOf(lap.truth, cfg);
    for (std::size_t i = 1; i < n; ++i) {
        start.obs[i].length_m *= 1.02;
        start.obs[i].dheading_rad += 0.002;
        start.poses[i] = ComposeStep(start.poses[i - 1], start.obs[i], 1.0, true, 0.0, 0.0);
    }
    int iterations = 0;
    for (auto _ : state) {
        TrajectoryState s = start;
        WindowProblem p(s, &lap.field, cfg.model, 1, n - 1, std::vector<std::uint8_t>(n - 1, 0));
        const SolveReport r =
            ipopt ? SolveWithIpopt(p, cfg.window_ipopt) : SolveWithNewton(p, NewtonOptions{});
        if (!Usable(r.status)) state.SkipWithError(r.message.c_str());
        iterations = r.iterations;
        benchmark::DoNotOptimize(s);
    }
    state.SetLabel(ipopt ? "Ipopt" : "Newton");
    state.counters["iterations"] = iterations;
    state.counters["poses_per_s"] =
        benchmark::Counter(double(n) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_WindowSolve)
    ->Args({300, 0})
    ->Args({300, 1})
    ->Args({3000, 0})
    ->Args({3000, 1})
    ->Unit(benchmark::kMillisecond);

// The covariance of n poses of the lap.
void BM_Covariance(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const Lap lap = CircleLap(n);
    const CorrectorConfig cfg;
    const TrajectoryState s = StateOf(lap.truth, cfg);
    const TraversableField& field = lap.field;
    std::size_t unknowns = 0;
    for (auto _ : state) {
        const CovarianceResult r = ComputeCovariance(s, &field, cfg.model, cfg.covariance);
        if (r.status != CovarianceStatus::kOk) state.SkipWithError(r.message.c_str());
        unknowns = r.unknowns;
        benchmark::DoNotOptimize(r);
    }
    state.counters["unknowns"] = double(unknowns);
    state.counters["us_per_pose"] = benchmark::Counter(
        double(n) * state.iterations(), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
    state.SetComplexityN(state.range(0));
}
BENCHMARK(BM_Covariance)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond)
    ->Complexity(benchmark::oN);

}  // namespace

BENCHMARK_MAIN();
