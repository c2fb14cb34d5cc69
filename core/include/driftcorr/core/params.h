#pragma once
// Parameter tables: one row per config field, naming its key (the unit in the name, as in
// params.yaml), the member it sets, the allowed range and one line of documentation. The default is
// the member's initialiser, written once in the struct; a row only points at it. Each config
// struct's Validate(), the params.yaml reader (examples/pipeline), its error messages and the
// parameter list in docs/parameters.md are made from the rows, so adding a parameter is its member
// and one row. Header-only and std-only: the YAML walking lives at the edge, in examples/pipeline.
//
//   struct FooConfig { double gap_m = 1.0; };
//   inline constexpr Param<FooConfig> kFooParamRows[] = {
//       {"gap_m", Field<&FooConfig::gap_m>(), kPositive, "largest gap bridged"},
//   };
//   inline constexpr ParamTable<FooConfig> kFooParams{"foo", kFooParamRows};
#include <charconv>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace driftcorr {

/// The value kinds a parameter can have (the type of the member a row points at).
enum class ParamKind {
    kReal,       ///< double
    kSize,       ///< std::size_t (a whole number)
    kInt,        ///< int (a whole number)
    kFlag,       ///< bool
    kChoice,     ///< std::string, one of the row's `choices`
    kRealByName  ///< std::map<std::string, double>: a value per name, each in the row's range
};

/// An interval of allowed values; every number must also be finite.
struct ParamRange {
    double min = -std::numeric_limits<double>::infinity();
    double max = std::numeric_limits<double>::infinity();
    bool min_open = false;  ///< min itself is excluded
    bool max_open = false;  ///< max itself is excluded

    constexpr bool Contains(double v) const {
        return v == v && v > -std::numeric_limits<double>::infinity() &&
               v < std::numeric_limits<double>::infinity() && (min_open ? v > min : v >= min) &&
               (max_open ? v < max : v <= max);
    }
};

inline constexpr double kParamInf = std::numeric_limits<double>::infinity();
inline constexpr ParamRange kFinite{};  ///< any finite number
/// The range of a kFlag or kChoice row: its kind says what is allowed.
inline constexpr ParamRange kNoRange{};
inline constexpr ParamRange kPositive{0.0, kParamInf, true, false};      ///< > 0
inline constexpr ParamRange kNonNegative{0.0, kParamInf, false, false};  ///< >= 0
inline constexpr ParamRange kWeight{0.0, 1.0, true, false};              ///< in (0, 1]
inline constexpr ParamRange kShare{0.0, 1.0, false, false};              ///< in [0, 1]
/// >= lo
constexpr ParamRange AtLeast(double lo) { return {lo, kParamInf, false, false}; }
/// in [lo, hi]
constexpr ParamRange Between(double lo, double hi) { return {lo, hi, false, false}; }

