// What the subcommands share: option parsing, output paths checked before any work is done.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

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

std::vector<ManifestEntry> ReadManifest(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw InputError(path, 0, "--manifest", "is a folder");
    std::ifstream in(path);
    if (!in) throw InputError(path, 0, "--manifest", "cannot open file");
    const fs::path dir = fs::path(path).parent_path();
    std::vector<ManifestEntry> entries;
    std::string line;
    for (long number = 1; std::getline(in, line); ++number) {
        const std::size_t begin = line.find_first_not_of(" \t\r");
        if (begin == std::string::npos || line[begin] == '#') continue;
        const std::size_t end = line.find_last_not_of(" \t\r");
        const fs::path p(line.substr(begin, end - begin + 1));
        entries.push_back({(p.is_absolute() ? p : dir / p).lexically_normal().string(),
                           path + ":" + std::to_string(number)});
    }
    if (in.bad()) throw InputError(path, 0, "--manifest", "read error");
    if (entries.empty()) throw InputError(path, 0, "--manifest", "names no scenario");
    return entries;
}

void RunOnThreadPool(std::size_t count, int jobs, const std::function<void(std::size_t)>& work) {
    std::atomic<std::size_t> next{0};
    const auto worker = [&] {
        for (std::size_t i = next++; i < count; i = next++) work(i);
    };
    const std::size_t threads = std::min<std::size_t>(count, std::max(1, jobs));
    std::vector<std::thread> pool;
    for (std::size_t t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();  // the calling thread is one of the workers
    for (std::thread& t : pool) t.join();
}

}  // namespace driftcorr::cli
