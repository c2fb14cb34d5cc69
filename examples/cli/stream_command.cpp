// `driftcorr stream`: corrects poses read from standard input one line at a time and writes each
// corrected pose to standard output as soon as it is computed (flushed per line).
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "commands.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/core/format.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/io/tum_line.h"
#include "driftcorr/optim/verdict.h"
#include "driftcorr/pipeline/online.h"

namespace driftcorr::cli {
namespace {

const char* kStreamUsage =
    "usage: driftcorr stream <scenario dir | scenario.yaml> [--config params.yaml]\n"
    "                        [--replay] [--rate-hz R] [--max-lag N] [--status-column]\n"
    "                        [--smoothed-out smoothed.tum] [--sync] [-q]\n"
    "\n"
    "Reads TUM pose lines (t x y z qx qy qz qw, in the scenario's trajectory frame) from standard\n"
    "input and writes each corrected pose as a TUM line to standard output as soon as it is\n"
    "computed (a causal estimate: the pose composed onto the newest solved window). The scenario\n"
    "supplies the map, anchor and frame; its estimate is only read with --replay, which feeds it\n"
    "through the same path instead of standard input, at R poses per second (as fast as possible\n"
    "when R is 0 or absent).\n"
    "--status-column appends to each line the age of the correction it used: epochs and seconds\n"
    "(stream time) since the last pose of the solve it chains from, 1 if that was the newest\n"
    "solve requested before the pose (fresh) else 0, the pose's horizontal covariance\n"
    "var_east var_east_north var_north [m^2] (nan when not known; scaled by how well it held\n"
    "the outputs' final estimates so far: online.calibrate_covariance), and why the pose may be\n"
    "wrong (bits: 1 off the map, 2 the solve it chains from in a wrong basin, 4 a step-length\n"
    "scale outside the plausible range, 8 start-scale hypotheses that part, 16 a speed jump of\n"
    "the input within the last 10 s or before a turn after it, 32 the global scale still\n"
    "searched, 64 the first output after a re-localisation, 128 the newest solve moved the\n"
    "previous output outside its 95 % region; 0: none).\n"
    "An anchor with `scale: auto` (an estimate of unknown size): the global scale is searched on\n"
    "the poses so far until its leading path is 1000 m (as correct does, its trial corrections\n"
    "on the poses so far); until then each output is the input at the scale that fits the map\n"
    "best so far (doubt 32, no covariance), then the online correction starts with every pose\n"
    "so far at the scale found (that pose's line waits for the search).\n"
    "Back-pressure: while the input arrives faster than real time (a file piped in, a replay, a\n"
    "burst: its timestamps advance more than twice as fast as the wall clock), the next line is\n"
    "read only once the last pose is at most N epochs past the last solved one (--max-lag N,\n"
    "default 1; online.max_lag_epochs in --config; 0: never wait, outputs then chain from older\n"
    "solves). Input at its own real-time pace is never held back (online.hold_live_input: true\n"
    "holds it too).\n"
    "With several start scales (the pedestrian model: 1, 1.25, 1.5) one hypothesis per start runs\n"
    "the online correction, and each output comes from the one of lowest NLL so far; a switch is\n"
    "noted on stderr (the output may jump there).\n"
    "Invalid lines (bad numbers, NaN, timestamps not increasing, a last line without newline) are\n"
    "skipped with a warning on stderr naming the line; the stream goes on. A pause of the input\n"
    "longer than online.gap_warn_s is reported once, when it resumes.\n"
    "At the end of input: a summary on stderr (share of poses emitted without a fresh solve, "
    "worst\n"
    "age, solve time per window, output latency per line), then the whole trajectory is smoothed\n"
    "(the batch result) and judged (the verdict); --smoothed-out writes it as TUM.\n"
    "--sync solves inside the pose loop (deterministic; slower per pose).\n"
    "The causal outputs are then compared with the smoothed trajectory: when the two lie farther\n"
    "apart than the input lies from the smoothed trajectory, both are reported as failed.\n"
    "SIGINT or SIGTERM ends the input: the stream finishes with the poses read (summary,\n"
    "--smoothed-out, verdict) and exits with 130 or 143.\n"
    "Exit codes: 0 ok, 1 usage, 2 bad input (scenario/config) or standard output not writable\n"
    "(the stream stops), 3 smoothing failed, the verdict failed or the causal outputs failed\n"
    "(everything was still written), 4 internal, 130 / 143 stopped by SIGINT / SIGTERM.\n";

struct StreamArgs {
    std::string scenario, config, smoothed_out, max_lag;
    bool replay = false, sync = false, quiet = false, status_column = false;
    double rate_hz = 0.0;
};

bool ParseStreamArgs(int argc, char** argv, StreamArgs& a, std::string& err) {
    std::string rate;
    const OptionTable table{{{"--replay", &a.replay},
                             {"--sync", &a.sync},
                             {"--quiet", &a.quiet},
                             {"-q", &a.quiet},
                             {"--status-column", &a.status_column}},
                            {{"--config", &a.config},
                             {"--smoothed-out", &a.smoothed_out},
                             {"--rate-hz", &rate},
                             {"--max-lag", &a.max_lag}}};
    auto positional = [&a](const std::string& arg) -> std::string {
        if (!a.scenario.empty()) return "unexpected argument " + arg;
        a.scenario = arg;
        return "";
    };
    if (!ParseOptions(argc, argv, 1, table, positional, err)) return false;
    if (!rate.empty()) {
        char* end = nullptr;
        a.rate_hz = std::strtod(rate.c_str(), &end);
        if (*end != '\0' || !(a.rate_hz >= 0.0)) {
            err = "--rate-hz needs a number >= 0";
            return false;
        }
    }
    if (!a.max_lag.empty() &&
        (a.max_lag.size() > 9 || a.max_lag.find_first_not_of("0123456789") != std::string::npos)) {
        err = "--max-lag needs a whole number of epochs >= 0 (0: never wait)";
        return false;
    }
    if (a.scenario.empty()) err = "missing scenario";
    return err.empty();
}

void Warn(long line, const std::string& what) {
    std::fprintf(stderr, "driftcorr stream: line %ld: %s\n", line, what.c_str());
}

double Percentile(std::vector<double> v, double p) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, std::size_t(p * double(v.size())))];
}

