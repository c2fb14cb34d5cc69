// `driftcorr stream`: corrects poses read from standard input one line at a time and writes each
// corrected pose to standard output as soon as it is computed (flushed per line).
#include <chrono>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "commands.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/io/tum_line.h"
#include "driftcorr/pipeline/online.h"

namespace driftcorr::cli {
namespace {

const char* kStreamUsage =
    "usage: driftcorr stream <scenario dir | scenario.yaml> [--config params.yaml]\n"
    "                        [--replay] [--rate-hz R] [--smoothed-out smoothed.tum] [--sync] [-q]\n"
    "\n"
    "Reads TUM pose lines (t x y z qx qy qz qw, in the scenario's trajectory frame) from standard\n"
    "input and writes each corrected pose as a TUM line to standard output as soon as it is\n"
    "computed (a causal estimate). The scenario supplies the map, anchor and frame; its estimate\n"
    "is only read with --replay, which feeds it through the same path instead of standard input,\n"
    "at R poses per second (as fast as possible when R is 0 or absent).\n"
    "Invalid lines (bad numbers, NaN, timestamps not increasing, a last line without newline) are\n"
    "skipped with a warning on stderr naming the line; the stream goes on.\n"
    "At the end of input the whole trajectory is smoothed; --smoothed-out writes it as TUM.\n"
    "--sync solves inside the pose loop (deterministic; slower per pose).\n"
    "Exit codes: 0 ok, 1 usage, 2 bad input (scenario/config), 3 smoothing failed, 4 internal.\n";

struct StreamArgs {
    std::string scenario, config, smoothed_out;
    bool replay = false, sync = false, quiet = false;
    double rate_hz = 0.0;
};

bool ParseStreamArgs(int argc, char** argv, StreamArgs& a, std::string& err) {
    std::string rate;
    const OptionTable table{
        {{"--replay", &a.replay}, {"--sync", &a.sync}, {"--quiet", &a.quiet}, {"-q", &a.quiet}},
        {{"--config", &a.config}, {"--smoothed-out", &a.smoothed_out}, {"--rate-hz", &rate}}};
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
    if (a.scenario.empty()) err = "missing scenario";
    return err.empty();
}

void Warn(long line, const std::string& what) {
    std::fprintf(stderr, "driftcorr stream: line %ld: %s\n", line, what.c_str());
}

// The stream's state: the corrector and the accepted inputs (for the smoothed output).
class StreamSession {
public:
    StreamSession(const pipeline::StreamSetup& setup, const OnlineConfig& cfg)
        : setup_(setup), corrector_(&setup.field, cfg) {}

    // One input line (without newline); `complete` is false for a last line without newline.
    void HandleLine(long number, const std::string& text, bool complete) {
        const io::TumLine line = io::ParseTumLine(text);
        if (line.kind == io::TumLine::Kind::kSkip) return;
        if (!complete) return Skip(number, "input ended mid-line (no newline); line ignored");
        if (line.kind == io::TumLine::Kind::kError) return Skip(number, line.error);
        const FrameAxes axes = setup_.scenario.frame;
        const PlanarPose in =
            pipeline::ToPlanarPose(line.t_s, line.p_frame, line.q_frame_body, axes, setup_.anchor);
        const PushResult r = corrector_.Push(in);
        if (!r.Accepted()) return Skip(number, r.message);
        const auto [p, q] = pipeline::FromPlanarPose(r.corrected, in, line.p_frame,
                                                     line.q_frame_body, axes, setup_.anchor);
        std::fputs(io::FormatTumLine(line.t_s, p, q).c_str(), stdout);
        std::fflush(stdout);
        Record(in, line);
        ReportWarnings(number, r);
    }

