#pragma once
// The subcommands of the driftcorr CLI, one source file each; main.cpp only dispatches.
// Each returns the process exit code (0 ok, 1 usage, 2 bad input, 3 solver failure, 4 internal)
// and receives argv with argv[0] = the subcommand name.
#include <string>

namespace driftcorr::cli {

/// Throws InputError (exit 2) unless `path` can be created as an output file: not a folder, in
/// an existing writable folder. Checked before any work is done, so nothing is lost to a typo.
void CheckOutputPath(const std::string& path, const std::string& option);

int RunStreamCommand(int argc, char** argv);
int RunEvalCommand(int argc, char** argv);

}  // namespace driftcorr::cli