std::string Milliseconds(const std::vector<double>& s) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "p50 %.2f / p99 %.2f / max %.2f ms", 1e3 * Percentile(s, 0.5),
                  1e3 * Percentile(s, 0.99),
                  s.empty() ? 0.0 : 1e3 * *std::max_element(s.begin(), s.end()));
    return buf;
}

using Clock = std::chrono::steady_clock;

// The stream's state: the corrector and the accepted inputs (for the smoothed output).
class StreamSession {
public:
    StreamSession(pipeline::StreamSetup setup, const OnlineConfig& cfg,
                  const pipeline::PipelineConfig& pipeline_config, bool status_column)
        : cfg_(cfg),
          session_(std::move(setup), cfg, pipeline_config.verdict, pipeline_config),
          status_column_(status_column) {}

    const pipeline::StreamSetup& setup() const { return session_.setup(); }

    // One input line (without newline), read at `arrived` after waiting `pause_s` for it (the
    // producer's pause, not this program's own work); `complete` is false for a last line without
    // newline.
    void HandleLine(long number, const std::string& text, bool complete, Clock::time_point arrived,
                    double pause_s) {
        const io::TumLine line = io::ParseTumLine(text);
        if (line.kind == io::TumLine::Kind::kSkip) return;
        if (!complete) return Skip(number, "input ended mid-line (no newline); line ignored");
        if (line.kind == io::TumLine::Kind::kError) return Skip(number, line.error);
        if (const std::string unit = io::ImplausibleTimestamp(line.t_s); !unit.empty()) {
            // Not one bad line but the whole input's unit: every later line would be wrong too.
            throw InputError("standard input", number, "", unit);
        }
        const pipeline::StreamSession::Output pushed =
            session_.Push(line.t_s, line.p_frame, line.q_frame_body);
        const PushResult& r = pushed.result;
        if (!r.Accepted()) return Skip(number, r.message);
        std::string out = io::FormatTumLine(line.t_s, pushed.p_frame, pushed.q_frame_body);
        if (status_column_) {
            char status[160];
            const Eigen::Matrix2d& c = r.covariance.xy_m2;
            const double nan = std::numeric_limits<double>::quiet_NaN();
            std::snprintf(status, sizeof(status), " %zu %.3f %d %.6g %.6g %.6g %u\n",
                          r.correction_age_epochs, r.correction_age_s, r.fresh ? 1 : 0,
                          r.covariance_ok ? c(0, 0) : nan, r.covariance_ok ? c(0, 1) : nan,
                          r.covariance_ok ? c(1, 1) : nan, r.doubt);
            out.pop_back();
            out += status;
        }
        if (std::fputs(out.c_str(), stdout) < 0 || std::fflush(stdout) != 0) {
            throw OutputError("standard output", "",
                              "write failed (" + std::string(std::strerror(errno)) +
                                  ") at input line " + std::to_string(number) +
                                  "; the stream stopped");
        }
        // Read to written: a back-pressure wait comes before the pose is taken (as if the line
        // had been read later), so it is not part of the pose's latency; it is reported apart.
        latency_s_.push_back(std::chrono::duration<double>(Clock::now() - arrived).count() -
                             r.waited_s);
        ReportWarnings(number, r, pause_s);
    }

