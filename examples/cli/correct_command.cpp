// `driftcorr correct`: one scenario, one trajectory file with its map given on the command line,
// or many scenarios on a pool of threads. Parsing and printing live here; the work is in the
// pipeline library.
//
// Exit codes: 0 written (verdict ok or degraded), 1 usage error, 2 bad input (file, line, key
// named), 3 verdict failed (nothing written unless --on-failure says so), 4 internal error.
// Several scenarios: 0 when every one was written; otherwise the code of the worst scenario, in
// the order 4, 2, 3.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "driftcorr/core/angles.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/core/metrics.h"
#include "driftcorr/io/geojson_writer.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/mapping/atomic_file.h"
#include "driftcorr/mapping/geodesy.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::cli {
namespace {

const char* kCorrectUsage =
    "usage: driftcorr correct <scenario dir | scenario.yaml> -o <corrected.tum>\n"
    "                         [--config params.yaml] [--geojson tracks.geojson]\n"
    "                         [--covariance poses.txt] [--on-failure refuse|estimate|write]\n"
    "                         [--solver driftcorr|paper] [--quiet]\n"
    "       driftcorr correct <trajectory> --osm <map.osm|map.osm.pbf> -o <corrected.tum>\n"
    "                         --anchor LAT,LON,YAW | --crs EPSG:n --anchor EASTING,NORTHING,YAW\n"
    "                         [--frame enu|kitti_camera] [--format tum|csv|euroc|kitti]\n"
    "                         [--rate-hz R | --times FILE] [--heading orientation|motion]\n"
    "                         [--ground-truth FILE [--ground-truth-times FILE]]\n"
    "                         [options as above]\n"
    "       driftcorr correct <scenario>... [--manifest FILE] -o <folder> [-j N]\n"
    "                         [--geojson <folder>] [--covariance <folder>] [options as above]\n"
    "\n"
    "Corrects the scenario's drifting estimate against its map and writes the corrected\n"
    "trajectory as TUM (t x y z qx qy qz qw: space-separated, no header, the format evo reads)\n"
    "in the estimate's own frame and timestamps; -o - writes it to standard output (the summary\n"
    "then goes to stderr). No output may be one of the run's inputs; a symbolic link is followed\n"
    "and the file it names replaced; a device or FIFO is written in place.\n"
    "--geojson also writes estimate and corrected track (and ground truth) as WGS84 GeoJSON\n"
    "LineStrings; properties.coordinateProperties.times holds each vertex's timestamp [s].\n"
    "--solver paper runs, as a reference, the epoch-wise gradient descent of Navard and Yilmaz,\n"
    "\"A Probabilistic-based Drift Correction Module for Visual Inertial SLAMs\" "
    "(arXiv:2404.10140).\n"
    "--covariance writes per pose: t, the horizontal covariance (East, North) [m^2], the\n"
    "height and heading variances, and the verdict's pose flags.\n"
    "A trajectory without a scenario file: road2d on one OpenStreetMap file (XML or PBF).\n"
    "  --anchor: where the trajectory frame's origin is (WGS84 degrees, or grid metres with\n"
    "  --crs) and its yaw [deg, counter-clockwise from East], or `auto` to estimate the yaw\n"
    "  from the map. --frame (required except for EuRoC) names the axes: enu (x, y horizontal,\n"
    "  z up) or kitti_camera (x right, y down, z forward). --format is taken from the name\n"
    "  (.tum, .csv; a .csv with the EuRoC header is EuRoC) unless given; kitti needs --rate-hz\n"
    "  or --times (one time [s] a line, as KITTI's times.txt).\n"
    "  --ground-truth: the same drive's true poses, in the trajectory's format and frame (and\n"
    "  rate or --ground-truth-times); the summary then gives the errors.\n"
    "  TUM may hold positions only (t x y z); CSV has a header (docs/FORMAT.md).\n"
    "  Without orientations, or with --heading motion, the heading is the direction of motion.\n"
    "Several scenarios (or --manifest, one scenario path a line, or -o naming a folder): -o is\n"
    "a folder that gets <name>.tum per scenario (<name>: the scenario's folder, or its .yaml\n"
    "without extension);\n"
    "-j N corrects N at a time (one process each); one line per scenario; a failing one does not\n"
    "stop the others.\n"
    "Every run ends with a verdict, judged without ground truth: ok, degraded (written, with the\n"
    "reasons) or failed. --on-failure: refuse (default) writes nothing, estimate writes the input\n"
    "unchanged, write writes the result anyway; a failed run exits 3 in every case.\n"
    "Exit codes: 0 ok or degraded, 1 usage, 2 bad input, 3 failed, 4 internal; several\n"
    "scenarios: 0 if all were written, else the worst of 4, 2, 3 (in that order).\n";

struct Args {
    std::vector<std::string> inputs;  ///< scenarios, or one trajectory file with --osm
    std::string manifest, output, config, geojson, covariance;
    std::string solver = "driftcorr";
    std::string on_failure = "refuse";
    std::string jobs = "1";
    /// A trajectory file without a scenario file.
    std::string osm, anchor, crs, scale, frame, format, rate_hz, heading;
    /// With --osm: the ground truth (same format and frame as the trajectory, the summary's
    /// errors) and a kitti file's per-line times (instead of --rate-hz), the ground truth's too.
    std::string ground_truth, times, ground_truth_times;
    bool quiet = false;

