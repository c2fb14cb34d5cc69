// The definitions of what driftcorr/optim/verdict.h declares.
#include "driftcorr/optim/verdict.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"
#include "driftcorr/core/format.h"
#include "driftcorr/core/metrics.h"
#include "driftcorr/core/observables.h"

namespace driftcorr {
namespace {

// Collects findings: the level is the worst one.
class Findings {
public:
    explicit Findings(Verdict& v) : v_(v) {}
    void Degraded(const std::string& why) { Add(VerdictLevel::kDegraded, "degraded: " + why); }
    void Failed(const std::string& why) { Add(VerdictLevel::kFailed, "failed: " + why); }
    /// A finding over `share` of the poses: failed beyond failed_share, else degraded.
    void ByShare(double share, double failed_share, const std::string& why) {
        if (share > failed_share) {
            Failed(why);
        } else {
            Degraded(why);
        }
    }

private:
    void Add(VerdictLevel level, const std::string& reason) {
        v_.level = std::max(v_.level, level);
        // The worst findings first.
        auto at = level == VerdictLevel::kFailed ? v_.reasons.begin() : v_.reasons.end();
        v_.reasons.insert(at, reason);
    }
    Verdict& v_;
};

void JudgeSolver(const CorrectionResult& r, Findings& f) {
    if (!Usable(r.status)) {
        f.Failed("the solver produced no usable correction (" + ToString(r.status) + ": " +
                 r.message + ")");
        return;
    }
    if (r.input_kept && r.input_nll_lower) {
        f.Degraded(
            "the correction explains the odometry and the map worse than the input does "
            "(NLL " +
            FormatFixed(r.nll, 1) + " against " + FormatFixed(r.input_nll, 1) +
            "): the input is written unchanged, and nothing here vouches for it");
    }
    if (r.refine_report.message.find("without hard constraints") != std::string::npos ||
        r.message.find("without hard constraints") != std::string::npos) {
        f.Failed(
            "the final solve could not keep the drive inside the mapped corridors and was "
            "re-solved without them (" +
            r.message + "): map and odometry disagree");
    }
}

// The step-length scale each stretch of `segment_m` of estimated path implies: corrected path
// length over estimated path length. Flags the poses of implausible stretches.
// step_m: the odometry's step lengths as the model observed them (dropped steps repaired); the
// estimate's own when empty. Stair treads (`tread`, when not empty) count on neither side.
void JudgeScale(const PlanarTrajectory& est, const std::vector<double>& step_m,
                const std::vector<std::uint8_t>& tread, const PlanarTrajectory& cor,
                double segment_m, const VerdictConfig& c, Verdict& v, Findings& f) {
    const bool model_steps = step_m.size() == est.size();
    const bool treads = tread.size() == est.size();
    std::size_t start = 0;
    double est_m = 0.0, cor_m = 0.0;
    v.scale_min = 1e9, v.scale_max = -1e9;
    std::size_t implausible = 0;
    for (std::size_t i = 1; i < est.size(); ++i) {
        if (!(treads && tread[i])) {  // a stair tread's run is not the odometry's scaled
            est_m += model_steps ? step_m[i] : (est.p_en[i] - est.p_en[i - 1]).norm();
            cor_m += (cor.p_en[i] - cor.p_en[i - 1]).norm();
        }
        const bool last = i + 1 == est.size();
        if (est_m < segment_m && !(last && est_m > 0.25 * segment_m)) continue;
        if (est_m >= 0.25 * segment_m) {
            const double ratio = cor_m / est_m;
            v.scale_min = std::min(v.scale_min, ratio);
            v.scale_max = std::max(v.scale_max, ratio);
            if (ratio < c.scale_plausible_min || ratio > c.scale_plausible_max) {
                for (std::size_t k = start; k <= i; ++k) v.pose_flags[k] |= kPoseScaleImplausible;
                implausible += i - start + 1;
            }
        }
        start = i, est_m = 0.0, cor_m = 0.0;
    }
    if (v.scale_min > v.scale_max) {
        v.scale_min = v.scale_max = 1.0;
        return;
    }
    const std::string range = FormatFixed(v.scale_min, 2) + ".." + FormatFixed(v.scale_max, 2);
    if (v.scale_min < c.scale_failed_min || v.scale_max > c.scale_failed_max) {
        // Every part squeezed (or stretched) alike: the estimate's size itself is off, as a
        // monocular tracker's is.
        const bool whole =
            v.scale_max < c.scale_plausible_min || v.scale_min > c.scale_plausible_max;
        f.Failed("the correction stretches or squeezes the drive by " + range +
                 " (corrected / estimated path per " + FormatFixed(segment_m, 0) +
                 " m; plausible " + FormatFixed(c.scale_plausible_min, 2) + ".." +
                 FormatFixed(c.scale_plausible_max, 2) + "): it was forced onto the map" +
                 (whole ? "; the whole drive alike, as when the estimate's size is unknown (a "
                          "monocular tracker's): then give anchor.scale: auto"
                        : ""));
    } else if (implausible > 0) {
        f.Degraded("the correction stretches or squeezes " +
                   FormatPercent(double(implausible) / est.size()) +
                   " of the drive beyond the plausible scale (" + range + ")");
    }
}

// Mean speed over poses (a, b] [m/s]: path over time.
double Speed(const PlanarTrajectory& t, std::size_t a, std::size_t b) {
    double path = 0.0;
    for (std::size_t i = a + 1; i <= b; ++i) path += (t.p_en[i] - t.p_en[i - 1]).norm();
    const double dt = t.t_s[b] - t.t_s[a];
    return dt > 0.0 ? path / dt : 0.0;
}

// A jump: the estimate's speed over jump_window_s changes faster than max_accel_mps2 against the
// window before it. Consecutive jumping poses are one episode.
void JudgeInputJumps(const PlanarTrajectory& est, const VerdictConfig& c, Verdict& v, Findings& f) {
    if (est.size() < 3) return;
    const double span_s = est.t_s.back() - est.t_s.front();
    const double dt = span_s / double(est.size() - 1);
    const std::size_t w =
        std::max<std::size_t>(1, std::lround(c.jump_window_s / std::max(dt, 1e-9)));
    bool in_episode = false;
    for (std::size_t i = w; i + w < est.size(); ++i) {
        const double dv = Speed(est, i, i + w) - Speed(est, i - w, i);
        const double gap_s = 0.5 * (est.t_s[i + w] - est.t_s[i - w]);
        const bool jump = gap_s > 0.0 && std::abs(dv) / gap_s > c.max_accel_mps2;
        if (jump && !in_episode) ++v.input_jumps;
        in_episode = jump;
        if (jump) {
            for (std::size_t k = i - w; k <= i + w; ++k) v.pose_flags[k] |= kPoseInputJump;
        }
    }
    if (v.input_jumps > 0) {
        f.Degraded("the estimate's speed changes faster than " + FormatFixed(c.max_accel_mps2, 1) +
                   " m/s^2 " + std::to_string(v.input_jumps) +
                   " time(s) (dropped or doubled odometry steps); the correction there is not "
                   "supported");
    }
}

// Turns the estimate does not make (VerdictConfig::turn_window_m, turn_ratio): per window of
// corrected path, the mean square of the corrected minus the estimated heading change per step,
// from the steps' directions where both steps are longer than turn_min_step_m. A window is
// flagged beyond turn_ratio times the drive's median window and beyond the model's own heading
// noise over its steps (the heading random walk over the step's time and heading_sigma_rel of
// the estimate's turn), so that the drive's straights, where a noiseless estimate and its
// correction agree exactly, do not make every turn an outlier.
void JudgeTurns(const PlanarTrajectory& est, const PlanarTrajectory& cor, const ModelConfig& model,
                const VerdictConfig& c, Verdict& v, Findings& f) {
    struct Window {
        double sum = 0.0, noise = 0.0;
        std::size_t count = 0, first = 0, last = 0;
    };
    std::vector<Window> windows;
    const auto direction = [](const PlanarTrajectory& t, std::size_t i) {
        const Eigen::Vector2d d = t.p_en[i] - t.p_en[i - 1];
        return std::atan2(d.y(), d.x());
    };
    // A step of more than kGapSteps times the input's median step time spans frames the
    // odometry did not report (a tracker lost or initialising): its direction is a chord over
    // whatever the platform drove meanwhile, which the correction bends with its ends.
    constexpr double kGapSteps = 3.0;
    std::vector<double> dts;
    for (std::size_t i = 1; i < est.size(); ++i) dts.push_back(est.t_s[i] - est.t_s[i - 1]);
    double gap_s = std::numeric_limits<double>::infinity();
    if (!dts.empty()) {
        std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
        if (dts[dts.size() / 2] > 0.0) gap_s = kGapSteps * dts[dts.size() / 2];
    }
    const auto moving = [&](std::size_t i) {
        return (est.p_en[i] - est.p_en[i - 1]).norm() > c.turn_min_step_m &&
               (cor.p_en[i] - cor.p_en[i - 1]).norm() > c.turn_min_step_m &&
               est.t_s[i] - est.t_s[i - 1] <= gap_s;
    };
    double path_m = 0.0;
    for (std::size_t i = 1; i < cor.size() && i < est.size(); ++i) {
        path_m += (cor.p_en[i] - cor.p_en[i - 1]).norm();
        const auto k = static_cast<std::size_t>(path_m / c.turn_window_m);
        if (windows.size() <= k) {
            windows.resize(k + 1);
            windows[k].first = i;
        }
        windows[k].last = i;
        if (i < 2 || !moving(i) || !moving(i - 1)) continue;
        const double turn_cor = WrapAngle(direction(cor, i) - direction(cor, i - 1));
        const double turn_est = WrapAngle(direction(est, i) - direction(est, i - 1));
        const double r = WrapAngle(turn_cor - turn_est);
        const double dt = std::max(est.t_s[i] - est.t_s[i - 1], 0.0);
        const double rw = model.heading_rw_rad_per_sqrt_s, rel = model.heading_sigma_rel;
        windows[k].sum += r * r;
        windows[k].noise += rw * rw * dt + (rel * turn_est) * (rel * turn_est);
        ++windows[k].count;
    }
    constexpr std::size_t kMinSteps = 10, kMinWindows = 3;
    std::vector<double> ms;
    for (const Window& w : windows) {
        if (w.count >= kMinSteps) ms.push_back(w.sum / double(w.count));
    }
    if (ms.size() < kMinWindows) return;
    std::nth_element(ms.begin(), ms.begin() + ms.size() / 2, ms.end());
    const double median = ms[ms.size() / 2];
    if (!(median > 0.0)) return;
    std::size_t flagged = 0;
    double worst = 0.0, worst_at_m = 0.0;
    for (std::size_t k = 0; k < windows.size(); ++k) {
        const Window& w = windows[k];
        if (w.count < kMinSteps) continue;
        const double ratio = w.sum / double(w.count) / median;
        if (ratio <= c.turn_ratio || w.sum <= w.noise) continue;
        for (std::size_t i = w.first; i <= w.last; ++i) v.pose_flags[i] |= kPoseTurnUnsupported;
        flagged += w.last - w.first + 1;
        if (ratio > worst) worst = ratio, worst_at_m = double(k) * c.turn_window_m;
    }
    if (flagged == 0) return;
    f.Degraded(
        "the correction turns where the estimate does not over " +
        FormatPercent(double(flagged) / double(est.size())) +
        " of the drive (its heading changes differ from the estimate's " + FormatFixed(worst, 0) +
        " times more than over the drive's median " + FormatFixed(c.turn_window_m, 0) +
        " m, from " + FormatFixed(worst_at_m, 0) +
        " m of the corrected path): the odometry does not support the path there (another road, a "
        "start off the map)");
}

void JudgeOffMap(const PlanarTrajectory& cor, const TraversableField& field, double reach_m,
                 const VerdictConfig& c, Verdict& v, Findings& f) {
    std::size_t off = 0;
    for (std::size_t i = 0; i < cor.size(); ++i) {
        const auto q = field.Query(Eigen::Vector3d(cor.p_en[i].x(), cor.p_en[i].y(), cor.up_m[i]));
        if (q && q->centre.value <= reach_m) continue;
        v.pose_flags[i] |= kPoseOffMap;
        ++off;
    }
    v.off_map_share = double(off) / double(std::max<std::size_t>(1, cor.size()));
    const std::string what = FormatPercent(v.off_map_share) +
                             " of the corrected poses lie farther than " + FormatFixed(reach_m, 1) +
                             " m from every traversable place";
    if (v.off_map_share > c.off_map_failed_share) {
        f.Failed(what);
    } else if (v.off_map_share > c.off_map_degraded_share) {
        f.Degraded(what + ": the map does not support them");
    }
}

// The size of a road drive (VerdictConfig::size_rms_margin_m).
void JudgeSize(const PlanarTrajectory& est, const PlanarTrajectory& cor,
               const TraversableField& field, const ModelConfig& model, const VerdictConfig& c,
               Findings& f) {
    AnchorFitConfig fit_cfg;
    fit_cfg.reach_m = model.map_giveup_m;
    fit_cfg.sample_spacing_m = 5.0;
    const SizeFit sizes = FitSizes(cor, field, model.scale_prior_sigma, fit_cfg);
    const double changed = PathLength(cor) / std::max(PathLength(est), 1e-9);
    if (!sizes.other || sizes.other->placement.rms_m > sizes.rms_m + c.size_rms_margin_m) return;
    if (std::abs(std::log(changed)) * sizes.farthest_m <= 2.0 * model.map_giveup_m) return;
    f.Failed("the corrected drive fits the map as well at " + FormatFixed(sizes.other->scale, 4) +
             " times its size (RMS " + FormatFixed(sizes.other->placement.rms_m, 2) +
             " m against " + FormatFixed(sizes.rms_m, 2) + " m; its farthest pose " +
             FormatFixed(std::abs(sizes.other->scale - 1.0) * sizes.farthest_m, 0) +
             " m away): the map does not tell the drive's size, and the correction changed it by " +
             FormatFixed(100.0 * (changed - 1.0), 1) + " %");
}

// How far a corrected height change d_cor lies beyond the estimate's d_est over the same span
// (VerdictConfig::height_disagree_m, height_disagree_rel, height_short_rel); <= 0: they agree.
double HeightChangeExcess(double d_cor, double d_est, const VerdictConfig& c) {
    const double rel =
        std::abs(d_cor) < std::abs(d_est) ? c.height_short_rel : c.height_disagree_rel;
    return std::abs(d_cor - d_est) - (c.height_disagree_m + rel * std::abs(d_est));
}

// The corrected height change against the estimate's over every height_window_s (VerdictConfig).
void JudgeHeightChanges(const PlanarTrajectory& est, const PlanarTrajectory& cor,
                        const VerdictConfig& c, Verdict& v, Findings& f) {
    std::size_t flagged = 0, episodes = 0, j = 0;
    double worst_est = 0.0, worst_cor = 0.0, worst_excess = 0.0, worst_t0 = 0.0, worst_t1 = 0.0;
    bool in_episode = false;
    for (std::size_t i = 0; i + 1 < est.size(); ++i) {
        j = std::max(j, i + 1);
        while (j + 1 < est.size() && est.t_s[j] < est.t_s[i] + c.height_window_s) ++j;
        const double d_est = est.up_m[j] - est.up_m[i], d_cor = cor.up_m[j] - cor.up_m[i];
        const double excess = HeightChangeExcess(d_cor, d_est, c);
        if (excess <= 0.0) {
            in_episode = false;
            continue;
        }
        if (!in_episode) ++episodes;
        in_episode = true;
        for (std::size_t k = i; k <= j; ++k) {
            flagged += (v.pose_flags[k] & kPoseHeightDisagrees) == 0;
            v.pose_flags[k] |= kPoseHeightDisagrees;
        }
        if (excess > worst_excess) {
            worst_excess = excess, worst_est = d_est, worst_cor = d_cor;
            worst_t0 = est.t_s[i] - est.t_s[0], worst_t1 = est.t_s[j] - est.t_s[0];
        }
    }
    if (episodes == 0) return;
    const double share = double(flagged) / double(est.size());
    const std::string what = "the corrected height changes disagree with the estimate's " +
                             std::to_string(episodes) + " time(s), over " + FormatPercent(share) +
                             " of the walk (worst: from " + FormatFixed(worst_t0, 0) + " s to " +
                             FormatFixed(worst_t1, 0) + " s the estimate changes height by " +
                             FormatFixed(worst_est, 1) + " m, the correction by " +
                             FormatFixed(worst_cor, 1) +
                             " m): a floor change the walk does not support, likely a wrong floor";
    f.ByShare(share, c.off_map_failed_share, what);
}

// A run of consecutive poses [first, last] that a check finds off, lasting duration_s (time of the
// last pose minus time of the first); worst: the largest amount off in it.
struct LongRun {
    std::size_t first = 0, last = 0;
    double duration_s = 0.0, worst = 0.0;
};

// The runs of consecutive poses with off(i) true that last at least min_s; amount(i) gives each
// run's worst.
template <class Off, class Amount>
std::vector<LongRun> LongRuns(const std::vector<double>& t_s, Off off, Amount amount,
                              double min_s) {
    std::vector<LongRun> runs;
    for (std::size_t i = 0; i < t_s.size();) {
        if (!off(i)) {
            ++i;
            continue;
        }
        LongRun r{i, i, 0.0, amount(i)};
        while (r.last + 1 < t_s.size() && off(r.last + 1))
            r.worst = std::max(r.worst, amount(++r.last));
        r.duration_s = t_s[r.last] - t_s[r.first];
        if (r.duration_s >= min_s) runs.push_back(r);
        i = r.last + 1;
    }
    return runs;
}

// Level walking between the map's floors (`floors`, not empty): runs of poses off every floor
// while the estimate is level; only runs of level_window_s / 2 or more count and are flagged.
void JudgeLevelOffFloor(const PlanarTrajectory& est, const PlanarTrajectory& cor,
                        const std::vector<double>& floors, const VerdictConfig& c, Verdict& v,
                        Findings& f) {
    auto floor_distance = [&](std::size_t i) {
        return std::abs(cor.up_m[i] - NearestFloor(floors, cor.up_m[i]));
    };
    const std::vector<std::uint8_t> level =
        LevelSpans(est.t_s, est.up_m, c.level_window_s, c.level_height_m);
    const std::vector<LongRun> runs = LongRuns(
        est.t_s, [&](std::size_t i) { return level[i] && floor_distance(i) > c.off_floor_m; },
        floor_distance, 0.5 * c.level_window_s);
    std::size_t flagged = 0;
    double longest_s = 0.0, worst_m = 0.0;
    for (const LongRun& r : runs) {
        longest_s = std::max(longest_s, r.duration_s);
        worst_m = std::max(worst_m, r.worst);
        for (std::size_t k = r.first; k <= r.last; ++k) v.pose_flags[k] |= kPoseHeightDisagrees;
        flagged += r.last - r.first + 1;
    }
    if (flagged == 0) return;
    const double share = double(flagged) / double(cor.size());
    const std::string what =
        FormatPercent(share) + " of the corrected poses walk level up to " +
        FormatFixed(worst_m, 1) + " m from every floor (" + FormatFixed(longest_s, 0) +
        " s in a row, while the estimate's height stays level): between floors, where only "
        "stairs or a lift could hold them; their floor is not supported";
    f.ByShare(share, c.off_map_failed_share, what);
}

bool HeightChangeAgrees(double d_cor, double d_est, const VerdictConfig& c) {
    return HeightChangeExcess(d_cor, d_est, c) <= 0.0;
}

// A stay on one floor: the corrected poses [first, last] that lie within off_floor_m of the floor
// at floor_m (NearestFloor) for at least min_s, with no such stay on another floor between them.
// Shorter visits (a lift or a stair flight passing a floor) are not stays.
struct FloorStay {
    double floor_m = 0.0;
    std::size_t first = 0, last = 0;
};

std::vector<FloorStay> FloorStays(const PlanarTrajectory& cor, const std::vector<double>& floors,
                                  const VerdictConfig& c, double min_s) {
    std::vector<FloorStay> visits;
    for (std::size_t i = 0; i < cor.size(); ++i) {
        const double floor_m = NearestFloor(floors, cor.up_m[i]);
        if (std::abs(cor.up_m[i] - floor_m) > c.off_floor_m) continue;
        if (!visits.empty() && visits.back().floor_m == floor_m) {
            visits.back().last = i;
        } else {
            visits.push_back({floor_m, i, i});
        }
    }
    std::vector<FloorStay> stays;
    for (const FloorStay& v : visits) {
        if (cor.t_s[v.last] - cor.t_s[v.first] < min_s) continue;
        if (!stays.empty() && stays.back().floor_m == v.floor_m) {
            stays.back().last = v.last;
        } else {
            stays.push_back(v);
        }
    }
    return stays;
}

// Mean estimated height over the poses of [first, last] within span_s of pose `from` (the first
// or the last of them).
double MeanHeightNear(const PlanarTrajectory& est, std::size_t first, std::size_t last,
                      std::size_t from, double span_s) {
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = first; i <= last; ++i) {
        if (std::abs(est.t_s[i] - est.t_s[from]) > span_s) continue;
        sum += est.up_m[i];
        ++n;
    }
    return n > 0 ? sum / double(n) : est.up_m[from];
}

// CentreFit of the corrected poses [first, last], moved up by shift_m and horizontally by
// `offset`.
CentreFit FitShifted(const PlanarTrajectory& cor, const TraversableField& field, std::size_t first,
                     std::size_t last, double shift_m, const Eigen::Vector2d& offset,
                     double reach_m) {
    return FitToCentres(field, last - first + 1, reach_m, [&](std::size_t k) {
        const Eigen::Vector2d p = cor.p_en[first + k] + offset;
        return Eigen::Vector3d(p.x(), p.y(), cor.up_m[first + k] + shift_m);
    });
}

// The best fit (fewest poses off the map, then the lowest RMS) of the poses [first, last] moved
// up by shift_m and horizontally by any offset on a 0.5 m grid within reach_m: on another floor
// the correction would have moved the path to that floor's walkways, by up to the map term's
// reach.
CentreFit BestShiftedFit(const PlanarTrajectory& cor, const TraversableField& field,
                         std::size_t first, std::size_t last, double shift_m, double reach_m) {
    constexpr double kGridM = 0.5;
    const int n = int(std::floor(reach_m / kGridM));
    CentreFit best{reach_m, 1.0};
    for (int ox = -n; ox <= n; ++ox) {
        for (int oy = -n; oy <= n; ++oy) {
            if (std::hypot(ox, oy) * kGridM > reach_m) continue;
            const CentreFit fit = FitShifted(cor, field, first, last, shift_m,
                                             kGridM * Eigen::Vector2d(ox, oy), reach_m);
            if (fit.off_share < best.off_share ||
                (fit.off_share == best.off_share && fit.rms_m < best.rms_m)) {
                best = fit;
            }
        }
    }
    return best;
}

// A stay on a floor after a floor change that another floor explains as well: the estimate's
// height changes into and out of the stay agree with that floor (HeightChangeAgrees), and the
// stay's path, shifted by at most the map's reach, lies on that floor's map as well as the
// verdict asks of any result (at most off_map_degraded_share of its poses beyond the reach).
// The barometer cannot tell such floors apart (a lift ride read 0.8x fits the floor below the
// true one as well), nor can the map: the stay's floor is not supported. Stays (FloorStays)
// last level_window_s / 2 or more; those whose own floor the height changes deny are not judged;
// the walk's first stay is the start's floor.
void JudgeFloorAlternatives(const PlanarTrajectory& est, const PlanarTrajectory& cor,
                            const TraversableField& field, const ModelConfig& model,
                            const VerdictConfig& c, Verdict& verdict, Findings& f) {
    const double span_s = 0.5 * c.level_window_s;
    const std::vector<double>& floors = field.floor_heights_m();
    const std::vector<FloorStay> stays = FloorStays(cor, floors, c, span_s);
    // The estimate's height change from stay k - 1 into stay k (k >= 1).
    std::vector<double> change_m(stays.size(), 0.0);
    for (std::size_t k = 1; k < stays.size(); ++k) {
        const FloorStay &from = stays[k - 1], &to = stays[k];
        change_m[k] = MeanHeightNear(est, to.first, to.last, to.first, span_s) -
                      MeanHeightNear(est, from.first, from.last, from.last, span_s);
    }
    // Whether the walk could stand on floor_m during stay k: the height changes into and out of
    // it agree with that floor.
    auto barometer_allows = [&](std::size_t k, double floor_m) {
        const bool next = k + 1 < stays.size();
        return HeightChangeAgrees(floor_m - stays[k - 1].floor_m, change_m[k], c) &&
               (!next || HeightChangeAgrees(stays[k + 1].floor_m - floor_m, change_m[k + 1], c));
    };
    std::size_t flagged = 0, ambiguous = 0;
    std::string worst;
    double worst_s = 0.0;
    for (std::size_t k = 1; k < stays.size(); ++k) {
        const FloorStay& v = stays[k];
        // A chosen floor the height changes deny is JudgeHeightChanges' finding.
        if (!barometer_allows(k, v.floor_m)) continue;
        for (const double other_m : floors) {
            if (other_m == v.floor_m || !barometer_allows(k, other_m)) continue;
            const CentreFit other = BestShiftedFit(cor, field, v.first, v.last, other_m - v.floor_m,
                                                   model.map_giveup_m);
            if (other.off_share > c.off_map_degraded_share) continue;
            ++ambiguous;
            for (std::size_t i = v.first; i <= v.last; ++i) {
                flagged += (verdict.pose_flags[i] & kPoseFloorAmbiguous) == 0;
                verdict.pose_flags[i] |= kPoseFloorAmbiguous;
            }
            const double stay_s = est.t_s[v.last] - est.t_s[v.first];
            if (stay_s > worst_s) {
                worst_s = stay_s;
                const CentreFit chosen = FitShifted(cor, field, v.first, v.last, 0.0,
                                                    Eigen::Vector2d::Zero(), model.map_giveup_m);
                auto signed_m = [](double m) { return (m > 0.0 ? "+" : "") + FormatFixed(m, 1); };
                const std::string heights = k + 1 < stays.size()
                                                ? "into and out of it (" + signed_m(change_m[k]) +
                                                      " m and " + signed_m(change_m[k + 1]) + " m)"
                                                : "into it (" + signed_m(change_m[k]) + " m)";
                worst = "from " + FormatFixed(est.t_s[v.first] - est.t_s[0], 0) + " s to " +
                        FormatFixed(est.t_s[v.last] - est.t_s[0], 0) +
                        " s the correction stands on the floor at " + FormatFixed(v.floor_m, 1) +
                        " m; the estimate's height changes " + heights + " read the floor at " +
                        FormatFixed(other_m, 1) + " m as well, and the path, shifted by at most " +
                        FormatFixed(model.map_giveup_m, 1) + " m, lies RMS " +
                        FormatFixed(other.rms_m, 2) + " m from that floor's walkways, " +
                        FormatPercent(other.off_share) + " of it beyond their reach (" +
                        FormatFixed(chosen.rms_m, 2) + " m and " + FormatPercent(chosen.off_share) +
                        " on the chosen floor)";
            }
            break;
        }
    }
    if (ambiguous == 0) return;
    const double share = double(flagged) / double(cor.size());
    // Degraded whatever the share: the correction stands on one of two floors that the walk
    // supports alike, and the flags say where.
    f.Degraded("the floor is not determined over " + FormatPercent(share) + " of the walk (" +
               std::to_string(ambiguous) + " stay(s); longest: " + worst +
               "): neither the barometer nor the map tells the two floors apart");
}

std::string Placement(const AnchorPlacement& p) {
    return FormatFixed(RadToDeg(p.dyaw_rad), 1) + " deg, (" + FormatFixed(p.offset_en.x(), 1) +
           ", " + FormatFixed(p.offset_en.y(), 1) + ") m: RMS " + FormatFixed(p.rms_m, 2) + " m";
}

void JudgeStart(const AnchorFitResult& fit, bool estimated, const VerdictConfig& c, Findings& f) {
    const std::string lead = "the first " + FormatFixed(fit.lead_path_m, 0) + " m";
    if (estimated) {
        if (fit.runner_up && fit.runner_up->rms_m < c.anchor_ambiguous_ratio * fit.best.rms_m) {
            f.Degraded("the start estimated from the map is ambiguous: " + lead + " fit turned " +
                       Placement(fit.best) + ", and turned " + Placement(*fit.runner_up));
        }
        return;
    }
    const AnchorPlacement& b = fit.best;
    const bool elsewhere = std::abs(RadToDeg(b.dyaw_rad)) >= c.anchor_other_yaw_deg ||
                           b.offset_en.norm() >= c.anchor_other_position_m;
    if (elsewhere && b.rms_m < c.anchor_rms_ratio * fit.given.rms_m) {
        f.Failed("the anchor does not fit the map: with it " + lead + " lie RMS " +
                 FormatFixed(fit.given.rms_m, 2) + " m from the map, turned and moved by " +
                 Placement(b) +
                 "; check anchor.yaw_deg and the position, or give "
                 "yaw_deg: auto");
    }
}

}  // namespace