    int Finish(const std::string& smoothed_out, bool quiet) {
        const OnlineStatistics st = session_.Statistics();
        if (!quiet) Summarise(st);
        const pipeline::StreamSession::Ending end = *session_.Finish();  // the one Finish
        const CorrectionResult& result = end.result;
        const std::optional<OnlineVerdict>& judged = end.judged;
        if (!quiet && end.scale) {
            std::fprintf(stderr,
                         "driftcorr stream: scale found %.4f from the map's fit of the first "
                         "%zu poses; their outputs were the input at the best scale so far "
                         "(doubt 32)\n",
                         end.scale->scale, end.outputs_before_scale);
        }
        if (!quiet) {
            std::fprintf(stderr, "driftcorr stream: smoothing: %s (%s)\n",
                         ToString(result.status).c_str(), result.message.c_str());
            if (judged) {
                std::string reasons;
                for (const std::string& why : judged->verdict.reasons) reasons += "; " + why;
                std::fprintf(stderr, "driftcorr stream: verdict %s%s\n",
                             ToString(judged->verdict.level).c_str(), reasons.c_str());
                ReportCausal(judged->check);
            }
        }
        // Outputs already written cannot be taken back: what the program cannot vouch for is
        // said, and the exit code says it too.
        const bool vouched = judged && judged->verdict.level != VerdictLevel::kFailed;
        if (smoothed_out.empty()) return vouched ? 0 : kExitSolver;
        if (!Usable(result.status)) {
            std::fprintf(stderr, "driftcorr stream: no smoothed trajectory (%s); nothing written\n",
                         result.message.c_str());
            return kExitSolver;
        }
        io::WriteTum(smoothed_out, *end.smoothed);
        return vouched ? 0 : kExitSolver;
    }

private:
    void Summarise(const OnlineStatistics& st) const {
        std::fprintf(stderr, "driftcorr stream: %zu poses corrected, %zu lines skipped\n",
                     session_.accepted(), skipped_);
        const double stale = st.poses ? 100.0 * double(st.stale_poses) / double(st.poses) : 0.0;
        std::fprintf(stderr,
                     "driftcorr stream: freshness: %.1f %% of poses emitted without a fresh solve; "
                     "worst age %zu epochs (%.2f s)%s\n",
                     stale, st.max_age_epochs, st.max_age_s,
                     st.stale_poses > 0 ? " (the solver did not keep up with the input)" : "");
        const double ahead = st.poses ? 100.0 * double(st.ahead_poses) / double(st.poses) : 0.0;
        std::string back_pressure = "off (--max-lag 0)";
        if (cfg_.max_lag_epochs > 0) {
            back_pressure = "at " + std::to_string(cfg_.max_lag_epochs) + " epochs, on " +
                            (cfg_.hold_live_input ? "all input" : "input faster than real time");
        }
        std::fprintf(stderr,
                     "driftcorr stream: input pace: %.1f %% of poses arrived faster than real "
                     "time; back-pressure %s\n",
                     ahead, back_pressure.c_str());
        std::fprintf(stderr,
                     "driftcorr stream: solves: %zu of %zu requested (%zu with a marginalised "
                     "prior, %zu failed); solve time per window %s\n",
                     st.solves, st.requests, st.prior_solves, st.failed_solves,
                     Milliseconds(st.solve_s).c_str());
        std::fprintf(stderr,
                     "driftcorr stream: output latency per line %s; input held back %zu "
                     "times, %.2f s in all (back-pressure)\n",
                     Milliseconds(latency_s_).c_str(), st.waits, st.wait_s);
        if (st.relocalisations > 0) {
            std::fprintf(stderr,
                         "driftcorr stream: re-localisations: %zu (the prefix solved as a "
                         "whole where the chain was in doubt), %.2f s in all; the chain "
                         "continued from %zu of them\n",
                         st.relocalisations, st.relocalise_s, st.relocalised);
        }
        if (!st.worker_error.empty()) {
            std::fprintf(stderr,
                         "driftcorr stream: warning: %s; later outputs were composed "
                         "onto the last solve\n",
                         st.worker_error.c_str());
        }
    }
    static void ReportCausal(const CausalCheck& c) {
        std::fprintf(
            stderr,
            "driftcorr stream: causal outputs against the smoothed trajectory: RMS %.2f m, "
            "max %.2f m (the input: RMS %.2f m)\n",
            c.causal_rms_m, c.causal_max_m, c.input_rms_m);
        if (c.floor_apart_share > 0.0) {
            std::fprintf(
                stderr,
                "driftcorr stream: causal outputs a floor apart from the smoothed "
                "trajectory: %.1f %% of the poses, %.0f s in a row at most, up to %.1f m\n",
                100.0 * c.floor_apart_share, c.floor_apart_longest_s, c.floor_apart_max_m);
        }
    }
    void Skip(long number, const std::string& why) {
        ++skipped_;
        Warn(number, "skipped: " + why);
    }
    // A pause of the input (wall time) or a gap in the stream's time: one message per pause;
    // leaving and re-entering the map once per transition.
    void ReportWarnings(long number, const PushResult& r, double pause_s) {
        const bool paused = pause_s > cfg_.gap_warn_s;
        if (paused || r.gap) {
            std::string msg = "warning: ";
            if (paused) msg += "input resumed after a pause of " + FormatFixed(pause_s, 2) + " s";
            if (paused && r.gap) msg += "; ";
            if (r.gap) msg += r.message;
            Warn(number, msg + "; the stream goes on");
        }
        if (start_scale_ && r.start_scale != *start_scale_) {
            Warn(number, "note: outputs now from start scale " + FormatFixed(r.start_scale, 2) +
                             " (the hypothesis of lowest NLL so far); the output may jump");
        }
        start_scale_ = r.start_scale;
        if (r.outside_map != outside_) {
            Warn(number, r.outside_map ? "warning: pose is outside the map; odometry only until "
                                         "it is back on the map"
                                       : "note: back on the map");
            outside_ = r.outside_map;
        }
    }

