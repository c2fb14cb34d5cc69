#pragma once
// One TUM pose line ("t x y z qx qy qz qw"), for streams read line by line.
#include <string>
#include <string_view>

#include "driftcorr/core/types.h"

namespace driftcorr::io {

struct TumLine {
    enum class Kind { kPose, kSkip, kError };
    Kind kind = Kind::kError;  ///< kSkip: blank line or '#' comment
    std::string error;         ///< kError: why, e.g. "expected 8 numbers, found 3 fields"
    double t_s = 0.0;
    Eigen::Vector3d p_frame = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q_frame_body = Eigen::Quaterniond::Identity();  ///< normalised
};

/// Parses one line (without its newline). Errors: wrong field count, a field that is not a
/// number, NaN/inf, a zero-norm quaternion. Same rules as ReadTum, per line.
TumLine ParseTumLine(std::string_view line);

/// Timestamps are seconds. Empty when |t_s| is below 1e10 s (the year 2286 as Unix time);
/// otherwise what it most likely is, for a message: "looks like nanoseconds (1.6e+18 s is past
/// the year 2286): timestamps are seconds; divide by 1e9". Milliseconds (up to 1e13),
/// microseconds (up to 1e16) and nanoseconds (beyond) are told apart by magnitude.
std::string ImplausibleTimestamp(double t_s);

/// Formats a pose as WriteTum does (timestamps and positions with 6 decimals, the quaternion with
/// 9: the characters printf's %.6f and %.9f give), with a trailing newline.
std::string FormatTumLine(double t_s, const Eigen::Vector3d& p, const Eigen::Quaterniond& q);
/// The same line into [buf, buf + size); returns its length, or 0 when it does not fit.
std::size_t FormatTumLine(char* buf, std::size_t size, double t_s, const Eigen::Vector3d& p,
                          const Eigen::Quaterniond& q);

}  // namespace driftcorr::io