std::string ToString(VerdictLevel level) {
    switch (level) {
        case VerdictLevel::kOk:
            return "ok";
        case VerdictLevel::kDegraded:
            return "degraded";
        case VerdictLevel::kFailed:
            return "failed";
    }
    return "?";
}

std::optional<ParamProblem> VerdictConfig::FindProblem() const {
    if (auto problem = CheckRows(kVerdictParams, *this)) return problem;
    if (!(scale_failed_min <= scale_plausible_min)) {
        return RelationProblem("scale_failed_min", scale_failed_min, "<=", "scale_plausible_min",
                               scale_plausible_min);
    }
    if (!(scale_failed_max >= scale_plausible_max)) {
        return RelationProblem("scale_failed_max", scale_failed_max, ">=", "scale_plausible_max",
                               scale_plausible_max);
    }
    if (!(off_map_degraded_share <= off_map_failed_share)) {
        return RelationProblem("off_map_degraded_share", off_map_degraded_share,
                               "<=", "off_map_failed_share", off_map_failed_share);
    }
    return std::nullopt;
}

std::string VerdictConfig::Validate() const {
    return ToMessage(kVerdictParams.section, FindProblem());
}

Verdict JudgeCorrection(const PlanarTrajectory& estimate, const TraversableField* field,
                        const ModelConfig& model, const CorrectionResult& result,
                        const AnchorFitResult* anchor_fit, bool start_estimated,
                        bool scale_estimated, const VerdictConfig& config) {
    Verdict v;
    v.pose_flags.assign(estimate.size(), 0);
    Findings f(v);
    JudgeSolver(result, f);
    if (anchor_fit) JudgeStart(*anchor_fit, start_estimated, config, f);
    JudgeInputJumps(estimate, config, v, f);
    if (!Usable(result.status) || result.corrected.size() != estimate.size()) return v;
    if (scale_estimated) {
        // A model with a plausible scale range (its range prior) says itself which scales an
        // odometry of its kind has (a pedestrian step model is tens of percent off): beyond them
        // the map pushed the scale against that prior, as when a walk is squeezed into a
        // corridor beside its own. Without one, the verdict's range.
        VerdictConfig c = config;
        if (model.scale_range_sigma > 0.0) {
            c.scale_plausible_min = model.scale_range_min;
            c.scale_plausible_max = model.scale_range_max;
        }
        c.scale_failed_min = std::min(c.scale_failed_min, c.scale_plausible_min);
        c.scale_failed_max = std::max(c.scale_failed_max, c.scale_plausible_max);
        JudgeScale(estimate, result.step_length_m, result.tread_steps, result.corrected,
                   model.scale_segment_m, c, v, f);
    }
    if (field && !field->empty() && field->planar() && !result.input_kept)
        JudgeTurns(estimate, result.corrected, model, config, v, f);
    if (field && !field->empty())
        JudgeOffMap(result.corrected, *field, model.map_giveup_m, config, v, f);
    if (field && !field->empty() && field->planar() && scale_estimated && !result.input_kept)
        JudgeSize(estimate, result.corrected, *field, model, config, f);
    if (field && !field->empty() && !field->planar()) {
        // The heights as the model observed them (a lift ride's lagged reading in the ride);
        // only the 3D checks read them.
        PlanarTrajectory observed = estimate;
        if (result.height_change_m.size() == estimate.size()) {
            for (std::size_t i = 1; i < observed.size(); ++i) {
                observed.up_m[i] = observed.up_m[i - 1] + result.height_change_m[i];
            }
        }
        JudgeHeightChanges(observed, result.corrected, config, v, f);
        if (!field->floor_heights_m().empty()) {
            JudgeLevelOffFloor(observed, result.corrected, field->floor_heights_m(), config, v, f);
            JudgeFloorAlternatives(observed, result.corrected, *field, model, config, v, f);
        }
    }
    return v;
}