    OnlineConfig cfg_;
    pipeline::StreamSession session_;
    bool status_column_;
    std::size_t skipped_ = 0;
    bool outside_ = false;
    std::optional<double> start_scale_;  ///< of the last output (OnlineConfig start scales)
    std::vector<double> latency_s_;      ///< per output line: read to written and flushed [s]
};

// SIGINT / SIGTERM end the input: the reading thread is interrupted (the signal is passed on to
// it when another thread caught it) and standard input closed, so that the stream finishes as at
// the end of its input (summary, smoothed output, verdict) and exits with 128 + the signal.
volatile std::sig_atomic_t g_stop_signal = 0;
pthread_t g_reader;

extern "C" void OnStopSignal(int sig) {
    const int saved = errno;
    g_stop_signal = sig;
    if (!pthread_equal(pthread_self(), g_reader)) {
        pthread_kill(g_reader, sig);
    } else {
        ::close(STDIN_FILENO);  // a read that starts after this returns at once
    }
    errno = saved;
}

void CatchStopSignals() {
    g_reader = pthread_self();
    struct sigaction action {};
    action.sa_handler = OnStopSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;  // no SA_RESTART: the blocked read returns EINTR
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
}

void ReadStdin(StreamSession& session) {
    std::string text;
    long number = 0;
    Clock::time_point waiting_since = Clock::now();
    while (g_stop_signal == 0 && std::getline(std::cin, text)) {
        ++number;
        const Clock::time_point arrived = Clock::now();
        const double waited_s =
            number > 1 ? std::chrono::duration<double>(arrived - waiting_since).count() : 0.0;
        session.HandleLine(number, text, !std::cin.eof(), arrived, waited_s);
        waiting_since = Clock::now();
    }
}

