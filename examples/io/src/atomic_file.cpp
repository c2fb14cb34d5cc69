#include "driftcorr/io/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <stdexcept>

namespace driftcorr::io {

namespace {
std::atomic<int> g_counter{0};
}

AtomicFile::AtomicFile(const std::string& path) : path_(path) {
    tmp_path_ = path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(g_counter++);
    out_.open(tmp_path_, std::ios::out | std::ios::trunc);
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
    if (std::rename(tmp_path_.c_str(), path_.c_str()) != 0) {
        throw std::runtime_error(path_ + ": cannot rename " + tmp_path_ + " into place");
    }
    committed_ = true;
}

}  // namespace driftcorr::io
