// `driftcorr params`: every params.yaml key at its default, with what it may be and what it does
// (pipeline::ParameterReference, made from the parameter tables).
#include <cstdio>
#include <string>

#include "commands.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::cli {

int RunParamsCommand(int argc, char** argv) {
    const char* usage =
        "usage: driftcorr params\n"
        "\n"
        "Prints every params.yaml section and key at its default, with the allowed values and\n"
        "what it does: a complete parameter file to copy and edit (--config params.yaml).\n";
    std::string err;
    const bool ok = ParseOptions(
        argc, argv, 1, {},
        [](const std::string& arg) { return "unexpected argument '" + arg + "'"; }, err);
    if (!ok) {
        if (err.empty()) {
            std::fputs(usage, stdout);
            return kExitOk;
        }
        std::fprintf(stderr, "driftcorr: %s\n\n%s", err.c_str(), usage);
        return kExitUsage;
    }
    std::fputs(pipeline::ParameterReference().c_str(), stdout);
    return kExitOk;
}

}  // namespace driftcorr::cli
