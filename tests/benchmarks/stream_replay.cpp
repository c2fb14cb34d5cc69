// Replays a scenario through the real `driftcorr stream` binary and a pipe, and scores its causal
// output (tests/benchmarks/run_stream_bench.sh runs both around the binary):
//   stream_replay feed <scenario> <rate_hz> [<stream log>]
//                                             the scenario's estimate as TUM lines on stdout, one
//                                             every 1/rate_hz s (0: as fast as the pipe takes
//                                             them), flushed per line; with a log, only once the
//                                             stream wrote "reading poses" into it (its map is
//                                             loaded: no start-up backlog in the pipe)
//   stream_replay score <scenario> <out.tum>  the causal ATE of the stream's output (its lines in
//                                             order, one per estimate pose; a --status-column is
//                                             read too) against the ground truth, with no
//                                             re-alignment, and the uncorrected estimate's
//   STREAM_SCORE_ERRORS=<file> score also writes each pose's time and horizontal error [m].
// Exit codes: 0 ok, 1 usage, 2 bad input.
#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "driftcorr/core/metrics.h"
#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/io/tum_line.h"
#include "driftcorr/pipeline/pipeline.h"

namespace {

using namespace driftcorr;

// Waits until `log` contains `text` (gives up after 10 min).
void WaitFor(const std::string& log, const std::string& text) {
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < std::chrono::minutes(10)) {
        std::ifstream in(log);
        std::stringstream ss;
        ss << in.rdbuf();
        if (ss.str().find(text) != std::string::npos) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
}

int Feed(const std::string& scenario, double rate_hz, const std::string& ready_log) {
    const io::Scenario sc = io::LoadScenario(scenario);
    const Trajectory est = io::LoadTrajectory(sc.estimate);
    if (!ready_log.empty()) WaitFor(ready_log, "reading poses");
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < est.size(); ++i) {
        if (rate_hz > 0.0) {
            std::this_thread::sleep_until(t0 + std::chrono::duration<double>(double(i) / rate_hz));
        }
        std::fputs(io::FormatTumLine(est.t_s[i], est.p_frame[i], est.q_frame_body[i]).c_str(),
                   stdout);
        if (rate_hz > 0.0) std::fflush(stdout);
    }
    std::fflush(stdout);
    return 0;
}

struct StreamOutput {
    Trajectory poses;
    std::vector<double> age_epochs, age_s;
    std::vector<Eigen::Matrix2d> xy_m2;  ///< per pose, when the status column has it
    std::size_t stale = 0;
};

StreamOutput ReadOutput(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    StreamOutput out;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream ss(line);
        double v[8];
        for (double& x : v) {
            if (!(ss >> x)) throw std::runtime_error(path + ": bad line: " + line);
        }
        out.poses.t_s.push_back(v[0]);
        out.poses.p_frame.emplace_back(v[1], v[2], v[3]);
        out.poses.q_frame_body.emplace_back(v[7], v[4], v[5], v[6]);
        double age = 0.0, age_s = 0.0;
        int fresh = 1;
        if (ss >> age >> age_s >> fresh) {
            out.age_epochs.push_back(age);
            out.age_s.push_back(age_s);
            out.stale += fresh == 0;
            std::string e, en, n;  // the horizontal covariance, "nan" when not known
            if (ss >> e >> en >> n) {
                Eigen::Matrix2d c;
                c << std::strtod(e.c_str(), nullptr), std::strtod(en.c_str(), nullptr),
                    std::strtod(en.c_str(), nullptr), std::strtod(n.c_str(), nullptr);
                out.xy_m2.push_back(c);
            }
        }
    }
    return out;
}

double Quantile(std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, std::size_t(q * double(v.size())))];
}

int Score(const std::string& scenario, const std::string& output) {
    const pipeline::PreparedScenario ps = pipeline::PrepareScenario(scenario, {});
    if (!ps.ground_truth) throw std::runtime_error(scenario + ": no ground truth");
    const StreamOutput out = ReadOutput(output);
    const PlanarTrajectory& gt = *ps.ground_truth;
    if (out.poses.size() != gt.size()) {
        std::printf("%s: %zu output poses for %zu ground-truth poses: incomplete\n",
                    ps.scenario.name.c_str(), out.poses.size(), gt.size());
        return 2;
    }
    const PlanarTrajectory causal = ToPlanar(out.poses, ps.scenario.frame, ps.anchor);
    const ErrorMetrics m = ComputeMetrics(causal, gt);
    if (const char* path = std::getenv("STREAM_SCORE_ERRORS")) {  // per pose: t, error [m]
        std::ofstream errors(path);
        for (std::size_t i = 0; i < gt.size(); ++i) {
            errors << gt.t_s[i] << ' ' << (causal.p_en[i] - gt.p_en[i]).norm() << '\n';
        }
    }
    const ErrorMetrics e = ComputeMetrics(ps.estimate, gt);
    std::printf(
        "%s: causal ATE %.2f m (final %.2f, max %.2f, right floor %.1f %%), estimate ATE "
        "%.2f m",
        ps.scenario.name.c_str(), m.ate_m, m.final_m, m.max_m, 100.0 * m.floor_accuracy, e.ate_m);
    if (!out.age_epochs.empty()) {
        std::printf("; stale %.1f %%, age p50 %.0f / max %.0f epochs",
                    100.0 * out.stale / out.poses.size(), Quantile(out.age_epochs, 0.5),
                    Quantile(out.age_epochs, 1.0));
    }
    if (out.xy_m2.size() == gt.size()) {  // 95 % region: d^T C^-1 d <= chi2(2 dof, 0.95)
        std::size_t inside = 0, known = 0;
        for (std::size_t i = 0; i < gt.size(); ++i) {
            const Eigen::Matrix2d& c = out.xy_m2[i];
            if (!c.allFinite() || !(c.determinant() > 0.0)) continue;
            ++known;
            const Eigen::Vector2d d = causal.p_en[i] - gt.p_en[i];
            inside += d.dot(c.inverse() * d) <= 5.991;
        }
        std::printf("; true error inside the 95 %% region: %.1f %% of %zu poses with a covariance",
                    known ? 100.0 * double(inside) / double(known) : 0.0, known);
    }
    std::printf("\n");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (argc < 4 || argc > 5 || (mode != "feed" && mode != "score") ||
        (mode == "score" && argc != 4)) {
        std::fprintf(stderr,
                     "usage: stream_replay feed <scenario> <rate_hz> [<stream log>]\n"
                     "       stream_replay score <scenario> <stream output.tum>\n");
        return 1;
    }
    try {
        if (mode == "feed") return Feed(argv[2], std::atof(argv[3]), argc == 5 ? argv[4] : "");
        return Score(argv[2], argv[3]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "stream_replay: %s\n", e.what());
        return 2;
    }
}
