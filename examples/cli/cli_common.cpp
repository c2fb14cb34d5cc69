// What the subcommands share: option parsing, output paths checked before any work is done.
#include <unistd.h>

#include <filesystem>
#include <string>

#include "commands.h"
#include "driftcorr/core/errors.h"

namespace driftcorr::cli {

// An output path must be creatable before any work is done: an existing folder, a missing or
// read-only parent folder are bad input (exit 2), not an internal error after the correction.
void CheckOutputPath(const std::string& path, const std::string& option) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        throw InputError(path, 0, option, "is a folder, expected an output file path");
    }
    const fs::path parent = fs::path(path).parent_path();
    const std::string dir = parent.empty() ? "." : parent.string();
    if (!fs::is_directory(dir, ec)) {
        throw InputError(path, 0, option, "folder '" + dir + "' does not exist");
    }
    if (::access(dir.c_str(), W_OK) != 0) {
        throw InputError(path, 0, option, "folder '" + dir + "' is not writable");
    }
}

bool ParseOptions(int argc, char** argv, int first, const OptionTable& table,
                  const std::function<std::string(const std::string& arg)>& positional,
                  std::string& err) {
    for (int i = first; i < argc; ++i) {
        const std::string arg = argv[i];
        if (auto s = table.switches.find(arg); s != table.switches.end()) {
            *s->second = true;
        } else if (auto v = table.values.find(arg); v != table.values.end()) {
            if (i + 1 >= argc) {
                err = arg + " needs a value";
                return false;
            }
            *v->second = argv[++i];
        } else if (arg == "-h" || arg == "--help") {
            err = "";
            return false;
        } else if (!arg.empty() && arg[0] == '-') {
            err = "unknown option " + arg;
            return false;
        } else if (err = positional(arg); !err.empty()) {
            return false;
        }
    }
    return true;
}

}  // namespace driftcorr::cli
