#pragma once
// Helpers the test executables share: a fresh scratch folder per test process (ctest runs every
// test in its own process, hence the process id) and the synthetic road generator.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

namespace driftcorr::test {

/// DRIFTCORR_TEST_TMPDIR/<prefix>_<pid>, emptied and created.
inline std::filesystem::path FreshProcessDir(const std::string& prefix) {
    const std::filesystem::path dir =
        std::filesystem::path(DRIFTCORR_TEST_TMPDIR) / (prefix + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

/// The command that runs the committed road generator into `dir` with `args`, output to /dev/null.
inline std::string RoadGeneratorCommand(const std::filesystem::path& dir, const std::string& args) {
    return std::string(DRIFTCORR_BINARY_DIR) + "/datasets/driftcorr_make_road_scenario \"" +
           dir.string() + "\" " + args + " > /dev/null";
}

/// The whole content of `path` ("" when it cannot be read).
inline std::string ReadFile(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Writes `text` to `path`, replacing it; throws std::runtime_error when it cannot.
inline void WriteFile(const std::filesystem::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out) throw std::runtime_error("test setup: cannot write " + path.string());
}

/// `root`/`name`, emptied (not created).
inline std::string EmptySubdir(const std::filesystem::path& root, const std::string& name) {
    const std::filesystem::path dir = root / name;
    std::filesystem::remove_all(dir);
    return dir.string();
}

/// Runs the road generator into `dir` with `args`; returns the exit status (0 on success).
inline int GenerateRoadScenario(const std::string& dir, const std::string& args) {
    return std::system(RoadGeneratorCommand(dir, args).c_str());
}

}  // namespace driftcorr::test
