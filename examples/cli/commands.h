#pragma once
// The subcommands of the driftcorr CLI, one source file each; main.cpp only dispatches.
// Each returns the process exit code (0 ok, 1 usage, 2 bad input, 3 solver failure, 4 internal)
// and receives argv with argv[0] = the subcommand name.
namespace driftcorr::cli {

int RunStreamCommand(int argc, char** argv);
int RunEvalCommand(int argc, char** argv);

}  // namespace driftcorr::cli
