// The definitions of what floor_hypotheses.h declares.
#include "floor_hypotheses.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "driftcorr/core/observables.h"

namespace driftcorr {
namespace {

// The spans where the estimate's height stays level (LevelSpans over the observed height
// changes, with the floor term's window and height): the stays on a floor between its floor
// changes.
struct LevelRun {
    std::size_t first = 0, last = 0;
};

std::vector<LevelRun> LevelRuns(const TrajectoryState& s, const std::vector<double>& t_s,
                                const ModelConfig& model) {
    std::vector<double> up_m(s.obs.size(), 0.0);
    for (std::size_t i = 1; i < s.obs.size(); ++i) up_m[i] = up_m[i - 1] + s.obs[i].dup_m;
    const std::vector<std::uint8_t> level =
        LevelSpans(t_s, up_m, model.floor_level_window_s, model.floor_level_height_m);
    std::vector<LevelRun> runs;
    for (std::size_t i = 0; i < level.size(); ++i) {
        if (!level[i]) continue;
        // Two level poses in a row with a height change between them (a lift ride between two
        // poses: each is level over the time around it) end one run and start the next.
        if (!runs.empty() && runs.back().last + 1 == i &&
            std::abs(up_m[i] - up_m[i - 1]) <= model.floor_level_height_m) {
            runs.back().last = i;
        } else {
            runs.push_back({i, i});
        }
    }
    return runs;
}

// The floor nearest to the mean corrected height over poses [first, last].
double FloorOf(const PlanarTrajectory& cor, const std::vector<double>& floors_m, std::size_t first,
               std::size_t last) {
    double sum = 0.0;
    for (std::size_t i = first; i <= last; ++i) sum += cor.up_m[i];
    return NearestFloor(floors_m, sum / double(last - first + 1));
}

// A floor change of the estimate: the steps (from, to] between two level runs (runs[run - 1] and
// runs[run]) whose observed height changes add up to read_m, restart_height_change_m or more;
// ride: one of its poses is in a lift ride (RideSpans).
struct FloorChange {
    std::size_t run = 0, from = 0, to = 0;
    double read_m = 0.0;
    bool ride = false;
};

std::vector<FloorChange> FloorChanges(const std::vector<StepObservation>& obs,
                                      const std::vector<LevelRun>& runs,
                                      const CorrectorConfig& cfg) {
    const ModelConfig& m = cfg.model;
    const std::vector<std::uint8_t> ride =
        RideSpans(obs, m.ride_min_s, m.ride_min_height_m, m.ride_gap_s, m.ride_lag_s);
    std::vector<FloorChange> changes;
    for (std::size_t j = 1; j < runs.size(); ++j) {
        FloorChange c{j, runs[j - 1].last, runs[j].first};
        for (std::size_t i = c.from + 1; i <= c.to; ++i) {
            c.read_m += obs[i].dup_m;
            c.ride = c.ride || ride[i];
        }
        if (std::abs(c.read_m) >= cfg.restart_height_change_m) changes.push_back(c);
    }
    return changes;
}

// CorrectorConfig::floor_gain_sigma: the NLL of the gains of `changes` as `cor` takes them,
// floor to floor, about one gain per kind (a lift ride or walked), each kind's gain at its best
// (the mean log). A gain is clamped to [1/4, 4] before its log: a change `cor` does not take, or
// takes the other way, costs as much as the farthest gain.
double GainNll(const std::vector<FloorChange>& changes, const std::vector<LevelRun>& runs,
               const PlanarTrajectory& cor, const std::vector<double>& floors_m,
               const CorrectorConfig& cfg) {
    if (cfg.floor_gain_sigma <= 0.0) return 0.0;
    constexpr double kGainMin = 0.25, kGainMax = 4.0;
    std::vector<double> log_gain[2];  // walked, ride
    for (const FloorChange& c : changes) {
        const LevelRun &before = runs[c.run - 1], &after = runs[c.run];
        const double taken_m = FloorOf(cor, floors_m, after.first, after.last) -
                               FloorOf(cor, floors_m, before.first, before.last);
        log_gain[c.ride].push_back(std::log(std::clamp(taken_m / c.read_m, kGainMin, kGainMax)));
    }
    double nll = 0.0;
    for (const std::vector<double>& g : log_gain) {
        if (g.size() < 2) continue;
        double mean = 0.0;
        for (double v : g) mean += v / double(g.size());
        for (double v : g) nll += 0.5 * (v - mean) * (v - mean);
    }
    return nll / (cfg.floor_gain_sigma * cfg.floor_gain_sigma);
}

}  // namespace

bool FloorHypotheses(const TraversableField* field, bool fix_height, const CorrectorConfig& cfg) {
    return field && !fix_height && !field->floor_heights_m().empty() &&
           !cfg.restart_height_gains.empty();
}

std::vector<CorrectionResult::FloorHypothesis> TryOtherFloors(
    const TrajectoryState& observed, double start_scale, const std::vector<double>& t_s,
    const TraversableField& field, const CorrectorConfig& cfg, WholeCorrections& run,
    KeptCorrection& kept) {
    std::vector<CorrectionResult::FloorHypothesis> tried;
    const std::vector<double>& floors = field.floor_heights_m();
    const auto [gain_min, gain_max] =
        std::minmax_element(cfg.restart_height_gains.begin(), cfg.restart_height_gains.end());
    TrajectoryState read = observed;  // the observations with the kept readings
    std::fill(read.scales.begin(), read.scales.end(), start_scale);
    const std::vector<LevelRun> runs = LevelRuns(read, t_s, cfg.model);
    // As observed: a kept hypothesis re-reads its own change's steps, and later changes' steps
    // lie after them.
    const std::vector<FloorChange> changes = FloorChanges(observed.obs, runs, cfg);
    auto gain_nll = [&](const CorrectionResult& r) {
        return GainNll(changes, runs, r.corrected, floors, cfg);
    };
    CorrectionResult& result = kept.result;
    double kept_gain_nll = gain_nll(result);
    for (const FloorChange& c : changes) {
        const std::size_t from = c.from, to = c.to;
        const double before_m =
            FloorOf(result.corrected, floors, runs[c.run - 1].first, runs[c.run - 1].last);
        const double after_m =
            FloorOf(result.corrected, floors, runs[c.run].first, runs[c.run].last);
        for (const double floor_m : floors) {
            const double gain = (floor_m - before_m) / c.read_m;
            if (floor_m == after_m || gain < *gain_min || gain > *gain_max) continue;
            TrajectoryState trial = read;
            trial.height_settled.resize(trial.obs.size(), 0);
            for (std::size_t i = from + 1; i <= to; ++i) {
                trial.obs[i].dup_m *= gain;
                trial.height_settled[i] = 1;
            }
            auto [inc, r] = run.Run(trial, start_scale, &observed.obs);
            const double nll_m =
                Usable(r.status) ? r.nll : std::numeric_limits<double>::quiet_NaN();
            const double trial_gain_nll = Usable(r.status) ? gain_nll(r) : 0.0;
            tried.push_back({t_s[to] - t_s[0], before_m, after_m, floor_m, nll_m, result.nll,
                             trial_gain_nll, kept_gain_nll});
            if (!Usable(r.status) ||
                r.nll + trial_gain_nll >= result.nll + kept_gain_nll - cfg.floor_hypothesis_margin)
                continue;
            tried.back().kept = true;
            kept_gain_nll = trial_gain_nll;
            kept.Keep(std::move(inc), std::move(r));
            read = std::move(trial);
            break;
        }
    }
    return tried;
}

}  // namespace driftcorr
