#pragma once
// The batch corrector: processes the trajectory incrementally (extend by a chunk, initialise the
// new poses by composing odometry onto the corrected end, re-solve a trailing window), then
// refines the whole trajectory in one solve. No I/O: progress goes through a callback, the outcome
// into CorrectionResult.
#include <functional>
#include <vector>

#include "driftcorr/core/types.h"
#include "driftcorr/mapping/traversable_field.h"
#include "driftcorr/optim/correction_result.h"
#include "driftcorr/optim/corrector_config.h"

namespace driftcorr {

class IncrementalCorrector;  // optim/incremental_corrector.h
struct TrajectoryState;      // optim/window_problem.h

/// Fills result.warnings from the estimate, the field and the outcome (see CorrectionResult).
void DiagnoseCorrection(const PlanarTrajectory& estimate, const TraversableField* field,
                        const CorrectorConfig& config, CorrectionResult& result);

/// Do no harm, after a correction of `estimate` (CorrectorConfig::keep_agreeing_input): the input
/// is scored by the correction's objective and by the correction's 95 % region, and is the result
/// where the map cannot tell it wrong or where it explains the data better
/// (CorrectionResult::input_kept, agreement_*, input_nll). CorrectTrajectory calls it; so does a
/// caller of CorrectFromStarts whose result stands for the batch's (the online corrector's Finish).
void KeepAgreeingInput(const PlanarTrajectory& estimate, const TraversableField* field,
                       const CorrectorConfig& config, CorrectionResult& result);

/// Corrects `estimate` (world ENU plane, >= 3 poses) against `field` (may be null: odometry
/// only). Pose 0 is the known initial position and heading and stays fixed. The whole correction
/// runs from each of config.start_scales, and the usable one of lowest NLL is kept
/// (CorrectionResult::start_scales, start_nll, start_chosen). In 3D with floors known, it then
/// runs again on the other floors a floor change of the estimate can reach, and keeps one whose
/// NLL, plus that of its floor changes' gains (config.floor_gain_sigma), is lower by more than
/// config.floor_hypothesis_margin (CorrectionResult::floor_hypotheses).
/// The covariance is the kept correction's.
CorrectionResult CorrectTrajectory(const PlanarTrajectory& estimate, const TraversableField* field,
                                   const CorrectorConfig& config,
                                   const ProgressCallback& progress = {});

/// CorrectTrajectory without the input's test (KeepAgreeingInput) and the warnings
/// (DiagnoseCorrection), for callers that need the kept start's state as well (its incremental
/// corrector, returned; the outcome into `result`).
IncrementalCorrector CorrectFromStarts(const PlanarTrajectory& estimate,
                                       const TraversableField* field, const CorrectorConfig& config,
                                       CorrectionResult& result,
                                       const ProgressCallback& progress = {});
/// The same from an initial state (BatchState: observations and poses, pose 0 the start) with
/// one time stamp per pose, for callers that built the observations themselves (the online
/// corrector's Finish).
IncrementalCorrector CorrectFromStarts(TrajectoryState initial, const std::vector<double>& t_s,
                                       const TraversableField* field, const CorrectorConfig& config,
                                       CorrectionResult& result,
                                       const ProgressCallback& progress = {});

/// CorrectFromStarts of `initial(config)` with the reading of the step lengths decided
/// (CorrectorConfig::decide_step_reading, with a step_length_exponent below 1; else that alone):
/// `initial` builds the initial state under a configuration, whose step_length_exponent reads
/// the step lengths; the corrections with the configured reading and with the step lengths as
/// read both run, and the one of lower NLL plus step-term normalisation is kept and returned
/// (CorrectionResult::step_reading). CorrectTrajectory and the online corrector's Finish use it.
IncrementalCorrector CorrectWithStepReading(
    const std::function<TrajectoryState(const CorrectorConfig&)>& initial,
    const std::vector<double>& t_s, const TraversableField* field, const CorrectorConfig& config,
    CorrectionResult& result, const ProgressCallback& progress = {});

}  // namespace driftcorr
