#pragma once
// Outputs are written to a temporary file beside the target and renamed when complete, so a
// failed run never leaves a partial file and never clobbers an existing one.
#include <fstream>
#include <string>

namespace driftcorr::io {

class AtomicFile {
public:
    /// Opens "<path>.tmp.<pid>.<n>" in the target's directory. Throws std::runtime_error naming
    /// the path if it cannot be created.
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

}  // namespace driftcorr::io