/// Shortest text that reads back as the same double ("0.0087", "1e-06", "240", "1000000").
inline std::string FormatParamNumber(double v) {
    if (v == std::floor(v) && std::fabs(v) < 9007199254740992.0) {
        return std::to_string(static_cast<long long>(v));
    }
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

/// The range as a rule: "> 0", ">= 0", "in (0, 1]", "a finite number".
inline std::string RangeText(const ParamRange& r) {
    const bool low = std::isfinite(r.min), high = std::isfinite(r.max);
    if (low && high) {
        return std::string("in ") + (r.min_open ? "(" : "[") + FormatParamNumber(r.min) + ", " +
               FormatParamNumber(r.max) + (r.max_open ? ")" : "]");
    }
    if (low) return (r.min_open ? "> " : ">= ") + FormatParamNumber(r.min);
    if (high) return (r.max_open ? "< " : "<= ") + FormatParamNumber(r.max);
    return "a finite number";
}

/// Where a row's value lives in its config struct: the kind and a function that returns the
/// member's address. Made by Field<&Config::member>() or, for a member of a member,
/// Field<&Config::sub, &Sub::member>().
template <class Config>
struct ParamAccess {
    ParamKind kind = ParamKind::kReal;
    void* (*address)(Config&) = nullptr;
};

namespace params_detail {

template <class T>
struct ClassOf;
template <class C, class M>
struct ClassOf<M C::*> {
    using type = C;
};

template <class T>
constexpr ParamKind KindOf() {
    if constexpr (std::is_same_v<T, double>)
        return ParamKind::kReal;
    else if constexpr (std::is_same_v<T, std::size_t>)
        return ParamKind::kSize;
    else if constexpr (std::is_same_v<T, int>)
        return ParamKind::kInt;
    else if constexpr (std::is_same_v<T, bool>)
        return ParamKind::kFlag;
    else if constexpr (std::is_same_v<T, std::string>)
        return ParamKind::kChoice;
    else if constexpr (std::is_same_v<T, std::map<std::string, double>>)
        return ParamKind::kRealByName;
    else
        static_assert(sizeof(T) == 0, "no ParamKind for this member type");
}

template <class Config, auto... Path>
auto& Follow(Config& c) {
    // clang-format off
    return (c .* ... .* Path);  // c.*first.*second...: the member, through nested members
    // clang-format on
}

template <class Config, auto... Path>
void* Address(Config& c) {
    return &Follow<Config, Path...>(c);
}

}  // namespace params_detail

template <auto First, auto... Rest>
constexpr auto Field() {
    using Config = typename params_detail::ClassOf<decltype(First)>::type;
    using Member = std::remove_reference_t<decltype(params_detail::Follow<Config, First, Rest...>(
        std::declval<Config&>()))>;
    return ParamAccess<Config>{params_detail::KindOf<Member>(),
                               &params_detail::Address<Config, First, Rest...>};
}

/// One parameter: its key as written in params.yaml (unit in the name), where it lives, what it
/// may be, and one line of documentation.
template <class Config>
struct Param {
    const char* key;
    ParamAccess<Config> access;
    ParamRange range = kFinite;  ///< kReal, kSize, kInt, kRealByName (each value)
    const char* doc = "";
    const char* choices = "";  ///< kChoice: the allowed values, separated by '|'

    ParamKind kind() const { return access.kind; }
    template <class T>
    T& Ref(Config& c) const {
        return *static_cast<T*>(access.address(c));
    }
    template <class T>
    const T& Ref(const Config& c) const {
        return *static_cast<const T*>(access.address(const_cast<Config&>(c)));
    }
};

/// The rows of one config struct and the params.yaml section it is read from by default (the
/// prefix of the keys Validate() names; the pipeline reads some structs under other sections too).
template <class Config>
struct ParamTable {
    const char* section;
    const Param<Config>* rows;
    std::size_t count;

    template <std::size_t N>
    constexpr ParamTable(const char* section_name, const Param<Config> (&table)[N])
        : section(section_name), rows(table), count(N) {}
    const Param<Config>* begin() const { return rows; }
    const Param<Config>* end() const { return rows + count; }
    const Param<Config>* Find(const std::string& key) const {
        for (const Param<Config>& p : *this) {
            if (key == p.key) return &p;
        }
        return nullptr;
    }
};

/// A value that breaks a rule. `key` is relative to the struct's table ("resolution_m"; a value
/// of a kRealByName row: "half_width_m.track"); `related_key` names the other key of a rule
/// between two values ("chunk_m" for "window_m: must be >= chunk_m"), empty otherwise.
struct ParamProblem {
    std::string key;
    std::string message;  ///< "must be > 0 (got -1)"
    std::string related_key;
};

/// A rule between two values that `key` = v breaks: `key` must be `op` (">=" or "<=") `other`
/// = w; the message reads "must be >= chunk_m (got 200 < 240)".
inline ParamProblem RelationProblem(const std::string& key, double v, const std::string& op,
                                    const std::string& other, double w) {
    const std::string negated = op == ">=" ? "<" : op == "<=" ? ">" : "not " + op;
    return {key,
            "must be " + op + " " + other + " (got " + FormatParamNumber(v) + " " + negated + " " +
                FormatParamNumber(w) + ")",
            other};
}

/// "<section>.<key>: <message>", the form Validate() returns; empty without a problem.
inline std::string ToMessage(const std::string& section,
                             const std::optional<ParamProblem>& problem) {
    if (!problem) return "";
    return (section.empty() ? "" : section + ".") + problem->key + ": " + problem->message;
}

/// The allowed range of a whole-number row: the row's range, at least 0.
template <class Config>
ParamRange WholeRange(const Param<Config>& p) {
    ParamRange r = p.range;
    if (r.min < 0.0 || (r.min == 0.0 && r.min_open)) r = {0.0, r.max, false, r.max_open};
    return r;
}

/// True when whole number `v` fits the row's member type (2^digits is the first that does not;
/// casting a double at or above it is undefined behaviour).
template <class Config>
bool FitsMember(const Param<Config>& p, double v) {
    const int digits = p.kind() == ParamKind::kInt ? std::numeric_limits<int>::digits
                                                   : std::numeric_limits<std::size_t>::digits;
    return v < std::ldexp(1.0, digits);
}

/// The words of a kChoice row's `choices` ("vehicle|pedestrian|all").
inline std::vector<std::string> ChoiceWords(const char* choices) {
    std::vector<std::string> words(1);
    for (const char* ch = choices; *ch; ++ch) {
        if (*ch == '|')
            words.emplace_back();
        else
            words.back() += *ch;
    }
    return words;
}

/// The rule a number for row `p` must satisfy, e.g. "must be > 0" or "must be a whole number in
/// [1, 1000000]".
template <class Config>
std::string RuleText(const Param<Config>& p) {
    if (p.kind() == ParamKind::kSize || p.kind() == ParamKind::kInt) {
        return "must be a whole number " + RangeText(WholeRange(p));
    }
    if (p.kind() == ParamKind::kFlag) return "must be true or false";
    if (p.kind() == ParamKind::kChoice) {
        const std::vector<std::string> words = ChoiceWords(p.choices);
        std::string text = "must be " + words.front();
        for (std::size_t i = 1; i < words.size(); ++i) {
            text += (i + 1 == words.size() ? " or " : ", ") + words[i];
        }
        return text;
    }
    const ParamRange& r = p.range;
    if (!std::isfinite(r.min) && !std::isfinite(r.max)) return "must be finite";
    return "must be " + RangeText(r);
}

/// The problem with number `v` for row `p` (kReal, kSize, kInt, a kRealByName value), if any.
template <class Config>
std::optional<std::string> NumberProblem(const Param<Config>& p, double v) {
    const bool whole = p.kind() == ParamKind::kSize || p.kind() == ParamKind::kInt;
    const bool ok = whole ? WholeRange(p).Contains(v) && v == std::floor(v) && FitsMember(p, v)
                          : p.range.Contains(v);
    if (ok) return std::nullopt;
    return RuleText(p) + " (got " + FormatParamNumber(v) + ")";
}

/// True when `value` is one of the row's choices.
template <class Config>
bool IsChoice(const Param<Config>& p, const std::string& value) {
    for (const std::string& word : ChoiceWords(p.choices)) {
        if (word == value) return true;
    }
    return false;
}

/// The first value of `c` that its row does not allow, in row order.
template <class Config>
std::optional<ParamProblem> CheckRows(const ParamTable<Config>& table, const Config& c) {
    for (const Param<Config>& p : table) {
        switch (p.kind()) {
            case ParamKind::kReal:
                if (auto m = NumberProblem(p, p.template Ref<double>(c)))
                    return ParamProblem{p.key, *m, ""};
                break;
            case ParamKind::kSize:
                if (auto m = NumberProblem(p, double(p.template Ref<std::size_t>(c))))
                    return ParamProblem{p.key, *m, ""};
                break;
            case ParamKind::kInt:
                if (auto m = NumberProblem(p, double(p.template Ref<int>(c))))
                    return ParamProblem{p.key, *m, ""};
                break;
            case ParamKind::kFlag:
                break;
            case ParamKind::kChoice: {
                const std::string& v = p.template Ref<std::string>(c);
                if (!IsChoice(p, v))
                    return ParamProblem{p.key, RuleText(p) + " (got '" + v + "')", ""};
                break;
            }
            case ParamKind::kRealByName:
                for (const auto& [name, v] : p.template Ref<std::map<std::string, double>>(c)) {
                    if (auto m = NumberProblem(p, v))
                        return ParamProblem{std::string(p.key) + "." + name, *m, ""};
                }
                break;
        }
    }
    return std::nullopt;
}

/// The value of row `p` in `c` as params.yaml writes it ("0.02", "true", "vehicle", "{}").
template <class Config>
std::string FormatParamValue(const Param<Config>& p, const Config& c) {
    switch (p.kind()) {
        case ParamKind::kReal:
            return FormatParamNumber(p.template Ref<double>(c));
        case ParamKind::kSize:
            return std::to_string(p.template Ref<std::size_t>(c));
        case ParamKind::kInt:
            return std::to_string(p.template Ref<int>(c));
        case ParamKind::kFlag:
            return p.template Ref<bool>(c) ? "true" : "false";
        case ParamKind::kChoice:
            return p.template Ref<std::string>(c);
        case ParamKind::kRealByName: {
            std::string out;
            for (const auto& [name, v] : p.template Ref<std::map<std::string, double>>(c)) {
                out += (out.empty() ? "" : ", ") + name + ": " + FormatParamNumber(v);
            }
            return "{" + out + "}";
        }
    }
    return "";
}

}  // namespace driftcorr