    /// Several scenarios, or one with -o naming a folder (an existing one, or a path ending in
    /// '/'): the same command then works whatever number of scenarios a glob matched.
    bool Batch() const {
        std::error_code ec;
        const bool folder =
            !output.empty() && (output.back() == '/' || std::filesystem::is_directory(output, ec));
        return inputs.size() > 1 || !manifest.empty() || (folder && osm.empty());
    }
};

std::string CheckChoices(const Args& a) {
    if (a.solver != "driftcorr" && a.solver != "paper") {
        return "--solver must be driftcorr or paper, not '" + a.solver + "'";
    }
    if (a.on_failure != "refuse" && a.on_failure != "estimate" && a.on_failure != "write") {
        return "--on-failure must be refuse, estimate or write, not '" + a.on_failure + "'";
    }
    const bool jobs_ok = !a.jobs.empty() && a.jobs.size() <= 3 &&
                         a.jobs.find_first_not_of("0123456789") == std::string::npos &&
                         std::stoi(a.jobs) >= 1;
    if (!jobs_ok) return "-j must be a whole number from 1 to 999, not '" + a.jobs + "'";
    if (!a.heading.empty() && a.heading != "orientation" && a.heading != "motion") {
        return "--heading must be orientation or motion, not '" + a.heading + "'";
    }
    return "";
}

std::string CheckModes(const Args& a) {
    const bool file_options = !a.anchor.empty() || !a.crs.empty() || !a.scale.empty() ||
                              !a.frame.empty() || !a.format.empty() || !a.rate_hz.empty() ||
                              !a.heading.empty() || !a.ground_truth.empty() || !a.times.empty() ||
                              !a.ground_truth_times.empty();
    if (a.inputs.empty() && a.manifest.empty()) return "missing scenario";
    if (a.output.empty()) {
        return a.Batch() ? "missing -o <folder>" : "missing -o <corrected.tum>";
    }
    if (a.Batch() && a.output == "-") return "several scenarios need -o <folder>, not -";
    if (a.Batch() && !a.osm.empty()) {
        return "--osm corrects one trajectory file; several scenarios need scenario files";
    }
    if (a.osm.empty() && file_options) {
        return "--anchor, --crs, --scale, --frame, --format, --rate-hz, --times, --heading, "
               "--ground-truth and --ground-truth-times go with --osm (a trajectory without a "
               "scenario file)";
    }
    if (!a.osm.empty() && a.anchor.empty()) return "missing --anchor (with --osm)";
    return "";
}

bool ParseArgs(int argc, char** argv, Args& a, std::string& err) {
    const OptionTable table{{{"--quiet", &a.quiet}, {"-q", &a.quiet}},
                            {{"-o", &a.output},
                             {"--output", &a.output},
                             {"--config", &a.config},
                             {"--geojson", &a.geojson},
                             {"--solver", &a.solver},
                             {"--covariance", &a.covariance},
                             {"--on-failure", &a.on_failure},
                             {"--manifest", &a.manifest},
                             {"-j", &a.jobs},
                             {"--jobs", &a.jobs},
                             {"--osm", &a.osm},
                             {"--anchor", &a.anchor},
                             {"--crs", &a.crs},
                             {"--scale", &a.scale},
                             {"--frame", &a.frame},
                             {"--format", &a.format},
                             {"--rate-hz", &a.rate_hz},
                             {"--heading", &a.heading},
                             {"--ground-truth", &a.ground_truth},
                             {"--times", &a.times},
                             {"--ground-truth-times", &a.ground_truth_times}}};
    auto positional = [&a](const std::string& arg) -> std::string {
        a.inputs.push_back(arg);
        return "";
    };
    if (!ParseOptions(argc, argv, 1, table, positional, err)) return false;
    err = CheckChoices(a);
    if (err.empty()) err = CheckModes(a);
    return err.empty();
}

// Progress on stderr: a rewritten line on a terminal, a line per 20 % otherwise.
ProgressCallback MakeProgress(bool quiet) {
    if (quiet) return {};
    const bool tty = ::isatty(STDERR_FILENO);
    using Clock = std::chrono::steady_clock;
    return [tty, last = -1, said = Clock::now()](const CorrectionProgress& p) mutable {
        if (p.stage == "refining") {  // the final solve: a line every 2 s while it runs
            if (Clock::now() - said < std::chrono::seconds(2)) return;
            said = Clock::now();
            std::fprintf(stderr, "%s[driftcorr] refine      iteration %d%s", tty ? "\r" : "",
                         p.iteration, tty ? "" : "\n");
            return;
        }
        if (p.stage == "incremental") said = Clock::now();
        const int pct = int(100.0 * p.poses_done / std::max<std::size_t>(1, p.poses_total));
        if (tty) {
            std::fprintf(stderr, "\r[driftcorr] %-11s %6zu / %zu poses (%3d %%)", p.stage.c_str(),
                         p.poses_done, p.poses_total, pct);
            if (p.stage == "refine") std::fputc('\n', stderr);
        } else if (pct / 20 != last / 20 || p.stage == "refine") {
            std::fprintf(stderr, "[driftcorr] %s %zu / %zu poses\n", p.stage.c_str(), p.poses_done,
                         p.poses_total);
        }
        last = pct;
    };
}

void PrintMetricsRow(std::FILE* out, const char* label, const ErrorMetrics& m, bool floors) {
    std::fprintf(out,
                 "  %-10s ATE %8.2f m   final %8.2f m   max %8.2f m   p90 %8.2f m   drift %6.2f %%",
                 label, m.ate_m, m.final_m, m.max_m, m.p90_m, m.drift_pct);
    if (floors) std::fprintf(out, "   right floor %5.1f %%", 100.0 * m.floor_accuracy);
    std::fprintf(out, "   vertical %8.2f m\n", m.vertical_rms_m);
}

// Where the solve held the heights (road2d): the estimate's, at bounded grades.
void PrintHeights(std::FILE* out, const CorrectionResult& r) {
    if (r.input_kept) {
        std::fprintf(out, "heights    the input's, unchanged\n");
    } else if (r.grades.stretches == 0) {
        std::fprintf(out,
                     "heights    as estimated, not bounded (model.max_grade 0, or a solver "
                     "without the bound)\n");
    } else if (r.grades.limited == 0) {
        std::fprintf(out,
                     "heights    as estimated: no stretch of the path steeper than the grade "
                     "bound (model.max_grade)\n");
    } else {
        std::fprintf(out,
                     "heights    as estimated, but %zu of %zu stretches of the path steeper than "
                     "the grade bound (model.max_grade): their height change limited to it\n",
                     r.grades.limited, r.grades.stretches);
    }
}

// How the start fits the map: the estimated start, or the given one and the best other heading.
void PrintAnchorFit(std::FILE* out, const pipeline::CorrectionRun& run) {
    using driftcorr::RadToDeg;
    const AnchorFitResult& f = *run.anchor_fit;
    const auto& a = run.scenario.anchor;
    const bool estimated = !a.yaw_deg || a.position_search_m > 0.0;
    std::fprintf(
        out,
        "anchor     %s yaw %.2f deg, start (%.1f, %.1f) m: the first %.0f m lie RMS %.2f m "
        "from the map (%.0f %% beyond reach)",
        estimated ? "estimated" : "given", RadToDeg(run.anchor.yaw_rad), run.anchor.origin_en.x(),
        run.anchor.origin_en.y(), f.lead_path_m, estimated ? f.best.rms_m : f.given.rms_m,
        100.0 * (estimated ? f.best.off_share : f.given.off_share));
    if (!estimated && (f.best.dyaw_rad != 0.0 || f.best.offset_en.norm() > 0.0)) {
        std::fprintf(out, "; best other start %+.1f deg, (%.1f, %.1f) m: RMS %.2f m",
                     RadToDeg(f.best.dyaw_rad), f.best.offset_en.x(), f.best.offset_en.y(),
                     f.best.rms_m);
    }
    if (f.runner_up) {
        std::fprintf(out, "; next distinct start %+.1f deg, (%.1f, %.1f) m: RMS %.2f m",
                     RadToDeg(f.runner_up->dyaw_rad), f.runner_up->offset_en.x(),
                     f.runner_up->offset_en.y(), f.runner_up->rms_m);
    }
    std::fprintf(out, "\n");
}

// The estimate's global scale: given, or found from the map (`scale: auto`) with the candidates
// of the search.
void PrintGlobalScale(std::FILE* out, const pipeline::CorrectionRun& run) {
    const io::AnchorSpec& a = run.scenario.anchor;
    if (!a.scale_auto && run.global_scale == 1.0) return;
    if (!run.scale_fit) {
        std::fprintf(out, "scale      given %.6g: the estimate's positions times it are metres\n",
                     run.global_scale);
        return;
    }
    const ScaleFitResult& f = *run.scale_fit;
    std::fprintf(out, "scale      found %.4f from the map", run.global_scale);
    const pipeline::DriveScale drive = pipeline::DriveScaleOf(run);
    if (std::isfinite(drive.value)) {
        // The drive's scale as corrected: the corrected path over the input's.
        std::fprintf(out, ", %.4f", drive.value);
        if (std::isfinite(drive.sd)) std::fprintf(out, " +- %.4f (1 sigma)", drive.sd);
        std::fprintf(out, " over the drive with the correction's scale walk (%.4f..%.4f)",
                     run.global_scale * run.result.scale_min,
                     run.global_scale * run.result.scale_max);
    }
    std::fprintf(out, "; searched %.4g..%.4g, the leading path's best fits:", f.scales.front(),
                 f.scales.back());
    for (std::size_t k = 0; k < f.candidates.size(); ++k) {
        const ScaleCandidate& c = f.candidates[k];
        std::fprintf(out, "%s %.4f RMS %.2f m", k ? "," : "", c.scale, c.placement.rms_m);
        if (!std::isnan(c.nll)) std::fprintf(out, " NLL %.1f", c.nll);
        if (k == f.kept) std::fprintf(out, " (kept)");
    }
    std::fprintf(out, "\n");
}

// The start scales of the correction, the NLL each reached and how far each one's correction lies
// from the kept one, when there were several.
void PrintStarts(std::FILE* out, const CorrectionResult& r) {
    if (r.start_scales.size() < 2) return;
    std::fprintf(out, "starts     scale");
    for (std::size_t k = 0; k < r.start_scales.size(); ++k) {
        std::fprintf(out, "%s %.2f", k ? " /" : "", r.start_scales[k]);
    }
    std::fprintf(out, ": NLL");
    for (std::size_t k = 0; k < r.start_nll.size(); ++k) {
        if (std::isnan(r.start_nll[k])) {
            std::fprintf(out, "%s failed", k ? " /" : "");
        } else {
            std::fprintf(out, "%s %.1f", k ? " /" : "", r.start_nll[k]);
        }
    }
    std::fprintf(out, ", kept %.2f; RMS to the kept one", r.start_scales[r.start_chosen]);
    for (std::size_t k = 0; k < r.start_rms_m.size(); ++k) {
        if (std::isnan(r.start_rms_m[k])) {
            std::fprintf(out, "%s -", k ? " /" : "");
        } else {
            std::fprintf(out, "%s %.2f", k ? " /" : "", r.start_rms_m[k]);
        }
    }
    std::fprintf(out, " m\n");
}

// One line per floor hypothesis of the batch correction (CorrectionResult::floor_hypotheses).
void PrintFloorHypotheses(std::FILE* out, const CorrectionResult& r) {
    for (const CorrectionResult::FloorHypothesis& h : r.floor_hypotheses) {
        const bool gains = h.gain_nll != 0.0 || h.against_gain_nll != 0.0;
        std::fprintf(out, "floors     the change from %.1f m ending at %.0f s onto %.1f m: NLL ",
                     h.from_m, h.t_s, h.tried_m);
        if (std::isnan(h.nll)) {
            std::fprintf(out, "failed");
        } else {
            std::fprintf(out, "%.1f", h.nll);
            if (gains) std::fprintf(out, " + %.1f of the gains", h.gain_nll);
        }
        std::fprintf(out, " against %.1f", h.against);
        if (gains) std::fprintf(out, " + %.1f", h.against_gain_nll);
        std::fprintf(out, " on %.1f m, %s\n", h.chosen_m, h.kept ? "kept" : "not kept");
    }
}

// The model freedoms decided for this input (CorrectorConfig::decide_heading_bias).
void PrintFreedoms(std::FILE* out, const CorrectionResult& r) {
    const char* label = "freedoms  ";
    if (r.scale_walk) {
        const ScaleWalkDecision& d = *r.scale_walk;
        const char* kept = d.kept == ScaleWalkDecision::Kept::kOneScale ? "left out (one scale)"
                           : d.kept == ScaleWalkDecision::Kept::kRefined
                               ? "kept (one scale's correction refined with it)"
                               : "kept (corrected with it)";
        std::fprintf(out,
                     "%s scale walk %s: NLL + price %.1f + %.1f with one scale, %.1f + %.1f "
                     "refined with the walk, %.1f + %.1f corrected with it\n",
                     label, kept, d.nll_one_scale, d.price_one_scale, d.nll_refined,
                     d.price_refined, d.nll_walk, d.price_walk);
        label = "          ";
    }
    if (r.one_scale_start) {
        const OneScaleStart& d = *r.one_scale_start;
        if (d.from_one_scale) {
            std::fprintf(out,
                         "%s scale walk from one scale: NLL %.1f corrected with it, %.1f with "
                         "one scale, %.1f that refined with the walk\n",
                         label, d.nll_walk, d.nll_one_scale, d.nll_refined);
        } else {
            std::fprintf(out,
                         "%s scale walk as the windows left it: NLL %.1f, with one scale %.1f\n",
                         label, d.nll_walk, d.nll_one_scale);
        }
        label = "          ";
    }
    if (r.step_reading) {
        const StepReadingDecision& d = *r.step_reading;
        std::fprintf(out,
                     "%s step lengths %s: NLL %.1f read about the median (exponent %.2f), "
                     "%.1f as read, price of reading them as read %.1f\n",
                     label, d.as_read ? "as read" : "read about the median", d.nll_about_median,
                     d.exponent, d.nll_as_read, d.price);
        label = "          ";
    }
    if (!r.heading_bias) return;
    std::fprintf(out,
                 "%s heading-rate bias %s: NLL %.1f with it, %.1f without, price of its "
                 "unknowns %.1f\n",
                 label, r.heading_bias->kept ? "kept" : "left out", r.heading_bias->nll_with,
                 r.heading_bias->nll_without, r.heading_bias->price);
}

// How the input lies in the correction's uncertainty, and whether it was kept.
void PrintAgreement(std::FILE* out, const CorrectionResult& r) {
    if (std::isnan(r.input_nll)) return;
    const char* label = "input     ";
    if (r.agreement_poses > 0) {
        const double share = double(r.agreement_inside) / double(r.agreement_poses);
        const bool agrees = share >= r.agreement_threshold;
        std::fprintf(out,
                     "%s inside the correction's 95 %% region at %.1f %% of %zu poses (%s %.1f "
                     "%%)%s\n",
                     label, 100.0 * share, r.agreement_poses, agrees ? "at least" : "below",
                     100.0 * r.agreement_threshold,
                     agrees && r.input_kept ? ": the map cannot tell it wrong" : "");
        label = "          ";
    }
    std::fprintf(out, "%s NLL %.1f, the correction's %.1f%s: %s\n", label, r.input_nll, r.nll,
                 r.input_nll_lower ? " (the input explains the data better)" : "",
                 r.input_kept ? "written unchanged" : "corrected");
}

void PrintVerdict(std::FILE* out, const Verdict& v) {
    std::fprintf(out, "verdict    %s", ToString(v.level).c_str());
    std::fprintf(
        out, " (corrected / estimated path %.2f..%.2f, %zu input jump(s), %.0f %% off the map)\n",
        v.scale_min, v.scale_max, v.input_jumps, 100.0 * v.off_map_share);
    for (const std::string& r : v.reasons) std::fprintf(out, "  %s\n", r.c_str());
}

void PrintHeading(std::FILE* out, const pipeline::CorrectionRun& run) {
    if (!run.heading_from_motion) return;
    std::fprintf(out, "heading    from the direction of motion (%s)\n",
                 run.estimate_frame.HasOrientation()
                     ? "heading: motion; the orientations are turned by the heading correction"
                     : "the estimate has no orientation; each written orientation is the corrected "
                       "heading alone, no roll or pitch");
}

// The process's peak resident memory so far [MB] (Linux reports ru_maxrss in KiB).
double PeakMemoryMb() {
    rusage usage{};
    if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
    return double(usage.ru_maxrss) / 1024.0;
}

void PrintSummary(std::FILE* out, const pipeline::CorrectionRun& run, const std::string& written,
                  pipeline::Solver solver) {
    const auto& r = run.result;
    const bool indoor = run.scenario.mode == io::ScenarioMode::kIndoor3d;
    const double total = run.timings.load_s + run.timings.map_s + run.timings.solve_s;
    std::fprintf(out, "scenario   %s (%s), %zu poses\n", run.scenario.name.c_str(),
                 io::ToString(run.scenario.mode).c_str(), run.estimate.size());
    PrintHeading(out, run);
    std::fprintf(out,
                 indoor ? "map        %zu walkways on the walk's floor, %.1f km, field %zu cells\n"
                        : "map        %zu roads, %.1f km, field %zu cells\n",
                 run.network.roads.size(), run.network.TotalLengthM() / 1000.0, run.map_grid_cells);
    if (solver == pipeline::Solver::kPaper) {
        std::fprintf(out, "solver     paper: %s (%s)\n", ToString(r.status).c_str(),
                     r.message.c_str());
    } else {
        std::fprintf(
            out,
            "solver     %s (%s); %zu windows, %d solver iterations, %zu poses on hard corridor,"
            " scale %.3f..%.3f\n",
            ToString(r.status).c_str(), r.message.c_str(), r.windows, r.iterations,
            r.constrained_poses, r.scale_min, r.scale_max);
        PrintStarts(out, r);
        PrintFreedoms(out, r);
        PrintFloorHypotheses(out, r);
    }
    std::fprintf(out,
                 "time       %.3f s (load %.3f, map %.3f, correction %.3f = %.0f poses/s:"
                 " incremental %.3f, refine %.3f); peak memory %.0f MB\n",
                 total, run.timings.load_s, run.timings.map_s, run.timings.solve_s,
                 run.estimate.size() / std::max(1e-9, run.timings.solve_s), r.incremental_s,
                 r.refine_s, PeakMemoryMb());
    PrintGlobalScale(out, run);
    if (!indoor && Usable(r.status)) PrintHeights(out, r);
    if (run.anchor_fit) PrintAnchorFit(out, run);
    PrintAgreement(out, r);
    if (run.before) {
        std::fprintf(out,
                     "errors     against the ground truth, no re-alignment: ATE to drift "
                     "horizontal (East, North), vertical the height's RMS error:\n");
        PrintMetricsRow(out, "estimate", *run.before, indoor);
    }
    if (run.after) PrintMetricsRow(out, "corrected", *run.after, indoor);
    PrintVerdict(out, run.verdict);
    if (!written.empty())
        std::fprintf(out, "wrote      %s\n", written == "-" ? "standard output" : written.c_str());
}

std::vector<GeoPoint> ToGeo(const pipeline::WorldFrame& w, const driftcorr::PlanarTrajectory& t) {
    std::vector<GeoPoint> out;
    for (const auto& p : t.p_en) out.push_back(w.ToGeo(p));
    return out;
}

// Per pose: t, covariance East-North [m^2], height and heading variance, the verdict's flags.
void WriteCovariance(const std::string& path, const pipeline::CorrectionRun& run) {
    const auto& cov = run.result.covariance;
    if (cov.status != CovarianceStatus::kOk) {
        throw std::runtime_error(path + ": no covariance: " + cov.message);
    }
    AtomicFile file(path);
    std::ostream& out = file.stream();
    out << "# t var_e_m2 cov_en_m2 var_n_m2 var_up_m2 var_yaw_rad2 flags"
           " (flags: 1 off the map, 2 input jump, 4 implausible scale, 8 height change denied,"
           " 16 floor not determined, 32 turn the estimate does not make)\n";
    char line[256];
    for (std::size_t i = 0; i < cov.poses.size(); ++i) {
        const auto& c = cov.poses[i];
        std::snprintf(line, sizeof(line), "%.6f %.6g %.6g %.6g %.6g %.6g %u\n",
                      run.result.corrected.t_s[i], c.xy_m2(0, 0), c.xy_m2(0, 1), c.xy_m2(1, 1),
                      c.z_m2, c.yaw_rad2, unsigned(run.verdict.pose_flags[i]));
        out << line;
    }
    file.Commit();
}

std::string JsonArray(const std::vector<std::string>& items) {
    std::string s = "[";
    for (std::size_t i = 0; i < items.size(); ++i) s += (i ? "," : "") + items[i];
    return s + "]";
}

// The corrected track's properties: verdict, reasons, per-vertex 1-sigma East/North and flags.
std::vector<std::pair<std::string, std::string>> CorrectedProperties(
    const pipeline::CorrectionRun& run) {
    std::vector<std::string> reasons, sigma_e, sigma_n, flags;
    for (const auto& r : run.verdict.reasons) reasons.push_back(io::JsonString(r));
    char buf[32];
    for (std::size_t i = 0; i < run.verdict.pose_flags.size(); ++i) {
        flags.push_back(std::to_string(run.verdict.pose_flags[i]));
    }
    for (const auto& c : run.result.covariance.poses) {
        std::snprintf(buf, sizeof(buf), "%.3f", std::sqrt(std::max(0.0, c.xy_m2(0, 0))));
        sigma_e.push_back(buf);
        std::snprintf(buf, sizeof(buf), "%.3f", std::sqrt(std::max(0.0, c.xy_m2(1, 1))));
        sigma_n.push_back(buf);
    }
    std::vector<std::pair<std::string, std::string>> p = {
        {"verdict", io::JsonString(ToString(run.verdict.level))},
        {"verdict_reasons", JsonArray(reasons)},
        {"pose_flags", JsonArray(flags)}};
    if (!sigma_e.empty()) {
        p.push_back({"sigma_east_m", JsonArray(sigma_e)});
        p.push_back({"sigma_north_m", JsonArray(sigma_n)});
    }
    return p;
}

// ---- a trajectory file without a scenario file ----------------------------------------------

double AnchorNumber(const std::string& text, const char* what) {
    const std::optional<double> value = ParseFiniteNumber(text);
    if (!value) {
        throw InputError("", 0, "--anchor", std::string(what) + " '" + text + "' is not a number");
    }
    return *value;
}

/// --anchor A,B,YAW (A,B: lat,lon in degrees, or easting,northing in metres with --crs).
io::AnchorSpec ParseAnchorOption(const Args& a) {
    std::vector<std::string> parts;
    std::size_t pos = 0;
    for (std::size_t comma; (comma = a.anchor.find(',', pos)) != std::string::npos;
         pos = comma + 1) {
        parts.push_back(a.anchor.substr(pos, comma - pos));
    }
    parts.push_back(a.anchor.substr(pos));
    const bool grid = !a.crs.empty();
    if (parts.size() != 3) {
        throw InputError("", 0, "--anchor",
                         grid ? "expected EASTING,NORTHING,YAW (metres, degrees or auto)"
                              : "expected LAT,LON,YAW (degrees, the yaw may be auto)");
    }
    io::AnchorSpec anchor;
    if (grid) {
        anchor.crs = a.crs;
        anchor.easting_m = AnchorNumber(parts[0], "easting");
        anchor.northing_m = AnchorNumber(parts[1], "northing");
    } else {
        anchor.lat_deg = AnchorNumber(parts[0], "latitude");
        anchor.lon_deg = AnchorNumber(parts[1], "longitude");
    }
    if (const std::optional<io::AnchorProblem> problem = io::FindAnchorProblem(anchor)) {
        const bool crs = problem->key == "crs";
        const std::string what = problem->key == "lat_deg"   ? "the latitude "
                                 : problem->key == "lon_deg" ? "the longitude "
                                                             : "";
        throw InputError("", 0, crs ? "--crs" : "--anchor", what + problem->rule);
    }
    if (parts[2] != "auto") anchor.yaw_deg = AnchorNumber(parts[2], "yaw");
    if (!a.scale.empty()) {
        const std::string problem = io::ParseAnchorScale(a.scale, anchor);
        if (!problem.empty()) throw InputError("", 0, "--scale", problem);
    }
    return anchor;
}

/// The trajectory's format: --format, else what its name (and a CSV's header) says.
/// The trajectory source of `path` from the file options; `times`: its kitti times file.
io::TrajectorySource SourceFromOptions(const Args& a, const std::string& path,
                                       const std::string& times, const char* times_flag) {
    io::TrajectorySource src;
    src.path = path;
    std::optional<io::TrajectoryFormat> format;
    if (!a.format.empty()) {
        format = io::ParseTrajectoryFormat(a.format);
        if (!format) {
            throw InputError(
                "", 0, "--format",
                "unknown format '" + a.format + "' (expected tum | csv | euroc | kitti)");
        }
    } else {
        format = io::DetectTrajectoryFormat(src.path);
        if (!format) {
            throw InputError(src.path, 0, "--format",
                             "the name does not tell the format (.tum, .csv): give --format "
                             "tum | csv | euroc | kitti");
        }
    }
    src.format = *format;
    if (!a.rate_hz.empty()) {
        if (src.format != io::TrajectoryFormat::kKitti) {
            throw InputError("", 0, "--rate-hz", "only with --format kitti");
        }
        src.rate_hz = AnchorNumber(a.rate_hz, "rate");
    }
    if (!times.empty()) {
        if (src.format != io::TrajectoryFormat::kKitti) {
            throw InputError("", 0, times_flag, "only with --format kitti");
        }
        if (src.rate_hz) {
            throw InputError("", 0, times_flag, "give --rate-hz or the times, not both");
        }
        src.times_path = times;
    }
    if (src.format == io::TrajectoryFormat::kKitti && !src.rate_hz && !src.times_path) {
        throw InputError(src.path, 0, "--rate-hz",
                         std::string("a kitti trajectory needs --rate-hz or ") + times_flag);
    }
    src.heading_from_motion = a.heading == "motion";
    return src;
}

io::Scenario ScenarioFromOptions(const Args& a) {
    io::Scenario s;
    s.yaml_path = "<command line>";
    s.dir = std::filesystem::current_path().string();
    s.name = std::filesystem::path(a.inputs.front()).stem().string();
    s.mode = io::ScenarioMode::kRoad2d;
    s.estimate = SourceFromOptions(a, a.inputs.front(), a.times, "--times");
    if (!a.ground_truth.empty()) {
        s.ground_truth =
            SourceFromOptions(a, a.ground_truth, a.ground_truth_times, "--ground-truth-times");
    } else if (!a.ground_truth_times.empty()) {
        throw InputError("", 0, "--ground-truth-times", "only with --ground-truth");
    }
    if (!a.frame.empty()) {
        const std::optional<FrameAxes> axes = ParseFrameAxes(a.frame);
        if (!axes) {
            throw InputError("", 0, "--frame",
                             "unknown frame '" + a.frame + "' (expected enu | kitti_camera)");
        }
        s.frame = *axes;
    } else if (s.estimate.format == io::TrajectoryFormat::kEuroc) {
        s.frame = FrameAxes::kEnu;  // EuRoC / ASL: R is the gravity-aligned world frame, z up
    } else {
        throw InputError(s.estimate.path, 0, "--frame",
                         "missing: the axes of the trajectory's frame (enu: x, y horizontal, z up; "
                         "kitti_camera: x right, y down, z forward)");
    }
    s.anchor = ParseAnchorOption(a);
    s.map.push_back({a.osm, io::MapFormat::kOsm, io::LayerRole::kNone, std::nullopt, {}});
    return s;
}

// ---- one correction -------------------------------------------------------------------------

struct OutputPaths {
    std::string tum, geojson, covariance;  ///< empty: not written
};

/// Every output checked before any work: creatable, not an input of the run, not each other.
void CheckOutputs(const OutputPaths& out, const Args& a, const io::Scenario& scenario) {
    CheckOutputPath(out.tum, "-o");
    if (!out.covariance.empty()) CheckOutputPath(out.covariance, "--covariance");
    if (!out.geojson.empty()) CheckOutputPath(out.geojson, "--geojson");
    std::vector<io::InputFile> inputs = io::InputFiles(scenario);
    if (!a.config.empty()) inputs.push_back({"the --config file", a.config});
    if (!a.manifest.empty()) inputs.push_back({"the --manifest file", a.manifest});
    CheckOutputsAgainstInputs(
        {{"-o", out.tum}, {"--geojson", out.geojson}, {"--covariance", out.covariance}}, inputs);
}

/// Per-vertex timestamps [s] as GeoJSON's coordinateProperties (the togeojson convention).
std::pair<std::string, std::string> TimesProperty(const std::vector<double>& t_s) {
    std::string json = "{\"times\":[";
    char buf[32];
    for (std::size_t i = 0; i < t_s.size(); ++i) {
        std::snprintf(buf, sizeof(buf), "%s%.6f", i ? "," : "", t_s[i]);
        json += buf;
    }
    return {"coordinateProperties", json + "]}"};
}

void WriteGeoJson(const std::string& path, const pipeline::CorrectionRun& run, bool with_result) {
    pipeline::WorldFrame world(run.scenario.anchor);
    std::vector<io::GeoTrack> tracks = {
        {"estimate", ToGeo(world, run.estimate), {TimesProperty(run.estimate.t_s)}}};
    if (with_result) {
        tracks.push_back(
            {"corrected", ToGeo(world, run.result.corrected), CorrectedProperties(run)});
        tracks.back().json_properties.push_back(TimesProperty(run.result.corrected.t_s));
    } else {
        tracks.front().json_properties.push_back(
            {"verdict", io::JsonString(ToString(run.verdict.level))});
    }
    if (run.ground_truth) {
        tracks.push_back({"ground_truth",
                          ToGeo(world, *run.ground_truth),
                          {TimesProperty(run.ground_truth->t_s)}});
    }
    io::WriteGeoJsonTracks(path, tracks);
}

/// What a finished correction wrote.
enum class Written { kNothing, kResult, kEstimate };

/// Writes what the verdict and --on-failure allow: the side outputs first, so that if one fails
/// the corrected trajectory (the main output) is not written (each file itself is written to a
/// temporary and renamed when complete).
Written WriteOutputs(const pipeline::CorrectionRun& run, const std::string& on_failure,
                     const OutputPaths& out) {
    const bool failed = run.verdict.level == VerdictLevel::kFailed;
    const bool write_result = Usable(run.result.status) && (!failed || on_failure == "write");
    const bool write_estimate = failed && !write_result && on_failure == "estimate";
    if (!write_result && !write_estimate) return Written::kNothing;
    if (!out.covariance.empty() && write_result) WriteCovariance(out.covariance, run);
    if (!out.geojson.empty()) WriteGeoJson(out.geojson, run, write_result);
    io::WriteTum(out.tum, write_result ? run.corrected_frame : run.estimate_frame);
    return write_result ? Written::kResult : Written::kEstimate;
}

pipeline::PipelineConfig LoadConfig(const Args& a) {
    pipeline::PipelineConfig cfg;
    if (!a.config.empty()) cfg = pipeline::LoadPipelineConfig(a.config);
    cfg.solver = a.solver == "paper" ? pipeline::Solver::kPaper : pipeline::Solver::kDriftcorr;
    return cfg;
}

/// A finding's advice in the terms the user gave: with --osm the anchor is a flag, not a
/// scenario key.
std::string InFlagTerms(std::string text, const Args& a) {
    if (a.osm.empty()) return text;
    const std::string place = a.crs.empty() ? "LAT,LON" : "EASTING,NORTHING";
    const std::pair<std::string, std::string> terms[] = {
        {"anchor.yaw_deg and the position", "the yaw and the position of --anchor"},
        {"anchor.yaw_deg", "the yaw of --anchor"},
        {"yaw_deg: auto", "--anchor " + place + ",auto"},
        {"anchor.scale: auto", "--scale auto"},
        {"`scale: auto` in the anchor", "--scale auto"},
    };
    for (const auto& [from, to] : terms) {
        for (std::size_t at = text.find(from); at != std::string::npos;
             at = text.find(from, at + to.size())) {
            text.replace(at, from.size(), to);
        }
    }
    return text;
}

int RunSingle(const Args& a) {
    const OutputPaths out{a.output, a.geojson, a.covariance};
    io::Scenario scenario =
        a.osm.empty() ? io::LoadScenario(a.inputs.front()) : ScenarioFromOptions(a);
    CheckOutputs(out, a, scenario);
    const pipeline::PipelineConfig cfg = LoadConfig(a);
    pipeline::CorrectionRun run =
        pipeline::RunCorrection(std::move(scenario), cfg, MakeProgress(a.quiet));
    for (std::string& reason : run.verdict.reasons) reason = InFlagTerms(reason, a);
    for (const std::string& w : run.scenario.warnings)
        std::fprintf(stderr, "driftcorr: warning: %s\n", w.c_str());
    for (const std::string& w : run.result.warnings)
        std::fprintf(stderr, "driftcorr: warning: %s\n", w.c_str());
    const Written written = WriteOutputs(run, a.on_failure, out);
    // With -o - (or /dev/stdout) the trajectory has standard output; the summary goes to stderr.
    std::FILE* report =
        ResolveOutput(a.output).kind == OutputTarget::Kind::kDescriptor && a.output != "/dev/stderr"
            ? stderr
            : stdout;
    PrintSummary(report, run, written == Written::kNothing ? "" : a.output, cfg.solver);
    const bool failed = run.verdict.level == VerdictLevel::kFailed;
    if (written == Written::kNothing) {
        std::fprintf(stderr, "driftcorr: the correction failed (%s); nothing written\n",
                     run.verdict.reasons.empty() ? run.result.message.c_str()
                                                 : run.verdict.reasons.front().c_str());
        return kExitSolver;
    }
    if (written == Written::kEstimate) {
        std::fprintf(stderr, "driftcorr: the correction failed; wrote the estimate unchanged\n");
    }
    return failed ? kExitSolver : kExitOk;
}

// ---- several scenarios ----------------------------------------------------------------------

struct BatchItem {
    std::string path;
    std::string where;  ///< "manifest:line" or "argument 2"
    std::string name;   ///< output file stem
};

/// The output stem of a scenario path: its folder's name, or the .yaml's stem (a .yaml named
/// scenario.yaml: its folder's name).
std::string OutputStem(const std::string& path) {
    namespace fs = std::filesystem;
    const fs::path p = fs::path(path).lexically_normal();
    const fs::path leaf = p.filename().empty() ? p.parent_path() : p;
    const std::string ext = leaf.extension().string();
    const bool yaml = ext == ".yaml" || ext == ".yml";
    if (yaml && leaf.stem() != "scenario") return leaf.stem().string();
    const fs::path folder = yaml ? fs::absolute(leaf).parent_path() : fs::absolute(leaf);
    return folder.lexically_normal().filename().string();
}

std::vector<BatchItem> BatchItems(const Args& a) {
    std::vector<BatchItem> items;
    for (std::size_t i = 0; i < a.inputs.size(); ++i) {
        items.push_back({a.inputs[i], "argument " + std::to_string(i + 1), ""});
    }
    if (!a.manifest.empty()) {
        for (const ManifestEntry& e : ReadManifest(a.manifest))
            items.push_back({e.path, e.where, ""});
    }
    std::map<std::string, std::string> seen;
    for (BatchItem& item : items) {
        item.name = OutputStem(item.path);
        const auto [it, fresh] = seen.emplace(item.name, item.where);
        if (!fresh) {
            throw InputError(item.path, 0, item.where,
                             "its output would be " + item.name + ".tum, as for " + it->second +
                                 ": give the scenarios distinct folder names");
        }
    }
    return items;
}

void PrepareFolder(const std::string& dir, const char* option) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (!std::filesystem::is_directory(dir, ec)) {
        throw InputError(dir, 0, option, "is not a folder and cannot be created");
    }
    if (::access(dir.c_str(), W_OK) != 0)
        throw InputError(dir, 0, option, "folder is not writable");
}