CausalCheck CheckCausalOutput(const PlanarTrajectory& input, const PlanarTrajectory& causal,
                              const PlanarTrajectory& smoothed, const VerdictConfig* heights) {
    DRIFTCORR_CHECK(
        input.size() == causal.size() && causal.size() == smoothed.size() && input.size() > 0,
        "CheckCausalOutput: the trajectories must have the same poses");
    CausalCheck c;
    double causal_sq = 0.0, input_sq = 0.0;
    for (std::size_t i = 0; i < smoothed.size(); ++i) {
        const double dc = (causal.p_en[i] - smoothed.p_en[i]).norm();
        causal_sq += dc * dc;
        c.causal_max_m = std::max(c.causal_max_m, dc);
        input_sq += (input.p_en[i] - smoothed.p_en[i]).squaredNorm();
    }
    const std::size_t n = smoothed.size();
    c.causal_rms_m = std::sqrt(causal_sq / double(n));
    c.input_rms_m = std::sqrt(input_sq / double(n));
    // (A micrometre: the rounding of outputs composed from the same input.)
    constexpr double kRoundingM = 1e-6;
    c.disagree = c.causal_rms_m > c.input_rms_m + kRoundingM;
    if (!heights || causal.up_m.size() != n || smoothed.up_m.size() != n ||
        smoothed.t_s.size() != n) {
        return c;
    }
    auto dz = [&](std::size_t i) { return std::abs(causal.up_m[i] - smoothed.up_m[i]); };
    std::size_t apart = 0;
    for (const LongRun& r : LongRuns(
             smoothed.t_s, [&](std::size_t i) { return dz(i) > heights->height_disagree_m; }, dz,
             heights->level_window_s)) {
        apart += r.last - r.first + 1;
        c.floor_apart_longest_s = std::max(c.floor_apart_longest_s, r.duration_s);
        c.floor_apart_max_m = std::max(c.floor_apart_max_m, r.worst);
    }
    c.floor_apart_share = double(apart) / double(n);
    return c;
}

