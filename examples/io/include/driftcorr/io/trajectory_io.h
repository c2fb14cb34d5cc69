#pragma once
// Trajectory files: TUM ("t x y z qx qy qz qw" a line) and KITTI (12 numbers a line, 3x4
// row-major T_world_cam, with timestamps from a times file or i / rate_hz).
#include <optional>
#include <string>

#include "driftcorr/core/types.h"
#include "driftcorr/io/scenario.h"

namespace driftcorr::io {

/// Every reader throws InputError(file, line, "", message) for: missing/unreadable file, a line
/// with the wrong number of fields or a field that is not a number, NaN/inf, timestamps that do
/// not strictly increase, a zero-norm quaternion (TUM), a times file whose line count differs from
/// the pose count, fewer than `min_poses` poses. Blank lines and lines starting with '#' are skipped.
/// Quaternions are normalised.
Trajectory ReadTum(const std::string& path, std::size_t min_poses = 3);
Trajectory ReadKitti(const std::string& path, const std::optional<std::string>& times_path,
                     std::optional<double> rate_hz, std::size_t min_poses = 3);
Trajectory LoadTrajectory(const TrajectorySource& source, std::size_t min_poses = 3);

/// Writes TUM with full precision (timestamps %.6f, positions %.6f, quaternions %.9f), through an
/// AtomicFile (nothing appears at `path` unless the whole file was written). Throws
/// std::runtime_error naming the path on I/O failure, std::invalid_argument (before anything is
/// written) when the trajectory's arrays differ in length or hold non-finite values.
void WriteTum(const std::string& path, const Trajectory& traj);

}  // namespace driftcorr::io
