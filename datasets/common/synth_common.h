#pragma once
// What the synthetic scenario generators (synth_road, synth_building) share: the random sources,
// 2D rotation, command-line parsing and atomic file writing.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace driftcorr::synth {

/// Standard normal samples by the Box-Muller transform on std::mt19937_64 (bit-identical for a
/// seed on every platform with IEEE doubles and a correctly rounded libm).
class NormalSampler {
public:
    explicit NormalSampler(std::uint64_t seed) : engine_(seed) {}
    double Next();

private:
    double Uniform01();  ///< in (0, 1], never 0 (so log() is finite)
    std::mt19937_64 engine_;
    double spare_ = 0.0;
    bool has_spare_ = false;
};

/// Uniform numbers from std::mt19937_64 converted by hand (the <random> distributions differ
/// between standard libraries; this is bit-identical for a seed everywhere). `stream` separates
/// independent uses of one seed, so that drawing more numbers for one never changes another.
class UniformSampler {
public:
    UniformSampler(std::uint64_t seed, std::uint64_t stream);
    double Next01();                     ///< in [0, 1)
    double Range(double lo, double hi);  ///< in [lo, hi)
    std::size_t Index(std::size_t n);    ///< in [0, n - 1]; precondition n > 0

private:
    std::mt19937_64 engine_;
};

/// printf-style formatting into a std::string of at most 511 characters (the generators keep the
/// "C" locale, so numbers always use a decimal point). Throws std::logic_error when too long.
#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
std::string
Format(const char* fmt, ...);

/// `v` turned by yaw_rad (counter-clockwise).
Eigen::Vector2d Rotate(double yaw_rad, const Eigen::Vector2d& v);

/// A finite number, the whole text; nullopt otherwise.
std::optional<double> ParseDouble(const char* text);
/// An unsigned 64-bit integer, the whole text, no sign or blanks; nullopt otherwise.
std::optional<std::uint64_t> ParseSeed(const char* text);

/// Applies "--seed N" to `seed` or "--<name> X" to the number registered under that flag; returns
/// an error message naming the flag, empty on success.
std::string ApplySeedOrNumberFlag(const std::string& flag, const char* value, std::uint64_t& seed,
                                  const std::vector<std::pair<const char*, double*>>& numbers);

/// Parses "<out_dir> [--flag value]...": one positional output folder, every flag through
/// `apply_flag` (which returns an error message or ""). Returns an error message, "" on success.
std::string ParseGeneratorArgs(
    int argc, char** argv, std::string& out_dir,
    const std::function<std::string(const std::string& flag, const char* value)>& apply_flag);

/// A generator's main(): -h/--help prints the usage to stdout (exit 0); otherwise `parse`
/// (an error message or "") and `run`; a bad argument prints the error and the usage to stderr
/// (exit 2), an exception from `run` its message (exit 1). Messages start with `name`.
int GeneratorMain(int argc, char** argv, const char* name, void (*print_usage)(std::FILE*),
                  const std::function<std::string(int, char**)>& parse,
                  const std::function<int()>& run);

}  // namespace driftcorr::synth
