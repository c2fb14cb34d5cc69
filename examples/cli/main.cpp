// driftcorr command-line tool: dispatches to the subcommands (commands.h, one source file each).
//
// Exit codes: 0 success, 1 usage error, 2 bad input (file, line, key named), 3 the solver did not
// produce a usable correction (nothing written), 4 internal error.
#include <cstdio>
#include <cstring>

#include "commands.h"

namespace {

const char* kAbout =
    "driftcorr removes the drift from a trajectory using the map of the place.\n"
    "\n"
    "commands:\n"
    "  correct   batch correction of a scenario, of a trajectory file on an OpenStreetMap file\n"
    "            (XML or PBF), or of many scenarios on a pool of threads (-j N)\n"
    "  stream    online correction, pose by pose (driftcorr stream -h)\n"
    "  eval      the estimate, the paper's method and driftcorr against ground truth\n"
    "            (driftcorr eval -h)\n"
    "  params    every params.yaml key at its default, with its allowed values\n"
    "  map       the walkable surface of a raw 3D map of a building (driftcorr map -h)\n"
    "\n";
const char* kOtherUsage =
    "       driftcorr eval <scenario dirs...> [-o report_dir] [--config params.yaml] [--quiet]\n"
    "       driftcorr stream <scenario dir | scenario.yaml> [--replay] [--rate-hz R] [--sync]\n"
    "                        [--config params.yaml] [--smoothed-out smoothed.tum]\n"
    "       driftcorr params\n"
    "       driftcorr map extract <raw .pcd | .ply | .bt | .ot> -o walkable.pcd [--lifts ...]\n";

struct Command {
    const char* name;
    int (*run)(int argc, char** argv);
};
const Command kCommands[] = {
    {"correct", &driftcorr::cli::RunCorrectCommand}, {"eval", &driftcorr::cli::RunEvalCommand},
    {"stream", &driftcorr::cli::RunStreamCommand},   {"params", &driftcorr::cli::RunParamsCommand},
    {"map", &driftcorr::cli::RunMapCommand},
};

void PrintUsage(std::FILE* out) {
    driftcorr::cli::PrintCorrectUsage(out);
    std::fputs("\n", out);
    std::fputs(kOtherUsage, out);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc >= 2 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
                      std::strcmp(argv[1], "help") == 0)) {
        std::fputs(kAbout, stdout);
        PrintUsage(stdout);
        return driftcorr::cli::kExitOk;
    }
    if (argc >= 2) {
        for (const Command& c : kCommands) {
            if (std::strcmp(argv[1], c.name) == 0) return c.run(argc - 1, argv + 1);
        }
    }
    std::fprintf(
        stderr, "driftcorr: %s\n\n",
        argc < 2 ? "missing command" : ("unknown command '" + std::string(argv[1]) + "'").c_str());
    PrintUsage(stderr);
    return driftcorr::cli::kExitUsage;
}
