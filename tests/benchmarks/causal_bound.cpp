// What a causal estimate can reach with this model and map: at sampled epochs i, the batch
// corrector run on the estimate's prefix [0, i] (everything known at epoch i, solved as well as
// the batch mode solves a whole drive), and the error of its last pose. Compared at the same
// epochs with the online corrector's causal output (synchronous: every window solved) and with
// the batch result of the whole drive. If the prefix-batch error is itself far above the batch
// error, the gap is the information only later epochs carry (a turn that fixes the along-track
// position), not the online machinery.
// Run: build/tests/causal_bound [scenario dir ...]  (default: the 7 KITTI scenarios)
//      CAUSAL_STRIDE=n samples every n-th epoch (default 25); CAUSAL_VERBOSE=1 prints each;
//      CAUSAL_CONFIG=params.yaml sets the parameters of all three (as `driftcorr eval --config`).
// Every solve uses the scenario's mode settings and map field as `driftcorr eval` does
// (road2d or indoor3d; the online corrector with the same corrector settings).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "driftcorr/eval/evaluation.h"
#include "driftcorr/pipeline/pipeline.h"
#include "scenario_list.h"

namespace {

using namespace driftcorr;

PlanarTrajectory Prefix(const PlanarTrajectory& t, std::size_t n) {
    PlanarTrajectory out;
    out.t_s.assign(t.t_s.begin(), t.t_s.begin() + n);
    out.p_en.assign(t.p_en.begin(), t.p_en.begin() + n);
    out.up_m.assign(t.up_m.begin(), t.up_m.begin() + n);
    if (t.HasYaw()) out.yaw_rad.assign(t.yaw_rad.begin(), t.yaw_rad.begin() + n);
    return out;
}

void Evaluate(const std::string& dir) {
    // Batch and online causal output exactly as `driftcorr eval` runs them (its per-pose errors).
    eval::EvalConfig ec;
    if (const char* path = std::getenv("CAUSAL_CONFIG")) {
        ec.pipeline = pipeline::LoadPipelineConfig(path);
    }
    ec.methods = {eval::Method::kDriftcorr, eval::Method::kOnline};
    const eval::ScenarioEvaluation ev = eval::EvaluateScenario(dir, ec);
    const eval::MethodResult* batch = ev.Find(eval::Method::kDriftcorr);
    const eval::MethodResult* online = ev.Find(eval::Method::kOnline);
    if (!ev.ok() || !ev.has_ground_truth || !batch || !batch->ok || !online || !online->ok) {
        std::printf("%-30s skipped: %s\n", ev.label.c_str(),
                    !ev.ok()               ? ev.error.c_str()
                    : !ev.has_ground_truth ? "no ground truth"
                    : !batch || !batch->ok ? "batch failed"
                                           : "online failed");
        return;
    }
    // The same scenario, field and settings for the prefix solves.
    const pipeline::PreparedScenario ps = pipeline::PrepareScenario(dir, ec.pipeline);
    const CorrectorConfig& corrector = pipeline::CorrectorFor(ps.scenario, ec.pipeline);
    const PlanarTrajectory& gt = *ps.ground_truth;
    const PlanarTrajectory& est = ps.estimate;
    std::size_t stride = 25;
    if (const char* s = std::getenv("CAUSAL_STRIDE")) stride = std::max(1, std::atoi(s));

    double s_prefix = 0.0, s_online = 0.0, s_batch = 0.0;
    std::size_t count = 0, failed = 0;
    const std::size_t n = std::min(batch->errors_m.size(), online->errors_m.size());
    // A prefix needs 3 poses (CorrectTrajectory's precondition).
    for (std::size_t i = std::max<std::size_t>(stride, 2); i < n && i < est.size(); i += stride) {
        const CorrectionResult r = CorrectTrajectory(Prefix(est, i + 1), &ps.field, corrector);
        if (!Usable(r.status)) {
            ++failed;
            continue;
        }
        const double e_prefix = (r.corrected.p_en[i] - gt.p_en[i]).norm();
        const double e_online = online->errors_m[i];
        const double e_batch = batch->errors_m[i];
        s_prefix += e_prefix * e_prefix;
        s_online += e_online * e_online;
        s_batch += e_batch * e_batch;
        ++count;
        if (std::getenv("CAUSAL_VERBOSE")) {
            std::printf("  %zu prefix-batch %.2f (height %+.2f) online %.2f batch %.2f\n", i,
                        e_prefix, r.corrected.up_m[i] - gt.up_m[i], e_online, e_batch);
        }
    }
    if (count == 0) {
        std::printf("%-30s no epoch sampled\n", ps.scenario.name.c_str());
        return;
    }
    const double prefix = std::sqrt(s_prefix / count), onl = std::sqrt(s_online / count),
                 bat = std::sqrt(s_batch / count);
    std::printf(
        "%-30s %zu epochs (every %zu, %zu failed): RMS error batch %.2f | prefix-batch "
        "last pose %.2f (x%.2f) | online causal %.2f (x%.2f)\n",
        ps.scenario.name.c_str(), count, stride, failed, bat, prefix, prefix / bat, onl, onl / bat);
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) { return driftcorr::bench::ForEachScenario(argc, argv, Evaluate); }
