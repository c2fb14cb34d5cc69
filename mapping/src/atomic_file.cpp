// Outputs written through a temporary file: renamed over a regular file, copied into a device, a
// FIFO or standard output (atomic_file.h).
#include "driftcorr/mapping/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <streambuf>

namespace driftcorr {
namespace {

namespace fs = std::filesystem;

std::atomic<int> g_counter{0};

std::string Reason(int err) { return err ? std::strerror(err) : "unknown error"; }

/// "-", /dev/stdout, /dev/stderr and /dev/fd/N name a descriptor this process already holds.
std::optional<int> DescriptorOf(const std::string& path) {
    if (path == "-" || path == "/dev/stdout") return STDOUT_FILENO;
    if (path == "/dev/stderr") return STDERR_FILENO;
    for (const char* prefix : {"/dev/fd/", "/proc/self/fd/"}) {
        const std::string p = prefix;
        if (path.rfind(p, 0) == 0 && path.size() > p.size() && path.size() <= p.size() + 4 &&
            path.find_first_not_of("0123456789", p.size()) == std::string::npos) {
            return std::stoi(path.substr(p.size()));
        }
    }
    return std::nullopt;
}

std::string TemporaryPathFor(const OutputTarget& target) {
    const std::string suffix =
        ".tmp." + std::to_string(::getpid()) + "." + std::to_string(g_counter++);
    if (target.kind == OutputTarget::Kind::kFile) return target.path + suffix;
    return (fs::temp_directory_path() / ("driftcorr-output" + suffix)).string();
}

/// Writes all of [data, data + size) to fd; false with errno set on failure.
bool WriteAll(int fd, const char* data, std::size_t size) {
    while (size > 0) {
        const ssize_t put = ::write(fd, data, size);
        if (put < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        if (put == 0) {
            errno = EIO;
            return false;
        }
        data += put;
        size -= static_cast<std::size_t>(put);
    }
    return true;
}

/// Copies the file at `from` into the open descriptor `to`; throws OutputError naming `path`.
void CopyInto(const std::string& from, int to, const std::string& path) {
    const int in = ::open(from.c_str(), O_RDONLY | O_CLOEXEC);
    if (in < 0) throw OutputError(path, "", "cannot read back the temporary " + from);
    char buf[1 << 16];
    for (;;) {
        const ssize_t got = ::read(in, buf, sizeof(buf));
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {
            const int err = errno;
            ::close(in);
            throw OutputError(path, "", "cannot read back the temporary: " + Reason(err));
        }
        if (got == 0) break;
        if (!WriteAll(to, buf, static_cast<std::size_t>(got))) {
            const int err = errno;
            ::close(in);
            throw OutputError(path, "", "write failed: " + Reason(err));
        }
    }
    ::close(in);
}

/// Moves the finished temporary to the target; removes the temporary in every case.
void PutInPlace(const std::string& tmp_path, const OutputTarget& target, const std::string& path) {
    struct Remove {
        const std::string& p;
        ~Remove() { std::remove(p.c_str()); }
    };
    if (target.kind == OutputTarget::Kind::kFile) {
        if (std::rename(tmp_path.c_str(), target.path.c_str()) != 0) {
            const int err = errno;
            std::remove(tmp_path.c_str());
            throw OutputError(path, "",
                              "cannot rename " + tmp_path + " into place: " + Reason(err));
        }
        return;
    }
    const Remove remove{tmp_path};
    if (const std::optional<int> fd = DescriptorOf(target.path)) {
        if (*fd == STDOUT_FILENO && std::fflush(stdout) != 0) {
            throw OutputError(path, "", "write failed: " + Reason(errno));
        }
        if (*fd == STDERR_FILENO) std::fflush(stderr);
        return CopyInto(tmp_path, *fd, path);
    }
    const int fd = ::open(target.path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw OutputError(path, "", "cannot open for writing: " + Reason(errno));
    try {
        CopyInto(tmp_path, fd, path);
    } catch (...) {
        ::close(fd);
        throw;
    }
    if (::close(fd) != 0) throw OutputError(path, "", "write failed: " + Reason(errno));
}

}  // namespace

/// A stream buffer over a file descriptor that remembers the first failed write's errno.
class AtomicFile::Buffer : public std::streambuf {
public:
    explicit Buffer(int fd) : fd_(fd) { setp(buf_, buf_ + sizeof(buf_)); }
    ~Buffer() override {
        if (fd_ >= 0) ::close(fd_);
    }
    /// Flushes and closes; the errno of the first failure, 0 when everything was written.
    int Close() {
        Drain();
        if (fd_ >= 0 && ::close(fd_) != 0 && error_ == 0) error_ = errno;
        fd_ = -1;
        return error_;
    }

protected:
    int_type overflow(int_type ch) override {
        if (!Drain()) return traits_type::eof();
        if (!traits_type::eq_int_type(ch, traits_type::eof())) {
            *pptr() = traits_type::to_char_type(ch);
            pbump(1);
        }
        return traits_type::not_eof(ch);
    }
    int sync() override { return Drain() ? 0 : -1; }

private:
    bool Drain() {
        const std::size_t n = static_cast<std::size_t>(pptr() - pbase());
        setp(buf_, buf_ + sizeof(buf_));
        if (error_ != 0) return false;
        if (n > 0 && !WriteAll(fd_, buf_, n)) error_ = errno ? errno : EIO;
        return error_ == 0;
    }
    int fd_;
    int error_ = 0;
    char buf_[1 << 16];
};

OutputTarget ResolveOutput(const std::string& path) {
    if (DescriptorOf(path)) return {OutputTarget::Kind::kDescriptor, path};
    struct stat link {};
    if (::lstat(path.c_str(), &link) != 0) {
        if (errno == ENOENT) return {OutputTarget::Kind::kFile, path};
        throw OutputError(path, "", "cannot examine the output path: " + Reason(errno));
    }
    struct stat st = link;
    if (S_ISLNK(link.st_mode) && ::stat(path.c_str(), &st) != 0) {
        throw OutputError(path, "",
                          "is a symbolic link to a file that does not exist (" + Reason(errno) +
                              "); give the target's path");
    }
    if (S_ISREG(st.st_mode)) {
        if (!S_ISLNK(link.st_mode)) return {OutputTarget::Kind::kFile, path};
        std::error_code ec;
        const fs::path resolved = fs::canonical(path, ec);
        if (ec) throw OutputError(path, "", "cannot resolve the symbolic link: " + ec.message());
        return {OutputTarget::Kind::kFile, resolved.string()};
    }
    if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return {OutputTarget::Kind::kInPlace, path};
    const char* what = S_ISDIR(st.st_mode)    ? "a folder"
                       : S_ISBLK(st.st_mode)  ? "a block device"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                                              : "not a regular file";
    throw OutputError(path, "", std::string("is ") + what + ", expected an output file path");
}

void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string& tmp_path)>& write) {
    const OutputTarget target = ResolveOutput(path);
    const std::string tmp_path = TemporaryPathFor(target);
    try {
        write(tmp_path);
    } catch (...) {
        std::remove(tmp_path.c_str());
        throw;
    }
    PutInPlace(tmp_path, target, path);
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
    AtomicFile file(path);
    file.stream().write(content.data(), static_cast<std::streamsize>(content.size()));
    file.Commit();
}

AtomicFile::AtomicFile(const std::string& path)
    : path_(path), target_(ResolveOutput(path)), tmp_path_(TemporaryPathFor(target_)) {
    const int fd = ::open(tmp_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) {
        throw OutputError(path, "",
                          "cannot create output file (" + tmp_path_ + "): " + Reason(errno));
    }
    buffer_ = std::make_unique<Buffer>(fd);
    out_ = std::make_unique<std::ostream>(buffer_.get());
}

AtomicFile::~AtomicFile() {
    if (!committed_) {
        out_.reset();
        buffer_.reset();
        std::remove(tmp_path_.c_str());
    }
}

std::ostream& AtomicFile::stream() { return *out_; }

void AtomicFile::Commit() {
    out_->flush();
    const int err = buffer_->Close();
    if (err != 0 || !*out_) {
        std::remove(tmp_path_.c_str());
        committed_ = true;  // nothing left to remove
        throw OutputError(path_, "", "write failed: " + Reason(err));
    }
    committed_ = true;  // PutInPlace removes the temporary whatever happens
    PutInPlace(tmp_path_, target_, path_);
}

}  // namespace driftcorr
