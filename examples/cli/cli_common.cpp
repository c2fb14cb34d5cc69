// What the subcommands share: option parsing, output paths checked before any work is done.
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/atomic_file.h"

namespace driftcorr::cli {

// An output path must be creatable before any work is done: an existing folder, a missing or
// read-only parent folder are bad input (exit 2), not an internal error after the correction.
std::string Format(const char* format, ...) {
    va_list args, again;
    va_start(args, format);
    va_copy(again, args);
    const int n = std::vsnprintf(nullptr, 0, format, args);
    va_end(args);
    std::string out(std::size_t(std::max(n, 0)), '\0');
    std::vsnprintf(out.data(), out.size() + 1, format, again);
    va_end(again);
    return out;
}

std::optional<double> ParseFiniteNumber(const std::string& text) {
    std::size_t used = 0;
    double value = 0.0;
    try {
        value = std::stod(text, &used);
    } catch (const std::exception&) {
        return std::nullopt;
    }
    if (used == 0 || used != text.size() || !std::isfinite(value)) return std::nullopt;
    return value;
}

int RunReportingErrors(const char* who, const std::function<int()>& work) {
    try {
        return work();
    } catch (const InputError& e) {
        std::fprintf(stderr, "%s: %s\n", who, e.what());
        return kExitBadInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: internal error: %s\n", who, e.what());
        return kExitInternal;
    }
}

void CheckOutputPath(const std::string& path, const std::string& option) {
    namespace fs = std::filesystem;
    const OutputTarget target = [&] {
        try {
            return ResolveOutput(path);
        } catch (const OutputError& e) {
            throw OutputError(path, option, e.message());
        }
    }();
    if (target.kind != OutputTarget::Kind::kFile) return;  // written in place: nothing to create
    const fs::path parent = fs::path(target.path).parent_path();
    const std::string dir = parent.empty() ? "." : parent.string();
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) {
        throw InputError(path, 0, option, "folder '" + dir + "' does not exist");
    }
    if (::access(dir.c_str(), W_OK) != 0) {
        throw InputError(path, 0, option, "folder '" + dir + "' is not writable");
    }
}

namespace {

/// A key that two existing paths share exactly when they are the same file (device and inode),
/// and two paths that do not exist when they name the same place once "..", "." and symbolic
/// links of the existing part are resolved; nothing when the path cannot be resolved.
std::optional<std::string> FileIdentity(const std::string& path) {
    namespace fs = std::filesystem;
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0) {
        return "inode " + std::to_string(st.st_dev) + " " + std::to_string(st.st_ino);
    }
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(fs::absolute(path, ec), ec);
    if (ec) return std::nullopt;
    return "path " + canonical.string();
}

/// Whether a and b name the same file: the same inode when both exist, else the same path once
/// "..", "." and symbolic links of the existing part are resolved.
bool SameFile(const std::string& a, const std::string& b) {
    const std::optional<std::string> ia = FileIdentity(a), ib = FileIdentity(b);
    return ia && ib && *ia == *ib;
}

}  // namespace

void CheckOutputsAgainstOtherRunsInputs(const std::vector<std::vector<NamedOutput>>& outputs,
                                        const std::vector<std::vector<io::InputFile>>& inputs) {
    std::map<std::string, std::pair<std::size_t, const io::InputFile*>> owner;  // identity -> run
    for (std::size_t j = 0; j < inputs.size(); ++j) {
        for (const io::InputFile& in : inputs[j]) {
            if (in.path.empty()) continue;
            if (const auto id = FileIdentity(in.path)) owner.emplace(*id, std::make_pair(j, &in));
        }
    }
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        for (const NamedOutput& out : outputs[i]) {
            if (out.path.empty()) continue;
            const auto id = FileIdentity(out.path);
            const auto it = id ? owner.find(*id) : owner.end();
            if (it == owner.end() || it->second.first == i) continue;
            const io::InputFile& in = *it->second.second;
            throw OutputError(out.path, out.option,
                              "is " + in.what + " (" + in.path +
                                  "): writing it would destroy an input; choose another path");
        }
    }
}

void CheckOutputsAgainstInputs(const std::vector<NamedOutput>& outputs,
                               const std::vector<io::InputFile>& inputs) {
    std::vector<std::pair<const NamedOutput*, bool>> files;  // output, is a (future) file
    for (const NamedOutput& out : outputs) {
        if (out.path.empty()) continue;
        const OutputTarget target = ResolveOutput(out.path);  // throws for what it refuses
        for (const io::InputFile& in : inputs) {
            if (!in.path.empty() && SameFile(out.path, in.path)) {
                throw OutputError(out.path, out.option,
                                  "is " + in.what + " (" + in.path +
                                      "): writing it would destroy an input; choose another path");
            }
        }
        files.push_back({&out, target.kind == OutputTarget::Kind::kFile});
    }
    for (std::size_t i = 0; i < files.size(); ++i) {
        for (std::size_t j = 0; j < i; ++j) {
            if (files[i].second && files[j].second &&
                SameFile(files[i].first->path, files[j].first->path)) {
                throw OutputError(files[i].first->path, files[i].first->option,
                                  "is the same file as " + files[j].first->option);
            }
        }
    }
}

