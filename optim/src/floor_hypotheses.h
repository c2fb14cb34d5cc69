#pragma once
// The floor hypotheses of a multi-floor walk (3D, the floors known): after the kept correction,
// each other floor that a floor change of the estimate can reach is tried as a whole correction
// of its own (docs/method.md, "Indoors: start scales and floor hypotheses").
#include <vector>

#include "whole_corrections.h"

namespace driftcorr {

/// Whether the batch correction re-runs itself on other floors after the estimate's floor changes
/// (CorrectorConfig::restart_height_gains): heights free, and the floors known.
bool FloorHypotheses(const TraversableField* field, bool fix_height, const CorrectorConfig& cfg);

/// After every floor change of the estimate (a change of restart_height_change_m or more between
/// two level runs), each other floor that the change reaches when read with a gain within the
/// range of restart_height_gains is tried: the whole correction again (`run`, from
/// `start_scale`), with that change's steps read to land on that floor (the windows do not
/// re-read them), refined and scored against the observations as they are (`observed`), plus the
/// NLL of its floor changes' gains (the kept correction scored alike). One whose score is lower
/// by more than floor_hypothesis_margin replaces `kept`, and later changes are read from there.
/// Returns every floor tried. Precondition: FloorHypotheses holds and kept.result is usable.
std::vector<CorrectionResult::FloorHypothesis> TryOtherFloors(
    const TrajectoryState& observed, double start_scale, const std::vector<double>& t_s,
    const TraversableField& field, const CorrectorConfig& cfg, WholeCorrections& run,
    KeptCorrection& kept);

}  // namespace driftcorr
