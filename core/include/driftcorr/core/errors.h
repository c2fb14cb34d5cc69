#pragma once
// Tier-2 errors: bad external input (files, config, command line). The message names the file,
// and the line and/or key when known, so the CLI can print it as one clear line.
#include <stdexcept>
#include <string>

namespace driftcorr {

class InputError : public std::runtime_error {
public:
    /// `line` <= 0 means "no line"; an empty `key` means "no key".
    InputError(const std::string& file, long line, const std::string& key,
               const std::string& message)
        : std::runtime_error(Format(file, line, key, message)),
          file_(file),
          line_(line),
          key_(key),
          message_(message) {}

    const std::string& file() const { return file_; }
    long line() const { return line_; }
    const std::string& key() const { return key_; }
    /// What is wrong, without the file, line and key.
    const std::string& message() const { return message_; }

private:
    static std::string Format(const std::string& file, long line, const std::string& key,
                              const std::string& message) {
        std::string out = file.empty() ? std::string("<input>") : file;
        if (line > 0) out += ":" + std::to_string(line);
        if (!key.empty()) out += ": " + key;
        return out + ": " + message;
    }
    std::string file_;
    long line_;
    std::string key_;
    std::string message_;
};

/// An output that could not be written: a full disk, a size limit, a path that must not be
/// replaced (a folder, a device, an input of the same run). Like bad input, it names the file and
/// the reason; the CLI reports it as one line and exits with code 2.
class OutputError : public InputError {
public:
    OutputError(const std::string& file, const std::string& key, const std::string& message)
        : InputError(file, 0, key, message) {}
};

}  // namespace driftcorr
