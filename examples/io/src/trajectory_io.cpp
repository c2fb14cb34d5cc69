#include "driftcorr/io/trajectory_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/io/atomic_file.h"
#include "parse_number.h"

namespace driftcorr::io {
namespace {

std::string ReadWholeFile(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        throw InputError(path, 0, "", "is a folder, expected a trajectory file");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "", "cannot open file");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw InputError(path, 0, "", "read error");
    return text;
}

/// Walks the data lines of a text buffer, skipping blank lines and lines starting with '#'.
/// The last line needs no newline.
class DataLines {
public:
    explicit DataLines(std::string_view text) : text_(text) {}

    /// Moves to the next data line; false at the end of the text.
    bool Next() {
        while (pos_ < text_.size()) {
            std::size_t end = text_.find('\n', pos_);
            if (end == std::string_view::npos) end = text_.size();
            line_ = internal::Trim(text_.substr(pos_, end - pos_));
            pos_ = end + 1;
            ++number_;
            if (!line_.empty() && line_.front() != '#') return true;
        }
        return false;
    }
    std::string_view line() const { return line_; }
    long number() const { return number_; }

private:
    std::string_view text_;
    std::size_t pos_ = 0;
    std::string_view line_;
    long number_ = 0;
};

/// Splits `line` at spaces/tabs into `fields` (views into `line`).
void SplitFields(std::string_view line, std::vector<std::string_view>& fields) {
    fields.clear();
    std::size_t pos = 0;
    while (pos < line.size()) {
        const std::size_t begin = line.find_first_not_of(" \t\r", pos);
        if (begin == std::string_view::npos) break;
        std::size_t end = line.find_first_of(" \t\r", begin);
        if (end == std::string_view::npos) end = line.size();
        fields.push_back(line.substr(begin, end - begin));
        pos = end;
    }
}

/// Parses exactly `n` finite numbers from the current line into `out`.
void ParseNumbers(const DataLines& lines, std::size_t n, const std::string& path,
                  std::vector<std::string_view>& fields, double* out) {
    SplitFields(lines.line(), fields);
    if (fields.size() != n) {
        throw InputError(path, lines.number(), "",
                         "expected " + std::to_string(n) + " numbers, found " +
                             std::to_string(fields.size()) + " fields");
    }
    for (std::size_t i = 0; i < n; ++i) {
        const std::optional<double> value = internal::ParseDouble(fields[i]);
        const std::string which = "field " + std::to_string(i + 1) + " '" + std::string(fields[i]);
        if (!value) throw InputError(path, lines.number(), "", which + "' is not a number");
        if (!std::isfinite(*value)) {
            throw InputError(path, lines.number(), "", which + "' is not finite");
        }
        out[i] = *value;
    }
}

void CheckIncreasing(const std::vector<double>& t_s, double t, const std::string& path, long line) {
    if (!t_s.empty() && !(t > t_s.back())) {
        char msg[160];
        std::snprintf(msg, sizeof(msg), "timestamp %.9g does not increase (previous %.9g)", t,
                      t_s.back());
        throw InputError(path, line, "", msg);
    }
}

void CheckMinPoses(std::size_t poses, std::size_t min_poses, const std::string& path) {
    if (poses < min_poses) {
        throw InputError(
            path, 0, "",
            "has " + std::to_string(poses) + " poses, need at least " + std::to_string(min_poses));
    }
}

std::size_t CountLines(const std::string& text) {
    return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1;
}

/// The orientation of a KITTI line's 3x4 matrix (row-major), or an error naming the line when its
/// rotation part is far from a rotation.
Eigen::Quaterniond KittiRotation(const double* v, const std::string& path, long line) {
    Eigen::Matrix3d rot;
    rot << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    const double det = rot.determinant();
    const double ortho_error = (rot.transpose() * rot - Eigen::Matrix3d::Identity()).norm();
    // Written so that NaN fails: entries near 1e200 overflow R^T R and det to inf - inf = NaN,
    // which a "> 0.1" test would let through (Eigen then returns an arbitrary orientation).
    if (!(std::abs(det - 1.0) <= 0.1 && ortho_error <= 0.1)) {
        char msg[160];
        std::snprintf(msg, sizeof(msg),
                      "rotation part is not a rotation matrix (det %.4g, |R^T R - I| %.4g)", det,
                      ortho_error);
        throw InputError(path, line, "", msg);
    }
    return Eigen::Quaterniond(rot).normalized();
}

/// Poses of a KITTI file; timestamps are left empty.
Trajectory ReadKittiPoses(const std::string& path) {
    const std::string text = ReadWholeFile(path);
    Trajectory traj;
    const std::size_t lines_in_file = CountLines(text);
    traj.p_frame.reserve(lines_in_file);
    traj.q_frame_body.reserve(lines_in_file);
    DataLines lines(text);
    std::vector<std::string_view> fields;
    double v[12];
    while (lines.Next()) {
        ParseNumbers(lines, 12, path, fields, v);
        traj.q_frame_body.push_back(KittiRotation(v, path, lines.number()));
        traj.p_frame.emplace_back(v[3], v[7], v[11]);
    }
    return traj;
}

/// One timestamp a line, strictly increasing.
std::vector<double> ReadTimes(const std::string& path) {
    const std::string text = ReadWholeFile(path);
    std::vector<double> t_s;
    t_s.reserve(CountLines(text));
    DataLines lines(text);
    std::vector<std::string_view> fields;
    double t = 0.0;
    while (lines.Next()) {
        ParseNumbers(lines, 1, path, fields, &t);
        CheckIncreasing(t_s, t, path, lines.number());
        t_s.push_back(t);
    }
    return t_s;
}

}  // namespace

