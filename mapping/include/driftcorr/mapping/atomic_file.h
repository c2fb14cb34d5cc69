#pragma once
// Every output of the project (trajectories, GeoJSON, reports, surface maps, the synthetic
// scenarios) is written through here, so that a failed write never leaves a partial file, never
// clobbers an existing one, and never replaces what is not a regular file:
//  - a regular file (or a path where nothing is yet): written to a temporary file beside it,
//    "<file>.tmp.<pid>.<n>", renamed over it when complete; a symbolic link is followed, and the
//    file it names is the one replaced (the link stays);
//  - a character device or a named pipe (/dev/null, /dev/stdout, a FIFO): the whole output is
//    written first to a temporary file, then copied into it in place; it is never replaced;
//  - "-": standard output, the same way;
//  - a folder, a block device, a socket or a link to nothing: refused (OutputError) before a
//    byte is written.
// Every write, flush and close is checked; a failure throws OutputError naming the path and the
// system's reason (no space left on device, file too large, ...).
#include <functional>
#include <memory>
#include <ostream>
#include <string>

#include "driftcorr/core/errors.h"

namespace driftcorr {

/// Where an output path leads, decided before anything is written.
struct OutputTarget {
    enum class Kind {
        kFile,        ///< a regular file, or none yet: written atomically (temporary + rename)
        kInPlace,     ///< a character device or FIFO: written in place, never replaced
        kDescriptor,  ///< "-", /dev/stdout, /dev/stderr, /dev/fd/N: a descriptor this process holds
    };
    Kind kind = Kind::kFile;
    /// kFile: the file the rename replaces (a symbolic link resolved to the file it names);
    /// kInPlace: the path as given; kDescriptor: the path as given.
    std::string path;
};

/// Resolves `path` as described at the top of this file. Throws OutputError naming `path` for a
/// folder, a block device, a socket or a symbolic link whose target does not exist.
OutputTarget ResolveOutput(const std::string& path);

/// Calls write(tmp_path), which creates the temporary file (e.g. through a library that takes a
/// path), then puts it at `path` (renamed over a regular file, copied into a device, a FIFO or
/// standard output). When `write` throws or the move fails, the temporary is removed and the
/// error propagates (OutputError naming `path` for a failed rename or copy).
void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string& tmp_path)>& write);

/// Writes `content` to `path` as AtomicFile does. Throws OutputError naming the file.
void WriteFileAtomically(const std::string& path, const std::string& content);

/// A stream to `path` whose content appears there only on Commit().
class AtomicFile {
public:
    /// Resolves `path` (ResolveOutput) and opens the temporary file. Throws OutputError naming
    /// the path if it is refused or the temporary cannot be created.
    explicit AtomicFile(const std::string& path);
    /// Removes the temporary file unless Commit() succeeded.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ostream& stream();
    /// Flushes and closes the temporary, then renames it over the file (or copies it into the
    /// device, FIFO or standard output). Throws OutputError naming the path and the reason.
    void Commit();

private:
    class Buffer;
    std::string path_;
    OutputTarget target_;
    std::string tmp_path_;
    std::unique_ptr<Buffer> buffer_;
    std::unique_ptr<std::ostream> out_;
    bool committed_ = false;
};

}  // namespace driftcorr
