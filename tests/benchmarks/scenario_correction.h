#pragma once
// A scenario with ground truth corrected as the pipeline corrects it (PrepareScenario, then
// CorrectFromStarts with the scenario's corrector settings), for the benchmark tools that compare
// a correction with its ground truth.
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "driftcorr/optim/corrector.h"
#include "driftcorr/optim/incremental_corrector.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::bench {

struct ScenarioCorrection {
    pipeline::PreparedScenario scenario;  ///< its field is the corrector's: held in place
    CorrectorConfig config;
    CorrectionResult result;
    std::optional<IncrementalCorrector> corrector;  ///< the kept correction's; its state solved
};

/// The correction of the scenario in `dir`; nothing (and a line saying so) when it has no ground
/// truth.
inline std::unique_ptr<ScenarioCorrection> CorrectWithGroundTruth(const std::string& dir) {
    const pipeline::PipelineConfig config;
    auto c = std::make_unique<ScenarioCorrection>();
    c->scenario = pipeline::PrepareScenario(dir, config);
    const pipeline::PreparedScenario& ps = c->scenario;
    if (!ps.ground_truth) {
        std::printf("%s: no ground truth, skipped\n", ps.scenario.name.c_str());
        return nullptr;
    }
    c->config = pipeline::CorrectorFor(ps.scenario, config);
    c->corrector.emplace(CorrectFromStarts(ps.estimate, &ps.field, c->config, c->result));
    return c;
}

}  // namespace driftcorr::bench
