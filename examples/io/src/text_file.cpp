// Whole text files read within bounds (text_file.h).
#include "driftcorr/io/text_file.h"

#include <cstring>
#include <filesystem>
#include <fstream>

#include "driftcorr/core/errors.h"

namespace driftcorr::io {
namespace {

std::string Mebibytes(std::size_t bytes) {
    return bytes >= (std::size_t(1) << 20) ? std::to_string(bytes >> 20) + " MiB"
                                           : std::to_string(bytes >> 10) + " KiB";
}

}  // namespace

std::string ReadTextFile(const std::string& path, const TextLimits& limits) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        throw InputError(path, 0, "",
                         std::string("is a folder, not a file (expected ") + limits.what + ")");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "", "cannot open file");
    std::string text;
    std::size_t line_bytes = 0;  // of the line being read so far
    long line = 1;
    char chunk[1 << 16];
    while (in) {
        in.read(chunk, sizeof(chunk));
        const std::size_t got = static_cast<std::size_t>(in.gcount());
        if (got == 0) break;
        if (text.size() + got > limits.max_bytes) {
            throw InputError(path, 0, "",
                             "larger than " + Mebibytes(limits.max_bytes) + ", the most " +
                                 limits.what + " may hold; is it the right file?");
        }
        for (const char* p = chunk; p < chunk + got;) {
            const char* nl = static_cast<const char*>(std::memchr(p, '\n', chunk + got - p));
            const std::size_t run = static_cast<std::size_t>((nl ? nl : chunk + got) - p);
            if (line_bytes + run > limits.max_line_bytes) {
                throw InputError(path, line, "",
                                 "line longer than " + Mebibytes(limits.max_line_bytes) +
                                     ", the most " + limits.what +
                                     " may have; is it the right "
                                     "file?");
            }
            if (!nl) {
                line_bytes += run;
                break;
            }
            line_bytes = 0;
            ++line;
            p = nl + 1;
        }
        text.append(chunk, got);
    }
    if (in.bad()) throw InputError(path, 0, "", "read error");
    return text;
}

std::optional<long> SecondYamlDocumentLine(std::string_view text) {
    bool content = false, ended = false;
    long number = 0;
    for (std::size_t pos = 0; pos < text.size();) {
        std::size_t end = text.find('\n', pos);
        if (end == std::string_view::npos) end = text.size();
        std::string_view line = text.substr(pos, end - pos);
        pos = end + 1;
        ++number;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        const bool marker_start =
            line.substr(0, 3) == "---" && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
        const bool marker_end =
            line.substr(0, 3) == "..." && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
        const std::size_t first = line.find_first_not_of(" \t");
        const bool blank = first == std::string_view::npos || line[first] == '#';
        if (marker_start) {
            if (content || ended) return number;
            content = true;  // an explicit start: what follows belongs to the first document
            continue;
        }
        if (marker_end) {
            ended = content;
            continue;
        }
        if (blank || line[0] == '%') continue;  // comments, blank lines, directives
        if (ended) return number;
        content = true;
    }
    return std::nullopt;
}

std::string YamlParserMessage(const std::string& yaml_cpp_message) {
    if (yaml_cpp_message == "bad file") {
        return "nested too deeply for the YAML parser (brackets or indentation thousands of levels "
               "deep); is it the right file?";
    }
    return yaml_cpp_message;
}

}  // namespace driftcorr::io
