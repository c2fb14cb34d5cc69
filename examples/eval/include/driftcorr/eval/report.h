#pragma once
// The report of `driftcorr eval`: a console table in the form of the paper's Table 1 (one row per
// scenario, columns per method), summary.md, results.json and two hand-written SVG plots per
// scenario (the map with every track, the error against distance travelled), each also as PNG.
#include <string>
#include <vector>

#include "driftcorr/eval/evaluation.h"

namespace driftcorr::eval {

/// Plain-text table for the terminal: per scenario and method ATE / final [m] (or the mean map
/// distance without ground truth), solver time [s] and poses/s; failures with their message.
std::string FormatTable(const std::vector<ScenarioEvaluation>& evals);

/// Markdown: the table (columns per method: ATE / final / max / p90 / drift / time / poses/s),
/// scenarios without ground truth marked, failures with their message, speed ratio paper vs
/// driftcorr, and links to the plots.
std::string SummaryMarkdown(const std::vector<ScenarioEvaluation>& evals);

/// Every number of the run as JSON (hand-written; non-finite numbers become null).
std::string ResultsJson(const std::vector<ScenarioEvaluation>& evals);

/// The map around the drive: roads (the scenario's OSM layers, drawn at their half-width), ground
/// truth black, estimate red, paper orange, driftcorr blue; legend, scale bar [m], north up,
/// equal aspect. Precondition: ev.ok().
std::string MapSvg(const ScenarioEvaluation& ev);

/// Horizontal error [m] against distance travelled along the ground truth [m], one line per
/// method, axes with ticks and labels. Precondition: ev.ok() && ev.has_ground_truth.
std::string ErrorSvg(const ScenarioEvaluation& ev);

/// The SVG plot rendered as a PNG image at its own size in pixels (librsvg onto cairo): the
/// file's bytes. Throws std::runtime_error with librsvg's or cairo's reason when it cannot.
std::string SvgToPng(const std::string& svg);

/// Writes report_dir/summary.md, results.json, <label>_map.svg for every evaluated scenario and
/// <label>_error.svg for those with ground truth, each plot also as .png (SvgToPng). Creates
/// report_dir (and parents); each file is written to a temporary and renamed when complete. Returns
/// the paths written. Throws std::runtime_error naming the path when a file cannot be written.
std::vector<std::string> WriteReport(const std::string& report_dir,
                                     const std::vector<ScenarioEvaluation>& evals);

/// Paper solver time / driftcorr solver time summed over the scenarios where both ran (> 1: the
/// paper's method is slower); 0 when there is no such scenario.
double SpeedRatioPaperOverDriftcorr(const std::vector<ScenarioEvaluation>& evals);

}  // namespace driftcorr::eval
