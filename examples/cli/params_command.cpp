// `driftcorr params`: every params.yaml key at its default, with what it may be and what it does
// (pipeline::ParameterReference, made from the parameter tables); `--preset NAME`: the sections
// model and corrector at a corrector preset (pipeline::CorrectorReference).
#include <algorithm>
#include <cstdio>
#include <iterator>
#include <string>

#include "commands.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::cli {
namespace {

/// The corrector presets --preset names: road is the members' initialisers.
struct Preset {
    const char* name;
    CorrectorConfig (*make)();
};
const Preset kPresets[] = {
    {"road", [] { return CorrectorConfig{}; }},
    {"pedestrian", &CorrectorConfig::Pedestrian},
};

/// The preset names joined by `sep`, the last two by `last_sep`: "road or pedestrian".
std::string PresetNames(const char* sep, const char* last_sep) {
    std::string names;
    const std::size_t n = std::size(kPresets);
    for (std::size_t i = 0; i < n; ++i) {
        names += (i == 0 ? "" : i + 1 == n ? last_sep : sep) + std::string(kPresets[i].name);
    }
    return names;
}

const char* kAbout =
    "Prints every params.yaml section and key at its default, with the allowed values and\n"
    "what it does: a complete parameter file to copy and edit (--config params.yaml).\n"
    "--preset prints the sections model and corrector (road2d's) at a corrector preset\n"
    "instead: road, their defaults; pedestrian, CorrectorConfig::Pedestrian(), the defaults\n"
    "of indoor_model and indoor_corrector (its start scales and covariance are no keys).\n";

const Preset* FindPreset(const std::string& name) {
    for (const Preset& p : kPresets) {
        if (name == p.name) return &p;
    }
    return nullptr;
}

}  // namespace

int RunParamsCommand(int argc, char** argv) {
    const std::string usage =
        "usage: driftcorr params [--preset " + PresetNames("|", "|") + "]\n\n" + kAbout;
    std::string preset, err;
    const bool ok = ParseOptions(
        argc, argv, 1, {{}, {{"--preset", &preset}}},
        [](const std::string& arg) { return "unexpected argument '" + arg + "'"; }, err);
    const bool given = std::find(argv + 1, argv + argc, std::string("--preset")) != argv + argc;
    const Preset* chosen = FindPreset(preset);
    if (ok && given && !chosen) {
        err = "--preset must be " + PresetNames(", ", " or ") + ", not '" + preset + "'";
    }
    if (!ok || !err.empty()) {
        if (err.empty()) {
            std::fputs(usage.c_str(), stdout);
            return kExitOk;
        }
        std::fprintf(stderr, "driftcorr: %s\n\n%s", err.c_str(), usage.c_str());
        return kExitUsage;
    }
    if (!chosen) {
        std::fputs(pipeline::ParameterReference().c_str(), stdout);
        return kExitOk;
    }
    std::printf("# driftcorr params --preset %s\n", chosen->name);
    std::fputs(pipeline::CorrectorReference(chosen->make()).c_str(), stdout);
    return kExitOk;
}

}  // namespace driftcorr::cli
