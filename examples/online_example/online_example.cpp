// The online corrector in a few lines: a scenario's map, its estimate fed pose by pose, each
// corrected pose printed as TUM at once, how fresh the corrections were, the smoothed trajectory
// at the end. A file is a replay: far faster than any sensor, so Push waits for the solver
// (back-pressure, OnlineConfig::max_lag_epochs) instead of emitting poses composed onto old
// solves; a live source at its own pace is never held back.
// Run: driftcorr_online_example <scenario dir>
#include <cstdio>

#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/io/tum_line.h"
#include "driftcorr/pipeline/online.h"

int main(int argc, char** argv) {
    using namespace driftcorr;
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s <scenario dir | scenario.yaml>\n", argv[0]);
        return 1;
    }
    try {
        // The map, anchor and frame of the scenario; the poses could come from any source.
        const pipeline::StreamSetup setup = pipeline::LoadStreamSetup(argv[1], {});
        const Trajectory est = io::LoadTrajectory(setup.scenario.estimate);
        const FrameAxes axes = setup.scenario.frame;

        OnlineCorrector online(&setup.field, OnlineConfig{});
        for (std::size_t i = 0; i < est.size(); ++i) {
            const PlanarPose in =
                pipeline::ToPlanarPose(est.t_s[i], est.p_frame[i], est.q_frame_body[i], setup);
            const PushResult r = online.Push(in);  // returns at once: a causal estimate
            if (!r.Accepted()) {
                std::fprintf(stderr, "pose %zu skipped: %s\n", i, r.message.c_str());
                continue;
            }
            const auto [p, q] = pipeline::FromPlanarPose(r.corrected, in, est.p_frame[i],
                                                         est.q_frame_body[i], axes, setup.anchor);
            std::fputs(io::FormatTumLine(est.t_s[i], p, q).c_str(), stdout);
        }
        const OnlineStatistics st = online.Statistics();
        std::fprintf(stderr, "%zu of %zu poses without a fresh solve, worst age %zu epochs\n",
                     st.stale_poses, st.poses, st.max_age_epochs);
        const CorrectionResult smoothed = online.Finish();  // the whole trajectory, refined
        std::fprintf(stderr, "smoothed: %s (%s), %zu poses\n", ToString(smoothed.status).c_str(),
                     smoothed.message.c_str(), smoothed.corrected.size());
        return Usable(smoothed.status) ? 0 : 3;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
}
