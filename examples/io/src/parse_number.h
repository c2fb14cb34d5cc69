#pragma once
// Number parsing shared by the io readers (internal to driftcorr_io, not installed).
#include <charconv>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

namespace driftcorr::io::internal {

/// Parses the whole of `text` as a double (decimal or exponent form, optional sign). Returns
/// std::nullopt when `text` is empty or holds anything else, e.g. "1.0abc" or "1,5". "nan" and
/// "inf" do parse: callers check std::isfinite and report non-finite values themselves.
inline std::optional<double> ParseDouble(std::string_view text) {
    if (text.size() > 1 && text.front() == '+' && text[1] != '-' && text[1] != '+') {
        text.remove_prefix(1);  // from_chars does not take a leading '+'
    }
    if (text.empty()) return std::nullopt;
    double value = 0.0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (ptr != end) return std::nullopt;
    if (ec == std::errc::result_out_of_range) {
        // Overflow (inf, rejected by the caller's finiteness check) or underflow (tiny, kept).
        return std::strtod(std::string(text).c_str(), nullptr);
    }
    if (ec != std::errc()) return std::nullopt;
    return value;
}

/// `text` without leading and trailing spaces, tabs and carriage returns.
inline std::string_view Trim(std::string_view text) {
    const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
    while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
    while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
    return text;
}

}  // namespace driftcorr::io::internal
