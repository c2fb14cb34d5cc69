// Output paths of the CLI, checked before any work is done.
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

}  // namespace driftcorr::cli
