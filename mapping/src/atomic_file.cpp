#include "driftcorr/mapping/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <stdexcept>

namespace driftcorr {
namespace {

std::atomic<int> g_counter{0};

std::string TemporaryPathFor(const std::string& path) {
    return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(g_counter++);
}

void RenameInto(const std::string& tmp_path, const std::string& path) {
    if (std::rename(tmp_path.c_str(), path.c_str()) != 0) {
        std::remove(tmp_path.c_str());
        throw std::runtime_error(path + ": cannot rename " + tmp_path + " into place");
    }
}

}  // namespace

void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string& tmp_path)>& write) {
    const std::string tmp_path = TemporaryPathFor(path);
    try {
        write(tmp_path);
    } catch (...) {
        std::remove(tmp_path.c_str());
        throw;
    }
    RenameInto(tmp_path, path);
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
    AtomicFile file(path);
    file.stream().write(content.data(), static_cast<std::streamsize>(content.size()));
    file.Commit();
}

AtomicFile::AtomicFile(const std::string& path) : path_(path), tmp_path_(TemporaryPathFor(path)) {
    out_.open(tmp_path_, std::ios::out | std::ios::binary | std::ios::trunc);
    if (!out_) throw std::runtime_error(path + ": cannot create output file (" + tmp_path_ + ")");
}

AtomicFile::~AtomicFile() {
    if (!committed_) {
        if (out_.is_open()) out_.close();
        std::remove(tmp_path_.c_str());
    }
}

void AtomicFile::Commit() {
    out_.flush();
    const bool ok = static_cast<bool>(out_);
    out_.close();
    if (!ok || out_.fail()) throw std::runtime_error(path_ + ": write failed");
    RenameInto(tmp_path_, path_);
    committed_ = true;
}

}  // namespace driftcorr
