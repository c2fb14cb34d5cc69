#pragma once
// The subcommands of the driftcorr CLI, one source file each; main.cpp only dispatches.
// Each returns the process exit code (0 ok, 1 usage, 2 bad input, 3 solver failure, 4 internal)
// and receives argv with argv[0] = the subcommand name.
#include <functional>
#include <map>
#include <string>

namespace driftcorr::cli {

constexpr int kExitOk = 0, kExitUsage = 1, kExitBadInput = 2, kExitSolver = 3, kExitInternal = 4;

/// The options of one subcommand: switches (no value) and options with one value, each under
/// every spelling ("-o" and "--output" pointing at the same string).
struct OptionTable {
    std::map<std::string, bool*> switches;
    std::map<std::string, std::string*> values;
};

/// Walks argv[first, argc): table options, "-h"/"--help", and positional arguments handed to
/// `positional` (which returns an error message or ""). Returns false with `err` set on a bad
/// argument, false with `err` empty for help.
bool ParseOptions(int argc, char** argv, int first, const OptionTable& table,
                  const std::function<std::string(const std::string& arg)>& positional,
                  std::string& err);

/// Throws InputError (exit 2) unless `path` can be created as an output file: not a folder, in
/// an existing writable folder. Checked before any work is done, so nothing is lost to a typo.
void CheckOutputPath(const std::string& path, const std::string& option);

int RunStreamCommand(int argc, char** argv);
int RunEvalCommand(int argc, char** argv);

}  // namespace driftcorr::cli
