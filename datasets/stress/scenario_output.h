#pragma once
// Reading the input scenario of the stress generator and writing one variant folder: the
// scenario.yaml (re-emitted from the parsed scenario, paths relative to the folder) and every
// file it names, copied byte for byte or rewritten.
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/types.h"
#include "driftcorr/io/scenario.h"

namespace driftcorr::stress {

/// The input scenario, its trajectories and the bytes of every file it names.
struct InputScenario {
    io::Scenario scenario;
    std::vector<std::string> header_comment;  ///< the yaml's leading '#' lines, as written
    Trajectory estimate;
    std::optional<Trajectory> ground_truth;
    std::map<std::string, std::string> file_bytes;  ///< resolved path -> content
};

/// Loads `path` (a folder with scenario.yaml, or a .yaml) and reads every file it names.
/// Throws InputError naming the file for anything unreadable or malformed.
InputScenario LoadInputScenario(const std::string& path);

/// One variant: the input with some parts replaced. What is not replaced is copied.
struct VariantSpec {
    std::string name;                             ///< folder name and `name:` suffix
    std::vector<std::string> description;         ///< header comment lines, without "# "
    io::AnchorSpec anchor;                        ///< written as the variant's anchor
    std::optional<Trajectory> estimate;           ///< rewritten estimate (same format as the input)
    std::optional<Trajectory> ground_truth;       ///< rewritten ground truth (same format)
    std::map<std::size_t, std::string> map_text;  ///< rewritten map layers, by layer index
};

/// A trajectory as the text of a file in `format` (KITTI: 12 numbers a line, %.12e; TUM:
/// t x y z qx qy qz qw, %.9f). Timestamps of a KITTI file stay in its times file / rate_hz.
std::string TrajectoryText(const Trajectory& traj, io::TrajectoryFormat format);

/// The shortest decimal text that reads back as exactly `value`.
std::string ExactNumber(double value);

/// Writes the variant into `dir` (created if needed): first removes an old dir/scenario.yaml,
/// then writes each data file, and scenario.yaml last, each atomically, so the folder is a
/// scenario only once it is complete. `generated_by` are the first header comment lines.
/// Throws std::runtime_error naming the path when a file cannot be written.
void WriteVariant(const InputScenario& input, const VariantSpec& spec,
                  const std::vector<std::string>& generated_by, const std::filesystem::path& dir);

/// How the first header line of every scenario.yaml this generator writes begins (after "# ").
extern const char* const kGeneratedMarker;

}  // namespace driftcorr::stress