bool ParseOptions(int argc, char** argv, int first, const OptionTable& table,
                  const std::function<std::string(const std::string& arg)>& positional,
                  std::string& err) {
    for (int i = first; i < argc; ++i) {
        const std::string arg = argv[i];
        if (auto s = table.switches.find(arg); s != table.switches.end()) {
            *s->second = true;
        } else if (auto v = table.values.find(arg); v != table.values.end()) {
            if (i + 1 >= argc) {
                err = arg + " needs a value";
                return false;
            }
            *v->second = argv[++i];
        } else if (arg == "-h" || arg == "--help") {
            err = "";
            return false;
        } else if (!arg.empty() && arg[0] == '-') {
            err = "unknown option " + arg;
            return false;
        } else if (err = positional(arg); !err.empty()) {
            return false;
        }
    }
    return true;
}

std::vector<ManifestEntry> ReadManifest(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw InputError(path, 0, "--manifest", "is a folder");
    std::ifstream in(path);
    if (!in) throw InputError(path, 0, "--manifest", "cannot open file");
    const fs::path dir = fs::path(path).parent_path();
    std::vector<ManifestEntry> entries;
    std::string line;
    for (long number = 1; std::getline(in, line); ++number) {
        const std::size_t begin = line.find_first_not_of(" \t\r");
        if (begin == std::string::npos || line[begin] == '#') continue;
        const std::size_t end = line.find_last_not_of(" \t\r");
        const fs::path p(line.substr(begin, end - begin + 1));
        entries.push_back({(p.is_absolute() ? p : dir / p).lexically_normal().string(),
                           path + ":" + std::to_string(number)});
    }
    if (in.bad()) throw InputError(path, 0, "--manifest", "read error");
    if (entries.empty()) throw InputError(path, 0, "--manifest", "names no scenario");
    return entries;
}

namespace {

// Reads everything a child writes into fd, then closes it.
std::string Drain(int fd) {
    std::string text;
    char buf[4096];
    for (;;) {
        const ssize_t got = read(fd, buf, sizeof(buf));
        if (got > 0) {
            text.append(buf, static_cast<std::size_t>(got));
        } else if (got == 0 || errno != EINTR) {
            break;
        }
    }
    close(fd);
    return text;
}

}  // namespace

void RunInProcesses(std::size_t count, int jobs,
                    const std::function<ProcessOutcome(std::size_t)>& work,
                    const std::function<void(std::size_t, const ProcessOutcome&)>& done) {
    struct Child {
        std::size_t index;
        int fd;
    };
    std::map<pid_t, Child> running;
    std::size_t next = 0;
    const std::size_t slots = std::min<std::size_t>(count, std::max(1, jobs));
    while (next < count || !running.empty()) {
        if (next < count && running.size() < slots) {
            int fds[2];
            if (pipe(fds) != 0)
                throw std::runtime_error("pipe: " + std::string(std::strerror(errno)));
            std::fflush(nullptr);
            const pid_t pid = fork();
            if (pid < 0) throw std::runtime_error("fork: " + std::string(std::strerror(errno)));
            if (pid == 0) {  // the child: one item, its text into the pipe, its code as exit status
                close(fds[0]);
                const ProcessOutcome o = work(next);
                for (std::size_t off = 0; off < o.text.size();) {
                    const ssize_t put = write(fds[1], o.text.data() + off, o.text.size() - off);
                    if (put <= 0 && errno != EINTR) break;
                    if (put > 0) off += static_cast<std::size_t>(put);
                }
                close(fds[1]);
                std::fflush(nullptr);
                _exit(o.code);
            }
            close(fds[1]);
            running[pid] = {next++, fds[0]};
            continue;
        }
        // Every slot busy (or nothing left to start): collect the next child to finish. Its
        // output is small (a few lines), within the pipe's buffer, so it never blocks the child.
        int status = 0;
        const pid_t pid = waitpid(-1, &status, 0);
        if (pid < 0) {
            if (errno == EINTR) continue;
            throw std::runtime_error("waitpid: " + std::string(std::strerror(errno)));
        }
        const auto it = running.find(pid);
        if (it == running.end()) continue;
        ProcessOutcome o;
        o.text = Drain(it->second.fd);
        if (WIFEXITED(status)) {
            o.code = WEXITSTATUS(status);
        } else {
            o.code = -1;
            o.text += "    (the process ended by signal " +
                      std::to_string(WIFSIGNALED(status) ? WTERMSIG(status) : 0) + ")\n";
        }
        done(it->second.index, o);
        running.erase(it);
    }
}

}  // namespace driftcorr::cli