// The scenario's estimate, formatted as TUM lines and fed through the same path, at rate_hz.
void Replay(const io::Scenario& sc, double rate_hz, StreamSession& session) {
    const Trajectory est = io::LoadTrajectory(sc.estimate);
    if (!est.HasOrientation()) {  // stream's lines carry one (t x y z qx qy qz qw)
        throw InputError(sc.estimate.path, 0, "",
                         "the estimate has positions only; stream reads poses with orientation "
                         "(correct takes positions only, the heading from the motion)");
    }
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < est.size() && g_stop_signal == 0; ++i) {
        if (rate_hz > 0.0) {
            std::this_thread::sleep_until(t0 + std::chrono::duration<double>(double(i) / rate_hz));
        }
        std::string text = io::FormatTumLine(est.t_s[i], est.p_frame[i], est.q_frame_body[i]);
        text.pop_back();  // the newline
        session.HandleLine(long(i + 1), text, true, Clock::now(), 0.0);
    }
}

int RunStream(const StreamArgs& a) {
    const auto start = Clock::now();
    io::Scenario scenario = io::LoadScenario(a.scenario);
    if (!a.smoothed_out.empty()) {
        CheckOutputPath(a.smoothed_out, "--smoothed-out");
        std::vector<io::InputFile> inputs = io::InputFiles(scenario);
        if (!a.config.empty()) inputs.push_back({"the --config file", a.config});
        CheckOutputsAgainstInputs({{"--smoothed-out", a.smoothed_out}}, inputs);
    }
    pipeline::PipelineConfig cfg;
    if (!a.config.empty()) cfg = pipeline::LoadPipelineConfig(a.config);
    pipeline::StreamSetup setup = pipeline::LoadStreamSetup(std::move(scenario), cfg);
    OnlineConfig online = cfg.online;
    online.corrector = pipeline::CorrectorFor(setup.scenario, cfg);
    online.synchronous = a.sync;
    if (!a.max_lag.empty()) online.max_lag_epochs = std::stoul(a.max_lag);
    if (std::string m = online.Validate(); !m.empty()) throw InputError(a.config, 0, "", m);
    StreamSession session(std::move(setup), online, cfg, a.status_column);
    if (!a.quiet) {
        // Poses a producer writes before this line wait in the pipe and arrive as one burst.
        std::fprintf(stderr, "driftcorr stream: map ready after %.2f s; reading poses\n",
                     std::chrono::duration<double>(Clock::now() - start).count());
    }
    CatchStopSignals();
    if (a.replay)
        Replay(session.setup().scenario, a.rate_hz, session);
    else
        ReadStdin(session);
    const int stop = g_stop_signal;
    if (stop != 0) {
        std::fprintf(stderr, "driftcorr stream: %s: input stopped; finishing with the poses read\n",
                     stop == SIGINT ? "SIGINT" : "SIGTERM");
    }
    const int code = session.Finish(a.smoothed_out, a.quiet);
    return stop != 0 ? 128 + stop : code;
}

}  // namespace

int RunStreamCommand(int argc, char** argv) {
    StreamArgs args;
    std::string err;
    if (!ParseStreamArgs(argc, argv, args, err)) {
        if (!err.empty()) std::fprintf(stderr, "driftcorr stream: %s\n\n", err.c_str());
        std::fputs(kStreamUsage, err.empty() ? stdout : stderr);
        return err.empty() ? 0 : kExitUsage;
    }
    return RunReportingErrors("driftcorr stream", [&] { return RunStream(args); });
}

}  // namespace driftcorr::cli
