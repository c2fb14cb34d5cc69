// The definitions of what driftcorr/io/trajectory_io.h declares.
#include "driftcorr/io/trajectory_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/io/text_file.h"
#include "driftcorr/io/tum_line.h"
#include "driftcorr/mapping/atomic_file.h"
#include "parse_number.h"

namespace driftcorr::io {
namespace {

std::string ReadWholeFile(const std::string& path) { return ReadTextFile(path, kTrajectoryLimits); }

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
        if (!value || !std::isfinite(*value)) {
            const std::string which =
                "field " + std::to_string(i + 1) + " '" + std::string(fields[i]);
            throw InputError(path, lines.number(), "",
                             which + (value ? "' is not finite" : "' is not a number"));
        }
        out[i] = *value;
    }
}

void CheckIncreasing(const std::vector<double>& t_s, double t, const std::string& path, long line) {
    if (const std::string unit = ImplausibleTimestamp(t); !unit.empty()) {
        throw InputError(path, line, "", unit);
    }
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

/// Poses of a KITTI file; timestamps are left empty. A file whose first line has 13 numbers
/// starts each line with its frame index (as trackers that skip frames where they were lost or
/// initialising write it): `frames` then receives the indices, whole numbers that increase.
Trajectory ReadKittiPoses(const std::string& path, std::vector<std::size_t>& frames) {
    const std::string text = ReadWholeFile(path);
    Trajectory traj;
    const std::size_t lines_in_file = CountLines(text);
    traj.p_frame.reserve(lines_in_file);
    traj.q_frame_body.reserve(lines_in_file);
    DataLines lines(text);
    std::vector<std::string_view> fields;
    double v[13];
    std::size_t columns = 0;  // 12, or 13 with a frame index: the first data line decides
    frames.clear();
    while (lines.Next()) {
        if (columns == 0) {
            SplitFields(lines.line(), fields);
            columns = fields.size() == 13 ? 13 : 12;
        }
        ParseNumbers(lines, columns, path, fields, v);
        const double* m = v + (columns - 12);
        if (columns == 13) {
            const double f = v[0];
            if (!(f >= 0.0 && f < 1e9 && f == std::floor(f)) ||
                (!frames.empty() && !(f > double(frames.back())))) {
                throw InputError(path, lines.number(), "",
                                 "field 1 (a frame index, the line having 13 numbers) must be a "
                                 "whole number above the previous line's");
            }
            frames.push_back(std::size_t(f));
        }
        traj.q_frame_body.push_back(KittiRotation(m, path, lines.number()));
        traj.p_frame.emplace_back(m[3], m[7], m[11]);
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
    std::size_t columns = 0;  // 8, or 4 for positions only: the first data line decides
    while (lines.Next()) {
        if (columns == 0) {
            SplitFields(lines.line(), fields);
            columns = fields.size() == 4 ? 4 : 8;
        }
        ParseNumbers(lines, columns, path, fields, v);
        CheckIncreasing(traj.t_s, v[0], path, lines.number());
        traj.t_s.push_back(v[0]);
        traj.p_frame.emplace_back(v[1], v[2], v[3]);
        if (columns == 4) continue;
        const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // file order: qx qy qz qw
        // stableNorm: q.norm() overflows to inf for components near 1e200, and q / inf is zero.
        const double norm = q.coeffs().stableNorm();
        if (!(norm > 1e-12)) throw InputError(path, lines.number(), "", "quaternion has zero norm");
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
    std::vector<std::size_t> frames;
    Trajectory traj = ReadKittiPoses(path, frames);
    CheckMinPoses(traj.p_frame.size(), min_poses, path);
    if (times_path) {
        const std::vector<double> times = ReadTimes(*times_path);
        if (!frames.empty()) {  // the times file lists every frame, the poses only some
            if (frames.back() >= times.size()) {
                throw InputError(*times_path, 0, "",
                                 "has " + std::to_string(times.size()) + " timestamps but " + path +
                                     " names frame " + std::to_string(frames.back()));
            }
            for (std::size_t f : frames) traj.t_s.push_back(times[f]);
        } else {
            traj.t_s = times;
        }
        if (traj.t_s.size() != traj.p_frame.size()) {
            throw InputError(*times_path, 0, "",
                             "has " + std::to_string(traj.t_s.size()) + " timestamps but " + path +
                                 " has " + std::to_string(traj.p_frame.size()) + " poses");
        }
    } else {
        traj.t_s.resize(traj.p_frame.size());
        for (std::size_t i = 0; i < traj.t_s.size(); ++i) {
            traj.t_s[i] = double(frames.empty() ? i : frames[i]) / *rate_hz;
        }
        if (!traj.t_s.empty() && !std::isfinite(traj.t_s.back())) {  // rate_hz 1e-320, say
            throw InputError(path, 0, "rate_hz", "is so small that the timestamps overflow");
        }
    }
    return traj;
}

namespace {

/// The columns of a CSV trajectory, found by name in its header line.
struct CsvColumns {
    std::size_t count = 0;  ///< fields a line must have
    std::size_t t = 0;
    double t_scale = 1.0;                         ///< to seconds: 1 or 1e-9
    std::size_t p[3] = {0, 0, 0};                 ///< x y z
    std::optional<std::array<std::size_t, 4>> q;  ///< qx qy qz qw, when all four are there
    bool euroc = false;
};

/// A header name as matched: without '#', spaces and a trailing unit "[...]", lower case; the
/// unit (without brackets) goes to `unit`.
std::string NormaliseColumn(std::string_view field, std::string& unit) {
    field = internal::Trim(field);
    if (!field.empty() && field.front() == '#') field.remove_prefix(1);
    unit.clear();
    if (const std::size_t open = field.find('['); open != std::string_view::npos) {
        const std::size_t close = field.find(']', open);
        unit = std::string(field.substr(
            open + 1, close == std::string_view::npos ? std::string_view::npos : close - open - 1));
        field = field.substr(0, open);
    }
    std::string name(internal::Trim(field));
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return name;
}

std::vector<std::string_view> SplitCommas(std::string_view line) {
    std::vector<std::string_view> fields;
    std::size_t pos = 0;
    for (;;) {
        const std::size_t comma = line.find(',', pos);
        fields.push_back(internal::Trim(line.substr(
            pos, comma == std::string_view::npos ? std::string_view::npos : comma - pos)));
        if (comma == std::string_view::npos) return fields;
        pos = comma + 1;
    }
}

/// Finds the columns named in the header (see ReadCsv in trajectory_io.h).
CsvColumns ParseCsvHeader(std::string_view header, const std::string& path, long line,
                          bool require_euroc) {
    CsvColumns cols;
    const std::vector<std::string_view> fields = SplitCommas(header);
    cols.count = fields.size();
    std::map<std::string, std::size_t> index;
    std::map<std::string, std::string> units;
    std::string unit;
    for (std::size_t i = 0; i < fields.size(); ++i) {
        const std::string name = NormaliseColumn(fields[i], unit);
        if (index.count(name)) throw InputError(path, line, name, "column named twice");
        index[name] = i;
        units[name] = unit;
    }
    const auto find = [&](std::initializer_list<const char*> names) -> std::optional<std::string> {
        for (const char* n : names) {
            if (index.count(n)) return std::string(n);
        }
        return std::nullopt;
    };
    cols.euroc = index.count("p_rs_r_x") > 0;
    if (require_euroc && !cols.euroc) {
        throw InputError(path, line, "",
                         "is not an EuRoC / ASL file: expected the header "
                         "'#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], ...'");
    }
    const char* const* pos_names;
    static const char* const kEurocPos[] = {"p_rs_r_x", "p_rs_r_y", "p_rs_r_z"};
    static const char* const kEurocQ[] = {"q_rs_x", "q_rs_y", "q_rs_z", "q_rs_w"};
    static const char* const kPlainQ[] = {"qx", "qy", "qz", "qw"};
    const std::optional<std::string> t =
        find({"timestamp", "t", "time", "t_s", "timestamp_s", "t_ns", "timestamp_ns"});
    if (!t) {
        throw InputError(path, line, "",
                         "header has no time column (t, time, timestamp, t_s, "
                         "timestamp_s, t_ns or timestamp_ns)");
    }
    cols.t = index[*t];
    // EuRoC / ASL stamps are nanoseconds whether or not the header says "[ns]".
    const bool ns_name = t->size() > 3 && t->substr(t->size() - 3) == "_ns";
    const bool ns = cols.euroc || units[*t] == "ns" || ns_name;
    if (!ns && !units[*t].empty() && units[*t] != "s") {
        throw InputError(path, line, *t, "time unit '" + units[*t] + "' (expected s or ns)");
    }
    cols.t_scale = ns ? 1e-9 : 1.0;
    static const char* const kPlainPos[] = {"x", "y", "z"};
    static const char* const kTPos[] = {"tx", "ty", "tz"};
    pos_names = cols.euroc ? kEurocPos : (index.count("x") ? kPlainPos : kTPos);
    for (int k = 0; k < 3; ++k) {
        if (!index.count(pos_names[k])) {
            throw InputError(path, line, "",
                             std::string("header has no position column '") + pos_names[k] +
                                 "' (x y z, or tx ty tz)");
        }
        cols.p[k] = index[pos_names[k]];
    }
    const char* const* q_names = cols.euroc ? kEurocQ : kPlainQ;
    int q_found = 0;
    std::array<std::size_t, 4> q{};
    for (int k = 0; k < 4; ++k) {
        if (index.count(q_names[k])) q[k] = index[q_names[k]], ++q_found;
    }
    if (q_found == 4) cols.q = q;
    if (q_found != 0 && q_found != 4) {
        throw InputError(path, line, "", "header names some quaternion columns but not all four");
    }
    return cols;
}

/// The time of one CSV line in seconds. Nanosecond stamps are read as integers first: a double
/// holds EuRoC's 19-digit stamps only to ~256 ns, an integer exactly.
std::optional<double> CsvTime(std::string_view field, double scale) {
    if (scale != 1.0) {
        std::int64_t ns = 0;
        const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), ns);
        if (ec == std::errc() && ptr == field.data() + field.size()) {
            return static_cast<double>(ns / 1000000000) +
                   static_cast<double>(ns % 1000000000) * 1e-9;
        }
    }
    const std::optional<double> t = internal::ParseDouble(field);
    return t ? std::optional<double>(*t * scale) : std::nullopt;
}

double CsvNumber(const std::vector<std::string_view>& fields, std::size_t i,
                 const std::string& path, long line) {
    const std::optional<double> v = internal::ParseDouble(fields[i]);
    const std::string which =
        "field " + std::to_string(i + 1) + " '" + std::string(fields[i]) + "'";
    if (!v) throw InputError(path, line, "", which + " is not a number");
    if (!std::isfinite(*v)) throw InputError(path, line, "", which + " is not finite");
    return *v;
}

}  // namespace

Trajectory ReadCsv(const std::string& path, bool require_euroc, std::size_t min_poses) {
    const std::string text = ReadWholeFile(path);
    // The header is the first non-blank line, '#' or not (EuRoC's starts with "#timestamp").
    std::string_view rest = text;
    long header_number = 0;
    std::string_view header;
    while (!rest.empty()) {
        const std::size_t end = std::min(rest.find('\n'), rest.size());
        ++header_number;
        header = internal::Trim(rest.substr(0, end));
        rest.remove_prefix(std::min(end + 1, rest.size()));
        if (!header.empty()) break;
    }
    if (header.empty()) throw InputError(path, 0, "", "empty file, expected a CSV header line");
    const CsvColumns cols = ParseCsvHeader(header, path, header_number, require_euroc);
    Trajectory traj;
    DataLines lines(text);
    bool have_line = lines.Next();
    while (have_line && lines.number() <= header_number) have_line = lines.Next();
    if (!have_line) {  // no data line after the header
        CheckMinPoses(0, min_poses, path);
        return traj;
    }
    do {
        const std::vector<std::string_view> fields = SplitCommas(lines.line());
        if (fields.size() != cols.count) {
            throw InputError(path, lines.number(), "",
                             "expected " + std::to_string(cols.count) +
                                 " comma-separated fields "
                                 "(as in the header), found " +
                                 std::to_string(fields.size()));
        }
        const std::optional<double> t = CsvTime(fields[cols.t], cols.t_scale);
        if (!t || !std::isfinite(*t)) {
            throw InputError(path, lines.number(), "",
                             "field " + std::to_string(cols.t + 1) + " '" +
                                 std::string(fields[cols.t]) + "' is not a finite time");
        }
        CheckIncreasing(traj.t_s, *t, path, lines.number());
        traj.t_s.push_back(*t);
        Eigen::Vector3d p;
        for (int k = 0; k < 3; ++k) p[k] = CsvNumber(fields, cols.p[k], path, lines.number());
        traj.p_frame.push_back(p);
        if (!cols.q) continue;
        double q[4];
        for (int k = 0; k < 4; ++k) q[k] = CsvNumber(fields, (*cols.q)[k], path, lines.number());
        const Eigen::Quaterniond quat(q[3], q[0], q[1], q[2]);
        const double norm = quat.coeffs().stableNorm();
        if (!(norm > 1e-12)) throw InputError(path, lines.number(), "", "quaternion has zero norm");
        traj.q_frame_body.emplace_back(quat.coeffs() / norm);
    } while (lines.Next());
    CheckMinPoses(traj.size(), min_poses, path);
    return traj;
}

Trajectory LoadTrajectory(const TrajectorySource& source, std::size_t min_poses) {
    switch (source.format) {
        case TrajectoryFormat::kKitti:
            return ReadKitti(source.path, source.times_path, source.rate_hz, min_poses);
        case TrajectoryFormat::kCsv:
            return ReadCsv(source.path, false, min_poses);
        case TrajectoryFormat::kEuroc:
            return ReadCsv(source.path, true, min_poses);
        case TrajectoryFormat::kTum:
            break;
    }
    return ReadTum(source.path, min_poses);
}

std::optional<TrajectoryFormat> DetectTrajectoryFormat(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".tum") return TrajectoryFormat::kTum;
    if (ext != ".csv") return std::nullopt;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line) && internal::Trim(line).empty()) {
    }
    std::transform(line.begin(), line.end(), line.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return line.find("p_rs_r_x") != std::string::npos ? TrajectoryFormat::kEuroc
                                                      : TrajectoryFormat::kCsv;
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
    std::ostream& out = file.stream();
    char buf[256];
    for (std::size_t i = 0; i < traj.size(); ++i) {
        const Eigen::Quaterniond q =
            traj.HasOrientation() ? traj.q_frame_body[i] : Eigen::Quaterniond::Identity();
        const Eigen::Vector3d& p = traj.p_frame[i];
        const std::size_t n = FormatTumLine(buf, sizeof(buf), traj.t_s[i], p, q);
        if (n == 0) {
            throw std::runtime_error(path + ": pose " + std::to_string(i) + " does not format");
        }
        out.write(buf, static_cast<std::streamsize>(n));
    }
    if (!out) throw std::runtime_error(path + ": write failed");
    file.Commit();
}

}  // namespace driftcorr::io