/// The files one scenario of a batch writes: <name>.tum, .geojson, .cov.txt in their folders.
OutputPaths BatchOutputs(const Args& a, const BatchItem& item) {
    const auto join = [](const std::string& dir, const std::string& file) {
        return dir.empty() ? std::string() : (std::filesystem::path(dir) / file).string();
    };
    return {join(a.output, item.name + ".tum"), join(a.geojson, item.name + ".geojson"),
            join(a.covariance, item.name + ".cov.txt")};
}

/// Before any work: no scenario's output may be another scenario's input, or one scenario's
/// correction would replace what a later one reads. (A scenario's outputs against its own inputs
/// are checked when it runs, CheckOutputs.) A scenario.yaml that cannot be read is left to its
/// own run to report.
void CheckBatchOutputsAgainstInputs(const Args& a, const std::vector<BatchItem>& items) {
    std::vector<std::vector<NamedOutput>> outputs;
    std::vector<std::vector<io::InputFile>> inputs(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) {
        const OutputPaths out = BatchOutputs(a, items[i]);
        outputs.push_back(
            {{"-o", out.tum}, {"--geojson", out.geojson}, {"--covariance", out.covariance}});
        try {
            inputs[i] = io::InputFiles(io::LoadScenario(items[i].path));
        } catch (const InputError&) {
        }
        for (io::InputFile& in : inputs[i])
            in.what += " of " + items[i].where + " (" + items[i].name + ")";
    }
    CheckOutputsAgainstOtherRunsInputs(outputs, inputs);
}