    int Finish(const std::string& smoothed_out, bool quiet) {
        const CorrectionResult result = corrector_.Finish();
        if (!quiet) {
            std::fprintf(stderr, "driftcorr stream: %zu poses corrected, %zu lines skipped; "
                         "smoothing: %s (%s)\n", accepted_.size(), skipped_,
                         ToString(result.status).c_str(), result.message.c_str());
        }
        if (smoothed_out.empty()) return 0;
        if (!Usable(result.status)) {
            std::fprintf(stderr, "driftcorr stream: no smoothed trajectory (%s); nothing written\n",
                         result.message.c_str());
            return kExitSolver;
        }
        io::WriteTum(smoothed_out, FromPlanar(result.corrected, reference_, accepted_,
                                              setup_.scenario.frame, setup_.anchor));
        return 0;
    }

private:
    void Skip(long number, const std::string& why) {
        ++skipped_;
        Warn(number, "skipped: " + why);
    }
    void Record(const PlanarPose& in, const io::TumLine& line) {
        accepted_.t_s.push_back(line.t_s);
        accepted_.p_frame.push_back(line.p_frame);
        accepted_.q_frame_body.push_back(line.q_frame_body);
        reference_.t_s.push_back(in.t_s);
        reference_.p_en.push_back(in.p_en);
        reference_.up_m.push_back(in.up_m);
        reference_.yaw_rad.push_back(*in.yaw_rad);
    }
    // Gaps every time; leaving and re-entering the map once per transition.
    void ReportWarnings(long number, const PushResult& r) {
        if (r.gap) Warn(number, "warning: " + r.message);
        if (r.outside_map != outside_) {
            Warn(number, r.outside_map ? "warning: pose is outside the map; odometry only until "
                                         "it is back on the map"
                                       : "note: back on the map");
            outside_ = r.outside_map;
        }
    }

    const pipeline::StreamSetup& setup_;
    OnlineCorrector corrector_;
    Trajectory accepted_;
    PlanarTrajectory reference_;
    std::size_t skipped_ = 0;
    bool outside_ = false;
};

void ReadStdin(StreamSession& session) {
    std::string text;
    long number = 0;
    while (std::getline(std::cin, text)) {
        ++number;
        session.HandleLine(number, text, !std::cin.eof());
    }
}

// The scenario's estimate, formatted as TUM lines and fed through the same path, at rate_hz.
void Replay(const io::Scenario& sc, double rate_hz, StreamSession& session) {
    const Trajectory est = io::LoadTrajectory(sc.estimate);
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < est.size(); ++i) {
        if (rate_hz > 0.0) {
            std::this_thread::sleep_until(t0 + std::chrono::duration<double>(double(i) / rate_hz));
        }
        std::string text = io::FormatTumLine(est.t_s[i], est.p_frame[i], est.q_frame_body[i]);
        text.pop_back();  // the newline
        session.HandleLine(long(i + 1), text, true);
    }
}

int RunStream(const StreamArgs& a) {
    if (!a.smoothed_out.empty()) CheckOutputPath(a.smoothed_out, "--smoothed-out");
    pipeline::PipelineConfig cfg;
    if (!a.config.empty()) cfg = pipeline::LoadPipelineConfig(a.config);
    const pipeline::StreamSetup setup = pipeline::LoadStreamSetup(a.scenario, cfg);
    OnlineConfig online = cfg.online;
    online.corrector = pipeline::CorrectorFor(setup.scenario, cfg);
    online.synchronous = a.sync;
    if (std::string m = online.Validate(); !m.empty()) throw InputError(a.config, 0, "", m);
    StreamSession session(setup, online);
    if (a.replay) Replay(setup.scenario, a.rate_hz, session);
    else ReadStdin(session);
    return session.Finish(a.smoothed_out, a.quiet);
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
    try {
        return RunStream(args);
    } catch (const InputError& e) {
        std::fprintf(stderr, "driftcorr stream: %s\n", e.what());
        return kExitBadInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "driftcorr stream: internal error: %s\n", e.what());
        return kExitInternal;
    }
}

}  // namespace driftcorr::cli
