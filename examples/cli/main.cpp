// driftcorr command-line tool. Parsing and printing live here; the work is in the library.
//
// Exit codes: 0 success, 1 usage error, 2 bad input (file, line, key named), 3 the solver did not
// produce a usable correction (nothing written), 4 internal error.
#include <unistd.h>

#include <cstdio>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"
#include "driftcorr/core/angles.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/io/atomic_file.h"
#include "driftcorr/io/geojson_writer.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/pipeline/pipeline.h"

namespace {

using driftcorr::cli::kExitBadInput;
using driftcorr::cli::kExitInternal;
using driftcorr::cli::kExitSolver;
using driftcorr::cli::kExitUsage;

const char* kAbout =
    "driftcorr removes the drift from a trajectory using the map of the place.\n"
    "commands: correct (batch), stream (online, pose by pose), eval (against ground truth)\n\n";
const char* kUsage =
    "usage: driftcorr correct <scenario dir | scenario.yaml> -o <corrected.tum>\n"
    "                         [--config params.yaml] [--geojson tracks.geojson]\n"
    "                         [--covariance poses.txt] [--on-failure refuse|estimate|write]\n"
    "                         [--solver driftcorr|paper] [--quiet]\n"
    "       driftcorr eval <scenario dirs...> [-o report_dir] [--config params.yaml] [--quiet]\n"
    "       driftcorr stream <scenario dir | scenario.yaml> [--replay] [--rate-hz R] [--sync]\n"
    "                        [--config params.yaml] [--smoothed-out smoothed.tum]\n"
    "\n"
    "Corrects the scenario's drifting estimate against its map and writes the corrected\n"
    "trajectory as TUM (t x y z qx qy qz qw) in the estimate's own frame and timestamps.\n"
    "--geojson also writes estimate and corrected track (and ground truth) as WGS84 GeoJSON.\n"
    "--solver paper runs the paper's epoch-wise gradient descent (a reference) instead.\n"
    "--covariance writes per pose: t, the horizontal covariance (East, North) [m^2], the\n"
    "height and heading variances, and the verdict's pose flags.\n"
    "eval compares the uncorrected estimate, the paper's method and driftcorr (see eval -h).\n"
    "Every run ends with a verdict, judged without ground truth: ok, degraded (written, with the\n"
    "reasons) or failed. --on-failure: refuse (default) writes nothing, estimate writes the input\n"
    "unchanged, write writes the result anyway; a failed run exits 3 in every case.\n"
    "Exit codes: 0 ok or degraded, 1 usage, 2 bad input, 3 failed, 4 internal.\n";

struct Args {
    std::string scenario, output, config, geojson, covariance;
    std::string solver = "driftcorr";
    std::string on_failure = "refuse";
    bool quiet = false;
};

bool ParseArgs(int argc, char** argv, Args& a, std::string& err) {
    if (argc < 2 || std::strcmp(argv[1], "correct") != 0) {
        err = argc < 2 ? "missing command" : std::string("unknown command '") + argv[1] + "'";
        return false;
    }
    const driftcorr::cli::OptionTable table{
        {{"--quiet", &a.quiet}, {"-q", &a.quiet}},
        {{"-o", &a.output}, {"--output", &a.output}, {"--config", &a.config},
         {"--geojson", &a.geojson}, {"--solver", &a.solver}, {"--covariance", &a.covariance},
         {"--on-failure", &a.on_failure}}};
    auto positional = [&a](const std::string& arg) -> std::string {
        if (!a.scenario.empty()) return "unexpected argument " + arg;
        a.scenario = arg;
        return "";
    };
    if (!driftcorr::cli::ParseOptions(argc, argv, 2, table, positional, err)) return false;
    if (a.solver != "driftcorr" && a.solver != "paper") {
        err = "--solver must be driftcorr or paper, not '" + a.solver + "'";
        return false;
    }
    if (a.on_failure != "refuse" && a.on_failure != "estimate" && a.on_failure != "write") {
        err = "--on-failure must be refuse, estimate or write, not '" + a.on_failure + "'";
        return false;
    }
    if (a.scenario.empty()) err = "missing scenario";
    else if (a.output.empty()) err = "missing -o <corrected.tum>";
    return err.empty();
}

// Progress on stderr: a rewritten line on a terminal, a line per 20 % otherwise.
driftcorr::ProgressCallback MakeProgress(bool quiet) {
    if (quiet) return {};
    const bool tty = ::isatty(STDERR_FILENO);
    return [tty, last = -1](const driftcorr::CorrectionProgress& p) mutable {
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

void PrintMetricsRow(const char* label, const driftcorr::ErrorMetrics& m, bool floors) {
    std::printf("  %-10s ATE %8.2f m   final %8.2f m   max %8.2f m   p90 %8.2f m   drift %6.2f %%",
                label, m.ate_m, m.final_m, m.max_m, m.p90_m, m.drift_pct);
    if (floors) std::printf("   right floor %5.1f %%", 100.0 * m.floor_accuracy);
    std::printf("\n");
}

// How the start fits the map: the estimated start, or the given one and the best other heading.
void PrintAnchorFit(const driftcorr::pipeline::CorrectionRun& run) {
    using driftcorr::RadToDeg;
    const driftcorr::AnchorFitResult& f = *run.anchor_fit;
    const auto& a = run.scenario.anchor;
    const bool estimated = !a.yaw_deg || a.position_search_m > 0.0;
    std::printf("anchor     %s yaw %.2f deg, start (%.1f, %.1f) m: the first %.0f m lie RMS %.2f m "
                "from the map (%.0f %% beyond reach)", estimated ? "estimated" : "given",
                RadToDeg(run.anchor.yaw_rad), run.anchor.origin_en.x(), run.anchor.origin_en.y(),
                f.lead_path_m, estimated ? f.best.rms_m : f.given.rms_m,
                100.0 * (estimated ? f.best.off_share : f.given.off_share));
    if (!estimated && (f.best.dyaw_rad != 0.0 || f.best.offset_en.norm() > 0.0)) {
        std::printf("; best other start %+.1f deg, (%.1f, %.1f) m: RMS %.2f m",
                    RadToDeg(f.best.dyaw_rad), f.best.offset_en.x(), f.best.offset_en.y(),
                    f.best.rms_m);
    }
    if (f.runner_up) {
        std::printf("; next distinct start %+.1f deg, (%.1f, %.1f) m: RMS %.2f m",
                    RadToDeg(f.runner_up->dyaw_rad), f.runner_up->offset_en.x(),
                    f.runner_up->offset_en.y(), f.runner_up->rms_m);
    }
    std::printf("\n");
}

void PrintVerdict(const driftcorr::Verdict& v) {
    std::printf("verdict    %s", driftcorr::ToString(v.level).c_str());
    std::printf(" (corrected / estimated path %.2f..%.2f, %zu input jump(s), %.0f %% off the map)\n",
                v.scale_min, v.scale_max, v.input_jumps, 100.0 * v.off_map_share);
    for (const std::string& r : v.reasons) std::printf("  %s\n", r.c_str());
}

void PrintSummary(const driftcorr::pipeline::CorrectionRun& run, const std::string& out,
                  driftcorr::pipeline::Solver solver) {
    const auto& r = run.result;
    const bool indoor = run.scenario.mode == driftcorr::io::ScenarioMode::kIndoor3d;
    const double total = run.timings.load_s + run.timings.map_s + run.timings.solve_s;
    std::printf("scenario   %s (%s), %zu poses\n", run.scenario.name.c_str(),
                driftcorr::io::ToString(run.scenario.mode).c_str(), run.estimate.size());
    std::printf(indoor ? "map        %zu walkways on the walk's floor, %.1f km, field %zu cells\n"
                       : "map        %zu roads, %.1f km, field %zu cells\n", run.network.roads.size(),
                run.network.TotalLengthM() / 1000.0, run.map_grid_cells);
    if (solver == driftcorr::pipeline::Solver::kPaper) {
        std::printf("solver     paper: %s (%s)\n", driftcorr::ToString(r.status).c_str(),
                    r.message.c_str());
    } else {
        std::printf("solver     %s (%s); %zu windows, %d Ipopt iterations, %zu poses on hard corridor,"
                    " scale %.3f..%.3f\n", driftcorr::ToString(r.status).c_str(), r.message.c_str(),
                    r.windows, r.iterations, r.constrained_poses, r.scale_min, r.scale_max);
    }
    std::printf("time       %.3f s (load %.3f, map %.3f, correction %.3f = %.0f poses/s:"
                " incremental %.3f, refine %.3f)\n", total, run.timings.load_s, run.timings.map_s,
                run.timings.solve_s, run.estimate.size() / std::max(1e-9, run.timings.solve_s),
                r.incremental_s, r.refine_s);
    if (run.anchor_fit) PrintAnchorFit(run);
    if (run.before) PrintMetricsRow("estimate", *run.before, indoor);
    if (run.after) PrintMetricsRow("corrected", *run.after, indoor);
    PrintVerdict(run.verdict);
    if (!out.empty()) std::printf("wrote      %s\n", out.c_str());
}

std::vector<driftcorr::GeoPoint> ToGeo(const driftcorr::pipeline::WorldFrame& w,
                                       const driftcorr::PlanarTrajectory& t) {
    std::vector<driftcorr::GeoPoint> out;
    for (const auto& p : t.p_en) out.push_back(w.ToGeo(p));
    return out;
}

// Per pose: t, covariance East-North [m^2], height and heading variance, the verdict's flags.
void WriteCovariance(const std::string& path, const driftcorr::pipeline::CorrectionRun& run) {
    const auto& cov = run.result.covariance;
    if (cov.status != driftcorr::CovarianceStatus::kOk) {
        throw std::runtime_error(path + ": no covariance: " + cov.message);
    }
    driftcorr::io::AtomicFile file(path);
    std::ofstream& out = file.stream();
    out << "# t var_e_m2 cov_en_m2 var_n_m2 var_up_m2 var_yaw_rad2 flags"
           " (flags: 1 off the map, 2 input jump, 4 implausible scale)\n";
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
    const driftcorr::pipeline::CorrectionRun& run) {
    std::vector<std::string> reasons, sigma_e, sigma_n, flags;
    for (const auto& r : run.verdict.reasons) reasons.push_back(driftcorr::io::JsonString(r));
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
        {"verdict", driftcorr::io::JsonString(driftcorr::ToString(run.verdict.level))},
        {"verdict_reasons", JsonArray(reasons)},
        {"pose_flags", JsonArray(flags)}};
    if (!sigma_e.empty()) {
        p.push_back({"sigma_east_m", JsonArray(sigma_e)});
        p.push_back({"sigma_north_m", JsonArray(sigma_n)});
    }
    return p;
}

int RunCorrect(const Args& a) {
    using namespace driftcorr;
    driftcorr::cli::CheckOutputPath(a.output, "-o");
    if (!a.geojson.empty()) {
        driftcorr::cli::CheckOutputPath(a.geojson, "--geojson");
        std::error_code ec;
        if (a.geojson == a.output || std::filesystem::equivalent(a.geojson, a.output, ec)) {
            throw InputError(a.geojson, 0, "--geojson", "is the same file as -o");
        }
    }
    pipeline::PipelineConfig cfg;
    if (!a.config.empty()) cfg = pipeline::LoadPipelineConfig(a.config);
    cfg.solver = a.solver == "paper" ? pipeline::Solver::kPaper : pipeline::Solver::kDriftcorr;
    pipeline::CorrectionRun run = pipeline::RunCorrection(a.scenario, cfg, MakeProgress(a.quiet));
    for (const std::string& w : run.scenario.warnings) std::fprintf(stderr, "driftcorr: warning: %s\n", w.c_str());
    for (const std::string& w : run.result.warnings) std::fprintf(stderr, "driftcorr: warning: %s\n", w.c_str());
    const bool failed = run.verdict.level == VerdictLevel::kFailed;
    const bool usable = Usable(run.result.status);
    // A failed correction is written only on request: the input unchanged (estimate), or the
    // result anyway (write, when the solver produced one).
    const bool write_result = usable && (!failed || a.on_failure == "write");
    const bool write_estimate = failed && !write_result && a.on_failure == "estimate";
    if (!write_result && !write_estimate) {
        PrintSummary(run, "", cfg.solver);
        std::fprintf(stderr, "driftcorr: the correction failed (%s); nothing written\n",
                     run.verdict.reasons.empty() ? run.result.message.c_str()
                                                 : run.verdict.reasons.front().c_str());
        return kExitSolver;
    }
    // The side outputs first: if anything fails, the corrected trajectory (the main output) is
    // not written (each file itself is written to a temporary and renamed when complete).
    if (!a.covariance.empty() && write_result) WriteCovariance(a.covariance, run);
    if (!a.geojson.empty()) {
        pipeline::WorldFrame world(run.scenario.anchor);
        std::vector<io::GeoTrack> tracks = {{"estimate", ToGeo(world, run.estimate)}};
        if (write_result) {
            tracks.push_back({"corrected", ToGeo(world, run.result.corrected),
                              CorrectedProperties(run)});
        } else {
            tracks.front().json_properties = {
                {"verdict", io::JsonString(ToString(run.verdict.level))}};
        }
        if (run.ground_truth) tracks.push_back({"ground_truth", ToGeo(world, *run.ground_truth)});
        io::WriteGeoJsonTracks(a.geojson, tracks);
    }
    io::WriteTum(a.output, write_result ? run.corrected_frame : run.estimate_frame);
    PrintSummary(run, a.output, cfg.solver);
    if (write_estimate) {
        std::fprintf(stderr, "driftcorr: the correction failed; wrote the estimate unchanged\n");
    }
    return failed ? kExitSolver : 0;
}

}  // namespace

namespace {

// Subcommands with their own source file (commands.h), one line each; `correct` is handled below.
struct Command {
    const char* name;
    int (*run)(int argc, char** argv);
};
const Command kCommands[] = {
    {"eval", &driftcorr::cli::RunEvalCommand},
    {"stream", &driftcorr::cli::RunStreamCommand},
};

}  // namespace

int main(int argc, char** argv) {
    if (argc >= 2 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
                      std::strcmp(argv[1], "help") == 0)) {
        std::fputs(kAbout, stdout);
        std::fputs(kUsage, stdout);
        return 0;
    }
    if (argc >= 2) {
        for (const Command& c : kCommands) {
            if (std::strcmp(argv[1], c.name) == 0) return c.run(argc - 1, argv + 1);
        }
    }
    Args args;
    std::string err;
    if (!ParseArgs(argc, argv, args, err)) {
        if (!err.empty()) std::fprintf(stderr, "driftcorr: %s\n\n", err.c_str());
        std::fputs(kUsage, err.empty() ? stdout : stderr);
        return err.empty() ? 0 : kExitUsage;
    }
    try {
        return RunCorrect(args);
    } catch (const driftcorr::InputError& e) {
        std::fprintf(stderr, "driftcorr: %s\n", e.what());
        return kExitBadInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "driftcorr: internal error: %s\n", e.what());
        return kExitInternal;
    }
}