Trajectory ReadTum(const std::string& path, std::size_t min_poses) {
    const std::string text = ReadWholeFile(path);
    Trajectory traj;
    traj.t_s.reserve(CountLines(text));
    DataLines lines(text);
    std::vector<std::string_view> fields;
    double v[8];
    while (lines.Next()) {
        ParseNumbers(lines, 8, path, fields, v);
        CheckIncreasing(traj.t_s, v[0], path, lines.number());
        const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // file order: qx qy qz qw
        // stableNorm: q.norm() overflows to inf for components near 1e200, and q / inf is zero.
        const double norm = q.coeffs().stableNorm();
        if (!(norm > 1e-12)) throw InputError(path, lines.number(), "", "quaternion has zero norm");
        traj.t_s.push_back(v[0]);
        traj.p_frame.emplace_back(v[1], v[2], v[3]);
        traj.q_frame_body.emplace_back(q.coeffs() / norm);
    }
    CheckMinPoses(traj.size(), min_poses, path);
    return traj;
}

Trajectory ReadKitti(const std::string& path, const std::optional<std::string>& times_path,
                     std::optional<double> rate_hz, std::size_t min_poses) {
    if (!times_path && !rate_hz) {
        throw InputError(path, 0, "", "a kitti trajectory needs a times file or rate_hz");
    }
    if (!times_path && !(std::isfinite(*rate_hz) && *rate_hz > 0.0)) {
        throw InputError(path, 0, "rate_hz", "must be a positive number");
    }
    Trajectory traj = ReadKittiPoses(path);
    CheckMinPoses(traj.p_frame.size(), min_poses, path);
    if (times_path) {
        traj.t_s = ReadTimes(*times_path);
        if (traj.t_s.size() != traj.p_frame.size()) {
            throw InputError(*times_path, 0, "",
                             "has " + std::to_string(traj.t_s.size()) + " timestamps but " + path +
                                 " has " + std::to_string(traj.p_frame.size()) + " poses");
        }
    } else {
        traj.t_s.resize(traj.p_frame.size());
        for (std::size_t i = 0; i < traj.t_s.size(); ++i) traj.t_s[i] = i / *rate_hz;
        if (!traj.t_s.empty() && !std::isfinite(traj.t_s.back())) {  // rate_hz 1e-320, say
            throw InputError(path, 0, "rate_hz", "is so small that the timestamps overflow");
        }
    }
    return traj;
}

Trajectory LoadTrajectory(const TrajectorySource& source, std::size_t min_poses) {
    if (source.format == TrajectoryFormat::kKitti) {
        return ReadKitti(source.path, source.times_path, source.rate_hz, min_poses);
    }
    return ReadTum(source.path, min_poses);
}

namespace {

/// Rejects trajectories whose arrays disagree in length or hold non-finite values (caller bugs:
/// writing them would produce a file that ReadTum refuses).
void CheckWritable(const std::string& path, const Trajectory& traj) {
    const bool sizes_ok = traj.p_frame.size() == traj.size() &&
                          (!traj.HasOrientation() || traj.q_frame_body.size() == traj.size());
    if (!sizes_ok) throw std::invalid_argument(path + ": trajectory arrays differ in length");
    for (std::size_t i = 0; i < traj.size(); ++i) {
        const bool finite = std::isfinite(traj.t_s[i]) && traj.p_frame[i].allFinite() &&
                            (!traj.HasOrientation() || traj.q_frame_body[i].coeffs().allFinite());
        if (!finite) {
            throw std::invalid_argument(path + ": pose " + std::to_string(i) + " is not finite");
        }
    }
}

}  // namespace

void WriteTum(const std::string& path, const Trajectory& traj) {
    CheckWritable(path, traj);
    AtomicFile file(path);
    std::ofstream& out = file.stream();
    char buf[256];
    for (std::size_t i = 0; i < traj.size(); ++i) {
        const Eigen::Quaterniond q =
            traj.HasOrientation() ? traj.q_frame_body[i] : Eigen::Quaterniond::Identity();
        const Eigen::Vector3d& p = traj.p_frame[i];
        const int n = std::snprintf(buf, sizeof(buf), "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n",
                                    traj.t_s[i], p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w());
        if (n < 0 || n >= static_cast<int>(sizeof(buf))) {
            throw std::runtime_error(path + ": pose " + std::to_string(i) + " does not format");
        }
        out.write(buf, n);
    }
    if (!out) throw std::runtime_error(path + ": write failed");
    file.Commit();
}

}  // namespace driftcorr::io