OnlineVerdict JudgeOnline(const PlanarTrajectory& input, const PlanarTrajectory& causal,
                          const TraversableField* field, const ModelConfig& model,
                          const CorrectionResult& smoothed, const VerdictConfig& config) {
    OnlineVerdict out{JudgeCorrection(input, field, model, smoothed, nullptr, false, true, config),
                      CheckCausalOutput(input, causal, smoothed.corrected,
                                        field && !field->planar() ? &config : nullptr)};
    const CausalCheck& c = out.check;
    Findings f(out.verdict);
    if (c.disagree && smoothed.input_kept) {
        f.Failed("the causal outputs lie " + FormatFixed(c.causal_rms_m, 2) +
                 " m (RMS) from the smoothed trajectory, which is the input itself (the map cannot "
                 "tell it wrong): the causal outputs moved an input they should have left as it "
                 "was");
    } else if (c.disagree) {
        f.Failed(
            "the causal outputs and the smoothed trajectory lie " + FormatFixed(c.causal_rms_m, 2) +
            " m apart (RMS), farther than the input lies from the smoothed trajectory (" +
            FormatFixed(c.input_rms_m, 2) + " m): one of them followed a wrong branch of the map");
    }
    if (c.floor_apart_share > 0.0) {
        f.ByShare(c.floor_apart_share, config.off_map_failed_share,
                  FormatPercent(c.floor_apart_share) + " of the causal outputs stood up to " +
                      FormatFixed(c.floor_apart_max_m, 1) +
                      " m above or below the smoothed trajectory (" +
                      FormatFixed(c.floor_apart_longest_s, 0) +
                      " s in a row): a floor apart, so one of them stood on a wrong floor");
    }
    return out;
}

}  // namespace driftcorr
