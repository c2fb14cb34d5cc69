#pragma once
// Whole corrections of one drive, each from a state of its own (a start scale, a floor read
// another way), and the one kept among them: what the start-scale search (corrector.cpp) and the
// floor hypotheses (floor_hypotheses.cpp) share.
#include <optional>
#include <utility>
#include <vector>

#include "driftcorr/optim/incremental_corrector.h"

namespace driftcorr {

class WholeCorrections {
public:
    /// `each`: the configuration of every correction (its scale prior's mean is replaced per
    /// run); `prior_mean`: the mean every final solve holds the scale about, so that every
    /// correction's NLL compares. The references must outlive this object.
    WholeCorrections(const std::vector<double>& t_s, const TraversableField* field,
                     const CorrectorConfig& each, double prior_mean,
                     const ProgressCallback& progress)
        : t_s_(t_s), field_(field), each_(each), prior_mean_(prior_mean), progress_(progress) {}

    /// One whole correction from `state`: its windows hold the scale about `scale` (the prior's
    /// mean, so that a start is a hypothesis the first windows keep rather than one the prior
    /// about 1 pulls back where the map cannot tell), its final solve about prior_mean, scored
    /// against `obs` when given (else its own observations). Adds its work to work().
    std::pair<IncrementalCorrector, CorrectionResult> Run(TrajectoryState state, double scale,
                                                          const std::vector<StepObservation>* obs) {
        CorrectorConfig held = each_;
        held.model.scale_prior_mean = scale;
        IncrementalCorrector inc(std::move(state), field_, held);
        inc.SolveRemaining(progress_);
        inc.SetScalePriorMean(prior_mean_);
        if (obs) inc.ReplaceObservations(*obs);
        CorrectionResult r = inc.Finish(t_s_, progress_);
        work_.windows += r.windows, work_.window_retries += r.window_retries;
        work_.window_restarts += r.window_restarts, work_.iterations += r.iterations;
        work_.incremental_s += r.incremental_s, work_.refine_s += r.refine_s;
        return std::make_pair(std::move(inc), std::move(r));
    }

    /// The counters and times over every correction run.
    CorrectionResult& work() { return work_; }

private:
    const std::vector<double>& t_s_;
    const TraversableField* field_;
    const CorrectorConfig& each_;
    double prior_mean_;
    const ProgressCallback& progress_;
    CorrectionResult work_;
};

/// The correction kept so far: its corrector (for the covariance and the heading-rate bias's
/// decision) and its outcome.
struct KeptCorrection {
    std::optional<IncrementalCorrector> corrector;
    CorrectionResult& result;

    /// Whether `r` replaces the kept one: the first of all, or usable with a lower NLL.
    bool Better(const CorrectionResult& r) const {
        return !corrector || (Usable(r.status) && (!Usable(result.status) || r.nll < result.nll));
    }
    void Keep(IncrementalCorrector inc, CorrectionResult r) {
        corrector.emplace(std::move(inc));
        result = std::move(r);
    }
};

}  // namespace driftcorr
