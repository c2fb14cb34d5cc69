#include "driftcorr/optim/corrector.h"

#include <cassert>

#include "driftcorr/optim/incremental_corrector.h"

namespace driftcorr {

std::string CorrectorConfig::Validate() const {
    if (std::string m = model.Validate(); !m.empty()) return m;
    if (!(chunk_m > 0.0)) return "corrector.chunk_m: must be > 0";
    if (!(window_m >= chunk_m)) return "corrector.window_m: must be >= chunk_m";
    if (max_chunk_poses < 1) return "corrector.max_chunk_poses: must be >= 1";
    if (max_window_poses < max_chunk_poses) return "corrector.max_window_poses: must be >= max_chunk_poses";
    if (!(stationary_m >= 0.0)) return "corrector.stationary_m: must be >= 0";
    return "";
}

// The incremental pass and the refinement live in IncrementalCorrector (shared with the online
// corrector); the batch case hands it the whole estimate at once.
CorrectionResult CorrectTrajectory(const PlanarTrajectory& estimate, const TraversableField* field,
                                   const CorrectorConfig& cfg, const ProgressCallback& progress) {
    assert(estimate.size() >= 3 && "CorrectTrajectory needs at least 3 poses");
    const bool planar = !field || field->planar();
    IncrementalCorrector inc(InitialState(estimate, cfg, planar), field, cfg);
    inc.SolveRemaining(progress);
    return inc.Finish(estimate.t_s, progress);
}

}  // namespace driftcorr
