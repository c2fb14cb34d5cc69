#pragma once
// Text inputs read whole with bounds: a file that never ends (/dev/zero), a line that never ends
// or a file far larger than its kind can be is refused naming the file (and the line) before the
// program holds more than the bound in memory.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace driftcorr::io {

/// Bounds of one kind of text file.
struct TextLimits {
    std::size_t max_bytes;       ///< the whole file
    std::size_t max_line_bytes;  ///< one line, without its newline
    const char* what;            ///< for messages: "a trajectory file", "a parameter file"
};

/// Trajectory and times files: 2 GiB (about 15 million KITTI poses), lines of 64 KiB.
inline constexpr TextLimits kTrajectoryLimits{std::size_t(2) << 30, std::size_t(64) << 10,
                                              "a trajectory file"};
/// scenario.yaml and params.yaml: 4 MiB, lines of 1 MiB.
inline constexpr TextLimits kScenarioLimits{std::size_t(4) << 20, std::size_t(1) << 20,
                                            "the scenario file"};
inline constexpr TextLimits kParameterLimits{std::size_t(4) << 20, std::size_t(1) << 20,
                                             "the parameter file"};

/// The whole content of `path`. Throws InputError naming the file for a folder, a file that
/// cannot be opened or read, a file over limits.max_bytes, and (with its line number) a line
/// over limits.max_line_bytes; nothing beyond the bound is read.
std::string ReadTextFile(const std::string& path, const TextLimits& limits);

/// The line (1-based) where a second YAML document starts ("---" after content, or a "..." end
/// marker followed by more content), std::nullopt when the text holds one document or none.
std::optional<long> SecondYamlDocumentLine(std::string_view text);

/// yaml-cpp's message for a user: its "bad file" for text it did read means nesting beyond its
/// depth limit (e.g. thousands of '['), said as such; other messages as they are.
std::string YamlParserMessage(const std::string& yaml_cpp_message);

}  // namespace driftcorr::io
