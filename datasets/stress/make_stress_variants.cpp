// driftcorr_make_stress_variants: writes stress variants of a scenario (one complete scenario
// folder per variant: clean, drop_steps, heading_bias_*, yaw_off_*, anchor_off_20m,
// road_removed). See datasets/README.md, "Stress variants".
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/errors.h"
#include "scenario_output.h"
#include "synth_common.h"
#include "variants.h"

namespace driftcorr::stress {
namespace {

namespace fs = std::filesystem;

constexpr const char* kName = "driftcorr_make_stress_variants";
constexpr int kExitBadInput = 2;

struct Options {
    std::string input;
    std::string out_dir;
    StressConfig config;
};

void PrintUsage(std::FILE* stream) {
    std::fprintf(
        stream,
        "usage: driftcorr_make_stress_variants <scenario dir or scenario.yaml> <out_dir> "
        "[--seed N]\n"
        "  Writes one scenario folder per variant into <out_dir>/<variant>/: clean, drop_steps,\n"
        "  heading_bias_0.1, heading_bias_0.3, heading_bias_0.5, yaw_off_10, yaw_off_20,\n"
        "  yaw_off_30, anchor_off_20m, road_removed. A variant that cannot be made is skipped\n"
        "  with a message.\n"
        "  --seed N   seed of the drop_steps episodes, the anchor_off direction and the\n"
        "             monocular scale walk, unsigned 64-bit (default %llu)\n"
        "  --monocular G1,G2,...  write only monocular variants instead: mono_<G> (the estimate's\n"
        "             steps scaled by G times a random walk, the anchor as given) and\n"
        "             mono_<G>_auto (the same with `scale: auto` in the anchor)\n"
        "  --monocular-drift X    that walk's spread per sqrt(100 m) of path (default %g)\n",
        static_cast<unsigned long long>(StressConfig().seed),
        StressConfig().monocular_drift_per_100m);
}

// "0.05,0.1,0.2": positive numbers, comma-separated.
std::string ParseScales(const std::string& text, std::vector<double>& scales) {
    scales.clear();
    std::size_t begin = 0;
    while (begin <= text.size()) {
        const std::size_t end = std::min(text.find(',', begin), text.size());
        const std::string item = text.substr(begin, end - begin);
        const std::optional<double> v = synth::ParseDouble(item.c_str());
        if (!v || !(*v > 0.0)) {
            return "--monocular: expected positive scales separated by commas, got '" + text + "'";
        }
        scales.push_back(*v);
        begin = end + 1;
    }
    return "";
}

std::string ParseArgs(int argc, char** argv, Options& opt) {
    std::vector<std::string> positional;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg.empty() || arg[0] != '-') {
            positional.push_back(arg);
            continue;
        }
        if (i + 1 >= argc) return arg + ": missing value";
        if (arg == "--monocular") {
            const std::string error = ParseScales(argv[++i], opt.config.monocular_scales);
            if (!error.empty()) return error;
            continue;
        }
        const std::string error = synth::ApplySeedOrNumberFlag(
            arg, argv[++i], opt.config.seed,
            {{"--monocular-drift", &opt.config.monocular_drift_per_100m}});
        if (!error.empty()) return error;
    }
    if (positional.size() != 2) {
        return "expected <scenario dir or scenario.yaml> and <out_dir>, got " +
               std::to_string(positional.size()) + " positional arguments";
    }
    opt.input = positional[0];
    opt.out_dir = positional[1];
    if (!(opt.config.monocular_drift_per_100m >= 0.0)) {
        return "--monocular-drift: must be >= 0";
    }
    return opt.config.drop.Validate();
}

// The --monocular flags that made the variants ("" for the default set).
std::string MonocularFlags(const StressConfig& c) {
    if (c.monocular_scales.empty()) return "";
    std::string flags = " --monocular ";
    for (std::size_t k = 0; k < c.monocular_scales.size(); ++k) {
        flags += (k ? "," : "") + ExactNumber(c.monocular_scales[k]);
    }
    return flags + " --monocular-drift " + ExactNumber(c.monocular_drift_per_100m);
}

std::vector<std::string> GeneratedBy(const Options& opt, const InputScenario& input,
                                     const std::string& variant) {
    return {std::string(kGeneratedMarker) +
                " (driftcorr repository, datasets/stress); do not edit, regenerate instead.",
            "input: " + input.scenario.yaml_path + " (scenario '" + input.scenario.name + "')",
            "variant: " + variant + "; seed " + std::to_string(opt.config.seed),
            "regenerate: driftcorr_make_stress_variants " + input.scenario.yaml_path +
                " <out_dir> --seed " + std::to_string(opt.config.seed) +
                MonocularFlags(opt.config)};
}

/// A skipped variant must not leave an earlier run's scenario behind under its name: removes
/// dir/scenario.yaml when this generator wrote it.
void RemoveStaleVariant(const fs::path& dir) {
    const fs::path yaml = dir / "scenario.yaml";
    std::ifstream in(yaml);
    std::string first_line;
    if (!in || !std::getline(in, first_line)) return;
    if (first_line.rfind(std::string("# ") + kGeneratedMarker, 0) != 0) return;
    in.close();
    fs::remove(yaml);
    std::printf("  (removed %s of an earlier run)\n", yaml.string().c_str());
}

int Run(const Options& opt) {
    InputScenario input;
    std::vector<VariantOutcome> variants;
    try {
        input = LoadInputScenario(opt.input);
        variants = MakeVariants(input, opt.config);
    } catch (const InputError& e) {
        std::fprintf(stderr, "%s: %s\n", kName, e.what());
        return kExitBadInput;
    }
    std::size_t written = 0;
    for (const VariantOutcome& v : variants) {
        const fs::path dir = fs::path(opt.out_dir) / v.name;
        if (!v.spec) {
            std::printf("skipped %-17s %s\n", v.name.c_str(), v.note.c_str());
            RemoveStaleVariant(dir);
            continue;
        }
        WriteVariant(input, *v.spec, GeneratedBy(opt, input, v.name), dir);
        std::printf("wrote   %-17s %s\n", v.name.c_str(), v.note.c_str());
        ++written;
    }
    std::printf("%s: %zu of %zu variants of '%s' written to %s (seed %llu)\n", kName, written,
                variants.size(), input.scenario.name.c_str(), opt.out_dir.c_str(),
                static_cast<unsigned long long>(opt.config.seed));
    return 0;
}

}  // namespace
}  // namespace driftcorr::stress

int main(int argc, char** argv) {
    using namespace driftcorr::stress;
    Options opt;
    return driftcorr::synth::GeneratorMain(
        argc, argv, kName, PrintUsage,
        [&opt](int n, char** args) { return ParseArgs(n, args, opt); },
        [&opt] { return Run(opt); });
}
