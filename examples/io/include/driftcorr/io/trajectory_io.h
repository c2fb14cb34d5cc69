#pragma once
// Trajectory files: TUM ("t x y z qx qy qz qw" a line, or positions only "t x y z"), KITTI (12
// numbers a line, 3x4 row-major T_world_cam, with timestamps from a times file or i / rate_hz) and
// CSV with a header line (EuRoC / ASL among them).
#include <optional>
#include <string>

#include "driftcorr/core/types.h"
#include "driftcorr/io/scenario.h"

namespace driftcorr::io {

/// Every reader throws InputError(file, line, "", message) for: missing/unreadable file, a line
/// with the wrong number of fields or a field that is not a number, NaN/inf, timestamps that do
/// not strictly increase, a zero-norm quaternion (TUM), a times file whose line count differs from
/// the pose count, fewer than `min_poses` poses. Blank lines and lines starting with '#' are
/// skipped. Quaternions are normalised. TUM: 8 numbers a line, or 4 ("t x y z", positions only: the
/// trajectory has no orientation); the first data line decides and every line must have as many.
Trajectory ReadTum(const std::string& path, std::size_t min_poses = 3);
/// CSV: the first non-blank line is the header, comma-separated column names; each name is
/// matched without a leading '#', surrounding spaces, case and a trailing unit in brackets.
///  - EuRoC / ASL (the header has p_RS_R_x): `#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m],
///    p_RS_R_z [m]` and optionally `q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []`; further columns
///    (velocities, biases) are ignored. Timestamps in nanoseconds (with or without "[ns]").
///  - otherwise: a time column `t`, `time`, `timestamp`, `t_s` or `timestamp_s` (seconds, or
///    nanoseconds with the unit `[ns]` or the names `t_ns`, `timestamp_ns`), positions `x, y, z`
///    (or `tx, ty, tz`) in metres, optionally `qx, qy, qz, qw`; other columns are ignored.
/// Without quaternion columns the trajectory has no orientation. Every data line has as many
/// fields as the header. `require_euroc`: a header without p_RS_R_x is an error.
Trajectory ReadCsv(const std::string& path, bool require_euroc, std::size_t min_poses = 3);
Trajectory ReadKitti(const std::string& path, const std::optional<std::string>& times_path,
                     std::optional<double> rate_hz, std::size_t min_poses = 3);
Trajectory LoadTrajectory(const TrajectorySource& source, std::size_t min_poses = 3);

/// The format of a trajectory file from its name: .tum -> kTum, .csv -> kEuroc when its first
/// line names p_RS_R_x, else kCsv; std::nullopt for anything else (.txt may be TUM or KITTI: the
/// caller must say which). A file that cannot be read is found out by the reader.
std::optional<TrajectoryFormat> DetectTrajectoryFormat(const std::string& path);

/// Writes TUM with full precision (timestamps %.6f, positions %.6f, quaternions %.9f), through an
/// AtomicFile (nothing appears at `path` unless the whole file was written). Throws
/// std::runtime_error naming the path on I/O failure, std::invalid_argument (before anything is
/// written) when the trajectory's arrays differ in length or hold non-finite values.
void WriteTum(const std::string& path, const Trajectory& traj);

}  // namespace driftcorr::io
