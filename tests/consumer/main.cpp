// Corrects a short synthetic drive without a map (odometry only) through the installed library,
// with the pipeline's road defaults, and reads a missing params.yaml (an error naming the file).
#include <cstdio>
#include <exception>
#include <string>

#include "driftcorr/optim/corrector.h"
#include "driftcorr/pipeline/pipeline.h"

int main() {
    driftcorr::PlanarTrajectory estimate;
    for (int i = 0; i < 20; ++i) {  // 1 m steps due East at 1 Hz
        estimate.t_s.push_back(i);
        estimate.p_en.emplace_back(i, 0.0);
        estimate.up_m.push_back(0.0);
        estimate.yaw_rad.push_back(0.0);
    }
    const driftcorr::pipeline::PipelineConfig config;
    const driftcorr::CorrectionResult result =
        driftcorr::CorrectTrajectory(estimate, nullptr, config.corrector);
    if (!driftcorr::Usable(result.status) || result.corrected.size() != estimate.size()) {
        std::printf("correction failed: %s\n", result.message.c_str());
        return 1;
    }
    // Without a map the odometry is all there is: the corrected end stays at the estimate's end.
    const double end_moved_m = (result.corrected.p_en.back() - estimate.p_en.back()).norm();
    std::printf("driftcorr consumer: %zu poses, status %s, end moved %.3f m\n",
                result.corrected.size(), driftcorr::ToString(result.status).c_str(), end_moved_m);

    const std::string missing = "/nonexistent/params.yaml";
    try {
        driftcorr::pipeline::LoadPipelineConfig(missing);
        std::printf("reading %s did not fail\n", missing.c_str());
        return 1;
    } catch (const std::exception& e) {
        std::printf("driftcorr consumer: %s\n", e.what());
        if (std::string(e.what()).find(missing) == std::string::npos) return 1;
    }
    return end_moved_m < 0.5 ? 0 : 1;
}
