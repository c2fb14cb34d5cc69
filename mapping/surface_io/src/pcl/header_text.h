// Word-level helpers for the PCD and PLY header checks (PRIVATE to driftcorr_surface_io).
#pragma once

#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace driftcorr::internal {

/// The blank-separated words of `line`.
inline std::vector<std::string> SplitWords(const std::string& line) {
    std::vector<std::string> words;
    std::istringstream in(line);
    for (std::string w; in >> w;) words.push_back(w);
    return words;
}

/// `s` as a whole number (decimal digits only, at most 18 of them) no larger than `max`; false
/// for anything else.
inline bool ParseWholeNumber(const std::string& s, unsigned long long max,
                             unsigned long long& value) {
    if (s.empty() || s.size() > 18 || s.find_first_not_of("0123456789") != std::string::npos) {
        return false;
    }
    value = std::strtoull(s.c_str(), nullptr, 10);
    return value <= max;
}

}  // namespace driftcorr::internal
