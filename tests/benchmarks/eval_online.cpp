// Online vs batch quality on the shared scenarios: batch ATE, causal (per-epoch Push output) ATE
// and smoothed (Finish) ATE, for the synchronous mode (the solver keeps up: the case of a stream
// at its real rate, KITTI 10 Hz, where a window solve takes far less than a chunk's duration) and
// for the threaded mode replayed as fast as possible (the solver lags; a worst case).
// Run: build/tests/eval_online [scenario dir ...]  (default: the 7 KITTI scenarios)
//      DUMP_CAUSAL=file writes, per epoch of the synchronous run: index, time, causal, estimate
//      and batch error [m] (the last scenario run overwrites it).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "driftcorr/pipeline/online.h"
#include "scenario_list.h"

namespace {

using namespace driftcorr;

struct OnlineRun {
    PlanarTrajectory causal;
    CorrectionResult smoothed;
};

OnlineRun RunOnline(const pipeline::CorrectionRun& run, const TraversableField& field,
                    bool synchronous) {
    OnlineConfig cfg;
    cfg.synchronous = synchronous;
    if (const char* c = std::getenv("CHUNK_M")) cfg.corrector.chunk_m = std::atof(c);
    if (const char* u = std::getenv("UPDATE_FRACTION")) cfg.update_fraction = std::atof(u);
    OnlineCorrector online(&field, cfg);
    OnlineRun out;
    for (std::size_t i = 0; i < run.estimate.size(); ++i) {
        const PlanarPose in{run.estimate.t_s[i], run.estimate.p_en[i], run.estimate.up_m[i],
                            run.estimate.yaw_rad[i]};
        const PushResult r = online.Push(in);
        out.causal.t_s.push_back(r.corrected.t_s);
        out.causal.p_en.push_back(r.corrected.p_en);
        out.causal.up_m.push_back(r.corrected.up_m);
    }
    out.smoothed = online.Finish();
    return out;
}

// RMS of the error along and across the ground truth's direction of travel (over 5 m chords;
// poses where the ground truth stands are left out): a road map corrects the cross-track error
// everywhere, the along-track error only at turns, so a causal estimate lags the smoothed one
// along the track.
struct AlongCross {
    double along_m = 0.0, cross_m = 0.0;
};
AlongCross AlongCrossRms(const PlanarTrajectory& t, const PlanarTrajectory& gt) {
    const std::size_t n = std::min(t.size(), gt.size());
    double sa = 0.0, sc = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        std::size_t a = i, b = i;
        while (a > 0 && (gt.p_en[i] - gt.p_en[a]).norm() < 2.5) --a;
        while (b + 1 < n && (gt.p_en[b] - gt.p_en[i]).norm() < 2.5) ++b;
        const Eigen::Vector2d d = gt.p_en[b] - gt.p_en[a];
        if (d.norm() < 2.5) continue;
        const Eigen::Vector2d u = d.normalized(), e = t.p_en[i] - gt.p_en[i];
        const double along = u.dot(e), cross = u.x() * e.y() - u.y() * e.x();
        sa += along * along;
        sc += cross * cross;
        ++count;
    }
    if (count == 0) return {};
    return {std::sqrt(sa / double(count)), std::sqrt(sc / double(count))};
}

void Evaluate(const std::string& dir) {
    const pipeline::PipelineConfig cfg;
    const pipeline::CorrectionRun run = pipeline::RunCorrection(dir, cfg);
    const pipeline::StreamSetup setup = pipeline::LoadStreamSetup(dir, cfg);
    const PlanarTrajectory& gt = *run.ground_truth;
    const AlongCross b = AlongCrossRms(run.result.corrected, gt);
    std::printf("%-30s batch %7.2f (along %.2f cross %.2f) |", run.scenario.name.c_str(),
                run.after ? run.after->ate_m : -1.0, b.along_m, b.cross_m);
    const char* modes = std::getenv("ONLINE_MODES");  // "sync", "fast" or both (default)
    for (bool sync : {true, false}) {
        if (modes && std::string(modes) != (sync ? "sync" : "fast")) continue;
        const OnlineRun o = RunOnline(run, setup.field, sync);
        const double causal = ComputeMetrics(o.causal, gt).ate_m;
        const double smooth =
            Usable(o.smoothed.status) ? ComputeMetrics(o.smoothed.corrected, gt).ate_m : -1.0;
        const AlongCross c = AlongCrossRms(o.causal, gt);
        if (const char* dump = std::getenv("DUMP_CAUSAL"); dump && sync) {
            // index, time, causal error, estimate error, batch error [m]
            if (FILE* f = std::fopen(dump, "w")) {
                for (std::size_t i = 0; i < gt.size() && i < o.causal.size(); ++i) {
                    std::fprintf(f, "%zu %.3f %.3f %.3f %.3f\n", i, gt.t_s[i],
                                 (o.causal.p_en[i] - gt.p_en[i]).norm(),
                                 (run.estimate.p_en[i] - gt.p_en[i]).norm(),
                                 (run.result.corrected.p_en[i] - gt.p_en[i]).norm());
                }
                std::fclose(f);
            }
        }
        std::printf(" %s causal %7.2f (x%.2f; along %.2f cross %.2f) smoothed %7.2f |",
                    sync ? "sync" : "fast", causal, causal / run.after->ate_m, c.along_m, c.cross_m,
                    smooth);
    }
    std::printf("\n");
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) { return driftcorr::bench::ForEachScenario(argc, argv, Evaluate); }
