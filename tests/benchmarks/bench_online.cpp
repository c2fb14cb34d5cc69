// Per-epoch latency of the online corrector with the correction on: kitti00_cvo_stereo_geometric
// pushed through OnlineCorrector::Push at 100 Hz (threaded mode: the window solves run on the
// worker, on the same core when pinned). Reports p50, p99 and max of the Push latency
// (microseconds), the solve time per window (milliseconds), the share of poses returned without a
// fresh solve, the worst correction age (epochs) and the back-pressure waits (seconds). The whole
// program, through a pipe and the binary: tests/benchmarks/run_stream_bench.sh. Run on one core:
// taskset -c 0 build/tests/bench_online Skipped with a message when ../shared/datasets is absent.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
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
    constexpr double kRateHz = 100.0;
    std::vector<double> us, solve_ms;
    double stale = 0.0, max_age = 0.0, waited_s = 0.0;
    for (auto _ : state) {
        OnlineCorrector online(&setup.field, OnlineConfig{});
        const auto start = std::chrono::steady_clock::now();
        for (std::size_t i = 0; i < planar.size(); ++i) {
            std::this_thread::sleep_until(start + std::chrono::duration<double>(i / kRateHz));
            const PlanarPose in{planar.t_s[i], planar.p_en[i], planar.up_m[i], planar.yaw_rad[i]};
            const auto t0 = std::chrono::steady_clock::now();
            const PushResult r = online.Push(in);
            const auto t1 = std::chrono::steady_clock::now();
            // A back-pressure wait (this replay runs 10x faster than the drive) comes before the
            // pose is taken: not part of its latency (counted in waits_s).
            us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count() -
                         1e6 * r.waited_s);
        }
        const OnlineStatistics st = online.Statistics();
        for (double s : st.solve_s) solve_ms.push_back(1e3 * s);
        stale = std::max(stale, double(st.stale_poses) / double(st.poses));
        max_age = std::max(max_age, double(st.max_age_epochs));
        waited_s = st.wait_s;
        state.PauseTiming();
        benchmark::DoNotOptimize(online.Finish());
        state.ResumeTiming();
    }
    auto pct = [](std::vector<double>& v, double p) {
        std::sort(v.begin(), v.end());
        return v.empty() ? 0.0 : v[std::min(v.size() - 1, std::size_t(p * v.size()))];
    };
    state.counters["p50_us"] = pct(us, 0.50);
    state.counters["p99_us"] = pct(us, 0.99);
    state.counters["max_us"] = us.back();
    state.counters["epochs"] = double(us.size());
    state.counters["solve_p50_ms"] = pct(solve_ms, 0.50);
    state.counters["solve_p99_ms"] = pct(solve_ms, 0.99);
    state.counters["solve_max_ms"] = solve_ms.empty() ? 0.0 : solve_ms.back();
    state.counters["stale_share"] = stale;
    state.counters["max_age_epochs"] = max_age;
    state.counters["waits_s"] = waited_s;
}
BENCHMARK(BM_OnlinePushLatency)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