/// One scenario of a batch: its exit code and the lines to print for it.
ProcessOutcome CorrectOneOfMany(const Args& a, const pipeline::PipelineConfig& cfg,
                                const BatchItem& item) {
    const auto t0 = std::chrono::steady_clock::now();
    const OutputPaths out = BatchOutputs(a, item);
    ProcessOutcome o;
    try {
        io::Scenario scenario = io::LoadScenario(item.path);
        CheckOutputs(out, a, scenario);
        const pipeline::CorrectionRun run = pipeline::RunCorrection(std::move(scenario), cfg);
        const Written written = WriteOutputs(run, a.on_failure, out);
        const bool failed = run.verdict.level == VerdictLevel::kFailed;
        o.code = failed || written == Written::kNothing ? kExitSolver : kExitOk;
        const double s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        o.text =
            Format("%-32s %-8s %6zu poses %7.1f s%s  %s\n", item.name.c_str(),
                   ToString(run.verdict.level).c_str(), run.estimate.size(), s,
                   run.heading_from_motion ? "  heading from motion" : "",
                   written == Written::kNothing    ? "nothing written"
                   : written == Written::kEstimate ? ("estimate unchanged -> " + out.tum).c_str()
                                                   : ("-> " + out.tum).c_str());
        for (const std::string& r : run.verdict.reasons) o.text += "    " + r + "\n";
        for (const std::string& w : run.scenario.warnings) o.text += "    warning: " + w + "\n";
        for (const std::string& w : run.result.warnings) o.text += "    warning: " + w + "\n";
    } catch (const InputError& e) {
        o.code = kExitBadInput;
        o.text =
            Format("%-32s bad input (%s): %s\n", item.name.c_str(), item.where.c_str(), e.what());
    } catch (const std::exception& e) {
        o.code = kExitInternal;
        o.text = Format("%-32s internal error (%s): %s\n", item.name.c_str(), item.where.c_str(),
                        e.what());
    }
    return o;
}

