// driftcorr command-line tool: dispatches to the subcommands (commands.h, one source file each).
//
// Exit codes: 0 success, 1 usage error, 2 bad input (file, line, key named), 3 the solver did not
// produce a usable correction (nothing written), 4 internal error.
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#if defined(__GLIBC__)  // (set by the headers above)
#include <malloc.h>
#endif

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
    "  params    every params.yaml key at its default, with its allowed values, or those of\n"
    "            the model and corrector at a preset (driftcorr params -h)\n"
    "  map       the walkable surface of a raw 3D map of a building (driftcorr map -h)\n"
    "driftcorr --version prints the version.\n"
    "\n";
const char* kOtherUsage =
    "       driftcorr eval <scenario dirs...> [-o report_dir] [--config params.yaml] [--quiet]\n"
    "       driftcorr stream <scenario dir | scenario.yaml> [--replay] [--rate-hz R] [--sync]\n"
    "                        [--config params.yaml] [--smoothed-out smoothed.tum]\n"
    "       driftcorr params [--preset road|pedestrian]\n"
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

/// Flushes standard output and says whether everything printed there arrived (a full disk or a
/// closed pipe behind it loses the summary and the verdict: that is an error, not a success).
int CheckStandardOutput(int code) {
    errno = 0;
    const bool flushed = std::fflush(stdout) == 0;
    const int err = errno;
    if (flushed && !std::ferror(stdout)) return code;
    std::fprintf(stderr,
                 "driftcorr: standard output: write failed (%s): what was printed there "
                 "(the summary, the verdict, the poses) is lost\n",
                 err ? std::strerror(err) : "an earlier write failed");
    return code == driftcorr::cli::kExitOk ? driftcorr::cli::kExitBadInput : code;
}

namespace {

// The windows, final solves and covariance allocate and free blocks of up to tens of MB, over
// and over. glibc maps each block above its mmap threshold afresh and unmaps it on free, and
// every first touch of a mapped page is a page fault. Blocks up to 32 MB (the largest threshold
// glibc takes) come from the heap instead, and up to 64 MB of freed heap is kept for the next
// solve rather than returned.
void KeepFreedMemoryForReuse() {
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
    mallopt(M_TRIM_THRESHOLD, 64 * 1024 * 1024);
#endif
}

}  // namespace

int main(int argc, char** argv) {
    KeepFreedMemoryForReuse();
    // A file-size limit (ulimit -f) makes write() fail with EFBIG, reported with the file's name,
    // instead of killing the process by SIGXFSZ with nothing said.
    std::signal(SIGXFSZ, SIG_IGN);
    if (argc >= 2 && std::strcmp(argv[1], "--version") == 0) {
        std::printf("driftcorr %s\n", DRIFTCORR_VERSION);
        return CheckStandardOutput(driftcorr::cli::kExitOk);
    }
    if (argc >= 2 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
                      std::strcmp(argv[1], "help") == 0)) {
        std::fputs(kAbout, stdout);
        PrintUsage(stdout);
        return CheckStandardOutput(driftcorr::cli::kExitOk);
    }
    if (argc >= 2) {
        for (const Command& c : kCommands) {
            if (std::strcmp(argv[1], c.name) == 0) {
                return CheckStandardOutput(c.run(argc - 1, argv + 1));
            }
        }
    }
    std::fprintf(
        stderr, "driftcorr: %s\n\n",
        argc < 2 ? "missing command" : ("unknown command '" + std::string(argv[1]) + "'").c_str());
    PrintUsage(stderr);
    return driftcorr::cli::kExitUsage;
}
