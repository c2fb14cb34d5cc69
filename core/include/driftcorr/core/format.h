#pragma once
// Number formatting for messages in result structs (the library does no I/O of its own).
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace driftcorr {

/// `value` with a fixed number of decimals, e.g. FormatFixed(3.14159, 2) == "3.14".
inline std::string FormatFixed(double value, int decimals) {
    std::ostringstream out;
    out << std::fixed << std::setprecision(decimals) << value;
    return out.str();
}

/// A share in [0, 1] as a rounded percentage, e.g. FormatPercent(0.314) == "31 %".
inline std::string FormatPercent(double share) {
    return std::to_string(int(std::lround(100.0 * share))) + " %";
}

}  // namespace driftcorr
