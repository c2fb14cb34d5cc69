// `driftcorr eval <scenario dirs...> [-o report_dir] [--methods LIST]`: the uncorrected estimate,
// the paper's method, driftcorr and the online output (or the methods listed) on every scenario,
// a table on stdout, a report folder on request.
//
// Exit codes: 0 every scenario and method ran, 1 usage error, 2 at least one scenario (or a
// method on it) failed (the others still ran and are reported), 3 every one ran but driftcorr's
// verdict is failed on at least one, 4 internal error (the report could not be written).
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/eval/evaluation.h"
#include "driftcorr/eval/report.h"

namespace driftcorr::cli {
namespace {

/// Some scenario could not be evaluated (bad input, or a method failed): exit 2.
constexpr int kExitFailed = kExitBadInput;

const char* kEvalUsage =
    "usage: driftcorr eval <scenario dir | scenario.yaml>... [-o report_dir]\n"
    "                      [--config params.yaml] [--methods LIST] [--quiet]\n"
    "\n"
    "Runs the uncorrected estimate, the paper's method (--solver paper), driftcorr (batch) and\n"
    "the online corrector's causal output on each scenario and prints ATE / final error (and\n"
    "solver time, poses/s) per scenario and method.\n"
    "--methods runs only the methods listed, comma-separated, in that order: estimate, paper,\n"
    "driftcorr, online (default: all four).\n"
    "-o also writes report_dir/summary.md, results.json, <scenario>_map.svg and\n"
    "<scenario>_error.svg, each plot also as .png. A scenario that fails is reported and does\n"
    "not stop the others.\n"
    "Exit codes: 0 all ran, 1 usage, 2 at least one scenario or method failed, 3 all ran but\n"
    "driftcorr's verdict is failed on at least one, 4 internal.\n";

// "estimate,paper,driftcorr,online": eval::DefaultMethods() by name.
std::string DefaultMethodList() {
    std::string list;
    for (const eval::Method m : eval::DefaultMethods()) {
        list += (list.empty() ? "" : ",") + eval::ToString(m);
    }
    return list;
}

struct EvalArgs {
    std::vector<std::string> scenarios;
    std::string report_dir, config;
    std::string methods = DefaultMethodList();
    bool quiet = false;
};

// A regular file that is not a .yaml: not a scenario (folders and .yaml files are, and
// missing paths are left to the evaluation to report).
bool IsNonScenarioFile(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return false;
    const std::string ext = std::filesystem::path(path).extension().string();
    return ext != ".yaml" && ext != ".yml";
}

bool ParseEvalArgs(int argc, char** argv, EvalArgs& a, std::string& err) {
    const OptionTable table{{{"--quiet", &a.quiet}, {"-q", &a.quiet}},
                            {{"-o", &a.report_dir},
                             {"--output", &a.report_dir},
                             {"--config", &a.config},
                             {"--methods", &a.methods}}};
    auto positional = [&a](const std::string& arg) -> std::string {
        if (IsNonScenarioFile(arg)) {
            // A shell glob over a datasets folder also matches its README.md / FORMAT.md.
            std::fprintf(stderr, "driftcorr: skipping %s (not a scenario folder or .yaml file)\n",
                         arg.c_str());
        } else {
            a.scenarios.push_back(arg);
        }
        return "";
    };
    if (!ParseOptions(argc, argv, 1, table, positional, err)) return false;
    if (a.scenarios.empty()) err = "missing scenario folder(s)";
    return err.empty();
}

// "--methods estimate,online" -> the methods in that order; an unknown, repeated or empty name
// is a usage error.
bool ParseMethods(const std::string& list, std::vector<eval::Method>& methods, std::string& err) {
    methods.clear();
    std::size_t from = 0;
    while (true) {
        const std::size_t comma = list.find(',', from);
        const std::string name =
            list.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
        const std::optional<eval::Method> m = eval::MethodFromString(name);
        if (!m) {
            err = "--methods: unknown method '" + name + "' (expected a comma-separated list of " +
                  DefaultMethodList() + ")";
            return false;
        }
        if (std::find(methods.begin(), methods.end(), *m) != methods.end()) {
            err = "--methods: '" + name + "' is listed twice";
            return false;
        }
        methods.push_back(*m);
        if (comma == std::string::npos) return true;
        from = comma + 1;
    }
}

// Progress bar on stderr: rewritten in place on a terminal, one line per stage otherwise.
eval::EvalProgressCallback MakeEvalProgress(bool quiet) {
    if (quiet) return {};
    const bool tty = ::isatty(STDERR_FILENO);
    return [tty, last = std::string()](const eval::EvalProgress& p) mutable {
        const std::string head = "[eval] " + std::to_string(p.scenario_index + 1) + "/" +
                                 std::to_string(p.scenario_count) + " " + p.label;
        if (!tty) {
            const std::string key = head + " " + p.stage;
            if (key != last && p.stage != "done")
                std::fprintf(stderr, "%s: %s\n", head.c_str(), p.stage.c_str());
            last = key;
            return;
        }
        constexpr int kBar = 24;
        const int filled = std::clamp(int(p.fraction * kBar + 0.5), 0, kBar);
        std::fprintf(stderr, "\r\033[K%-45s %-10s [%s%s] %3d %%", head.c_str(), p.stage.c_str(),
                     std::string(filled, '#').c_str(), std::string(kBar - filled, '.').c_str(),
                     int(100 * p.fraction));
        if (p.stage == "done") std::fputc('\n', stderr);
        std::fflush(stderr);
    };
}

}  // namespace

int RunEvalCommand(int argc, char** argv) {
    EvalArgs args;
    std::string err;
    eval::EvalConfig config;
    const bool parsed =
        ParseEvalArgs(argc, argv, args, err) && ParseMethods(args.methods, config.methods, err);
    if (!parsed) {
        if (!err.empty()) std::fprintf(stderr, "driftcorr: %s\n\n", err.c_str());
        std::fputs(kEvalUsage, err.empty() ? stdout : stderr);
        return err.empty() ? kExitOk : kExitUsage;
    }
    try {
        if (!args.config.empty()) config.pipeline = pipeline::LoadPipelineConfig(args.config);
    } catch (const InputError& e) {
        std::fprintf(stderr, "driftcorr: %s\n", e.what());
        return kExitFailed;
    }
    const std::vector<eval::ScenarioEvaluation> evals =
        eval::EvaluateScenarios(args.scenarios, config, MakeEvalProgress(args.quiet));
    std::fputs(eval::FormatTable(evals).c_str(), stdout);
    if (!args.report_dir.empty()) {
        try {
            eval::WriteReport(args.report_dir, evals);
            std::printf("wrote      %s/ (summary.md, results.json, plots)\n",
                        args.report_dir.c_str());
        } catch (const std::exception& e) {
            std::fprintf(stderr, "driftcorr: cannot write the report: %s\n", e.what());
            return kExitInternal;
        }
    }
    const bool any_failed =
        std::any_of(evals.begin(), evals.end(),
                    [](const eval::ScenarioEvaluation& e) { return e.AnyFailed(); });
    if (any_failed) {
        std::fprintf(stderr, "driftcorr: %zu of %zu scenario(s) failed (see the table)\n",
                     static_cast<std::size_t>(std::count_if(
                         evals.begin(), evals.end(),
                         [](const eval::ScenarioEvaluation& e) { return e.AnyFailed(); })),
                     evals.size());
    }
    if (any_failed) return kExitFailed;
    // As `correct` does: a verdict `failed` is a result the program cannot vouch for.
    const auto verdict_failed = [](const eval::ScenarioEvaluation& e) {
        return std::any_of(e.methods.begin(), e.methods.end(), [](const eval::MethodResult& m) {
            return m.method == eval::Method::kDriftcorr && m.verdict &&
                   m.verdict->level == VerdictLevel::kFailed;
        });
    };
    const std::size_t judged_failed =
        static_cast<std::size_t>(std::count_if(evals.begin(), evals.end(), verdict_failed));
    if (judged_failed > 0) {
        std::fprintf(stderr, "driftcorr: driftcorr's verdict is failed on %zu of %zu scenario(s)\n",
                     judged_failed, evals.size());
        return kExitSolver;
    }
    return kExitOk;
}

}  // namespace driftcorr::cli
