// Per-epoch latency of the online corrector: kitti00_cvo_stereo_geometric replayed through
// OnlineCorrector::Push as fast as possible (threaded mode: window solves run on the worker).
// Reports p50, p99 and max of the Push latency as counters (microseconds).
// Run on one core: taskset -c 0 build/tests/bench_online
// Skipped with a message when ../shared/datasets is absent.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/pipeline/online.h"

namespace {

using namespace driftcorr;

const std::string kScenario =
    std::string(DRIFTCORR_SHARED_DATASETS) + "/kitti00_cvo_stereo_geometric";

void BM_OnlinePushLatency(benchmark::State& state) {
    if (!std::filesystem::exists(kScenario)) {
        state.SkipWithError(("scenario not found: " + kScenario).c_str());
        return;
    }
    const pipeline::PipelineConfig cfg;
    const pipeline::StreamSetup setup = pipeline::LoadStreamSetup(kScenario, cfg);
    const Trajectory est = io::LoadTrajectory(setup.scenario.estimate);
    const PlanarTrajectory planar = ToPlanar(est, setup.scenario.frame, setup.anchor);
    std::vector<double> us;
    for (auto _ : state) {
        OnlineCorrector online(&setup.field, OnlineConfig{});
        for (std::size_t i = 0; i < planar.size(); ++i) {
            const PlanarPose in{planar.t_s[i], planar.p_en[i], planar.up_m[i], planar.yaw_rad[i]};
            const auto t0 = std::chrono::steady_clock::now();
            benchmark::DoNotOptimize(online.Push(in));
            const auto t1 = std::chrono::steady_clock::now();
            us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        }
        state.PauseTiming();
        benchmark::DoNotOptimize(online.Finish());
        state.ResumeTiming();
    }
    std::sort(us.begin(), us.end());
    auto pct = [&](double p) { return us[std::min(us.size() - 1, std::size_t(p * us.size()))]; };
    state.counters["p50_us"] = pct(0.50);
    state.counters["p99_us"] = pct(0.99);
    state.counters["max_us"] = us.back();
    state.counters["epochs"] = double(us.size());
}
BENCHMARK(BM_OnlinePushLatency)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