/// 4 before 2 before 3 before 0.
int WorstCode(int a, int b) {
    const auto rank = [](int code) {
        return code == kExitInternal ? 3 : code == kExitBadInput ? 2 : code == kExitSolver ? 1 : 0;
    };
    return rank(b) > rank(a) ? b : a;
}

int RunBatch(const Args& a) {
    const std::vector<BatchItem> items = BatchItems(a);
    PrepareFolder(a.output, "-o");
    if (!a.geojson.empty()) PrepareFolder(a.geojson, "--geojson");
    if (!a.covariance.empty()) PrepareFolder(a.covariance, "--covariance");
    CheckBatchOutputsAgainstInputs(a, items);
    const pipeline::PipelineConfig cfg = LoadConfig(a);
    const int jobs = std::stoi(a.jobs);
    std::vector<int> codes(items.size(), kExitOk);
    std::size_t done = 0;
    const auto t0 = std::chrono::steady_clock::now();
    RunInProcesses(
        items.size(), jobs, [&](std::size_t i) { return CorrectOneOfMany(a, cfg, items[i]); },
        [&](std::size_t i, const ProcessOutcome& o) {
            codes[i] = o.code < 0 ? kExitInternal : o.code;
            std::printf("[%zu/%zu] %s", ++done, items.size(),
                        o.code < 0 ? (items[i].name + " internal error\n" + o.text).c_str()
                                   : o.text.c_str());
            std::fflush(stdout);
        });
    int worst = kExitOk;
    std::size_t written = 0;
    for (const int c : codes) {
        worst = WorstCode(worst, c);
        written += c == kExitOk;
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%zu of %zu scenarios corrected and written in %.1f s (-j %d)\n", written,
                items.size(), s, jobs);
    if (worst != kExitOk) {
        std::fprintf(stderr, "driftcorr: %zu of %zu scenarios failed (see above)\n",
                     items.size() - written, items.size());
    }
    return worst;
}

}  // namespace

int RunCorrectCommand(int argc, char** argv) {
    Args args;
    std::string err;
    if (!ParseArgs(argc, argv, args, err)) {
        if (!err.empty()) std::fprintf(stderr, "driftcorr: %s\n\n", err.c_str());
        std::fputs(kCorrectUsage, err.empty() ? stdout : stderr);
        return err.empty() ? kExitOk : kExitUsage;
    }
    return RunReportingErrors("driftcorr",
                              [&] { return args.Batch() ? RunBatch(args) : RunSingle(args); });
}

void PrintCorrectUsage(std::FILE* out) { std::fputs(kCorrectUsage, out); }

}  // namespace driftcorr::cli
