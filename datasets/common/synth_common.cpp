// The definitions of what synth_common.h declares.
#include "synth_common.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <stdexcept>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"

namespace driftcorr::synth {

double NormalSampler::Uniform01() {
    constexpr double kTwoPow53 = 9007199254740992.0;
    return (static_cast<double>(engine_() >> 11) + 1.0) / kTwoPow53;
}

double NormalSampler::Next() {
    if (has_spare_) {
        has_spare_ = false;
        return spare_;
    }
    const double radius = std::sqrt(-2.0 * std::log(Uniform01()));
    const double angle_rad = 2.0 * kPi * Uniform01();
    spare_ = radius * std::sin(angle_rad);
    has_spare_ = true;
    return radius * std::cos(angle_rad);
}

UniformSampler::UniformSampler(std::uint64_t seed, std::uint64_t stream)
    : engine_(seed * 0x9E3779B97F4A7C15ULL + stream) {}

double UniformSampler::Next01() {
    constexpr double kTwoPowMinus53 = 1.0 / 9007199254740992.0;
    return static_cast<double>(engine_() >> 11) * kTwoPowMinus53;
}

double UniformSampler::Range(double lo, double hi) { return lo + (hi - lo) * Next01(); }

std::size_t UniformSampler::Index(std::size_t n) {
    DRIFTCORR_CHECK(n > 0, "UniformSampler::Index: empty range");
    const auto k = static_cast<std::size_t>(Next01() * static_cast<double>(n));
    return std::min(k, n - 1);
}

std::string Format(const char* fmt, ...) {
    char buffer[512];
    va_list args;
    va_start(args, fmt);
    const int n = std::vsnprintf(buffer, sizeof(buffer), fmt, args);
    va_end(args);
    if (n < 0 || n >= static_cast<int>(sizeof(buffer))) throw std::logic_error("Format overflow");
    return std::string(buffer, static_cast<std::size_t>(n));
}

Eigen::Vector2d Rotate(double yaw_rad, const Eigen::Vector2d& v) {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

std::optional<double> ParseDouble(const char* text) {
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(text, &end);
    if (end == text || *end != '\0' || errno != 0 || !std::isfinite(value)) return std::nullopt;
    return value;
}

std::optional<std::uint64_t> ParseSeed(const char* text) {
    if (*text < '0' || *text > '9') return std::nullopt;  // no sign, no blanks
    char* end = nullptr;
    errno = 0;
    const unsigned long long value = std::strtoull(text, &end, 10);
    if (*end != '\0' || errno != 0) return std::nullopt;
    return static_cast<std::uint64_t>(value);
}

std::string ApplySeedOrNumberFlag(const std::string& flag, const char* value, std::uint64_t& seed,
                                  const std::vector<std::pair<const char*, double*>>& numbers) {
    if (flag == "--seed") {
        const auto parsed = ParseSeed(value);
        if (!parsed) return "--seed: not an unsigned integer: " + std::string(value);
        seed = *parsed;
        return "";
    }
    for (const auto& [name, target] : numbers) {
        if (flag != name) continue;
        const auto number = ParseDouble(value);
        if (!number) return flag + ": not a finite number: " + value;
        *target = *number;
        return "";
    }
    return "unknown option: " + flag;
}

std::string ParseGeneratorArgs(
    int argc, char** argv, std::string& out_dir,
    const std::function<std::string(const std::string& flag, const char* value)>& apply_flag) {
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg.empty() || arg[0] != '-') {
            if (!out_dir.empty()) return "more than one output folder: " + arg;
            out_dir = arg;
            continue;
        }
        if (i + 1 >= argc) return arg + ": missing value";
        const std::string error = apply_flag(arg, argv[++i]);
        if (!error.empty()) return error;
    }
    if (out_dir.empty()) return "missing <out_dir>";
    return "";
}

int GeneratorMain(int argc, char** argv, const char* name, void (*print_usage)(std::FILE*),
                  const std::function<std::string(int, char**)>& parse,
                  const std::function<int()>& run) {
    constexpr int kExitFailure = 1, kExitBadArguments = 2;
    if (argc == 2 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0)) {
        print_usage(stdout);
        return 0;
    }
    const std::string error = parse(argc, argv);
    if (!error.empty()) {
        std::fprintf(stderr, "%s: %s\n", name, error.c_str());
        print_usage(stderr);
        return kExitBadArguments;
    }
    try {
        return run();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: %s\n", name, e.what());
        return kExitFailure;
    }
}

}  // namespace driftcorr::synth
