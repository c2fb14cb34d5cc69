#pragma once
// The subcommands of the driftcorr CLI, one source file each; main.cpp only dispatches.
// Each returns the process exit code (0 ok, 1 usage, 2 bad input, 3 solver failure, 4 internal)
// and receives argv with argv[0] = the subcommand name.
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/io/scenario.h"

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

/// printf into a string (any length).
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// `text` as a finite number, all of it (no trailing characters); nullopt otherwise.
std::optional<double> ParseFiniteNumber(const std::string& text);

/// Runs a subcommand's work and turns what it throws into its exit code and one line on stderr,
/// "<who>: <message>": InputError is bad input (2), anything else an internal error (4).
int RunReportingErrors(const char* who, const std::function<int()>& work);

/// Throws InputError (exit 2) unless `path` can be created as an output file: not a folder, in
/// an existing writable folder. Checked before any work is done, so nothing is lost to a typo.
void CheckOutputPath(const std::string& path, const std::string& option);

/// An output file of one run and the option that named it ("-o", "--geojson").
struct NamedOutput {
    std::string option;
    std::string path;
};

/// Throws OutputError (exit 2) naming the option when an output is one of `inputs` (the same
/// file however it is spelled: "..", a symbolic link, a hard link), when two outputs that are
/// files would be the same file, or when an output is refused by ResolveOutput (a folder, a block
/// device, a socket, a link to nothing). Called before any work, so that no input is overwritten
/// and no work is lost to a typo. Outputs that are devices, FIFOs or "-" may be shared.
void CheckOutputsAgainstInputs(const std::vector<NamedOutput>& outputs,
                               const std::vector<io::InputFile>& inputs);

/// For runs of one batch: throws OutputError (exit 2) naming the option when an output of run i
/// is an input of another run j (the same file however it is spelled), so that no run replaces
/// what a later one reads. Each run's outputs against its own inputs are for
/// CheckOutputsAgainstInputs. Time linear in the files (one stat each).
void CheckOutputsAgainstOtherRunsInputs(const std::vector<std::vector<NamedOutput>>& outputs,
                                        const std::vector<std::vector<io::InputFile>>& inputs);

/// One scenario path of a manifest, with where it was named (for messages).
struct ManifestEntry {
    std::string path;   ///< resolved against the manifest's folder when relative
    std::string where;  ///< "manifest.txt:3"
};

/// Reads a manifest: one scenario path a line (a folder or a .yaml), relative paths resolved
/// against the manifest's folder; blank lines and lines starting with '#' are skipped. Throws
/// InputError naming the manifest when it cannot be read or names no scenario. Whether each path
/// is a scenario is found out when it runs (a bad line fails alone).
std::vector<ManifestEntry> ReadManifest(const std::string& path);

/// What one item of RunInProcesses reports: a few lines of text and an exit code.
struct ProcessOutcome {
    int code = 0;
    std::string text;
};

/// Runs work(i) for i in [0, count), each in a child process of its own (fork), at most `jobs`
/// at a time, and calls done(i, outcome) in the parent as each one ends (code -1 and a note if
/// it died by a signal). Processes, not threads: Ipopt 3.11's linear solver MUMPS is not
/// thread-safe, so threads in one process take turns in every Ipopt solve (a final solve with an
/// active corridor constraint; optim/ipopt_solver.h), and a crash stays with its item. Call it
/// while the process has no other threads; `work` must not throw. Throws std::runtime_error when a
/// process cannot be started.
void RunInProcesses(std::size_t count, int jobs,
                    const std::function<ProcessOutcome(std::size_t)>& work,
                    const std::function<void(std::size_t, const ProcessOutcome&)>& done);

int RunCorrectCommand(int argc, char** argv);
int RunStreamCommand(int argc, char** argv);
int RunEvalCommand(int argc, char** argv);
int RunParamsCommand(int argc, char** argv);
int RunMapCommand(int argc, char** argv);
/// The usage text of `correct` (driftcorr --help prints it).
void PrintCorrectUsage(std::FILE* out);

}  // namespace driftcorr::cli
