#pragma once
// Every output of the project (trajectories, GeoJSON, reports, surface maps, the synthetic
// scenarios) is written to a temporary file beside the target and renamed over it when complete,
// so a failed write never leaves a partial file and never clobbers an existing one. The temporary
// is "<path>.tmp.<pid>.<n>", unique per process and call.
#include <fstream>
#include <functional>
#include <string>

namespace driftcorr {

/// Calls write(tmp_path), which creates the temporary file (e.g. through a library that takes a
/// path), then renames it over `path`. When `write` throws or the rename fails, the temporary is
/// removed and the error propagates (a failed rename: std::runtime_error naming `path`).
void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string& tmp_path)>& write);

/// Writes `content` to `path` atomically. Throws std::runtime_error naming the file.
void WriteFileAtomically(const std::string& path, const std::string& content);

/// A stream to `path` that appears there only on Commit().
class AtomicFile {
public:
    /// Opens the temporary file. Throws std::runtime_error naming the path if it cannot be
    /// created.
    explicit AtomicFile(const std::string& path);
    /// Removes the temporary file unless Commit() succeeded.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ofstream& stream() { return out_; }
    /// Flushes, closes and renames over `path`. Throws std::runtime_error on failure.
    void Commit();

private:
    std::string path_;
    std::string tmp_path_;
    std::ofstream out_;
    bool committed_ = false;
};

}  // namespace driftcorr
