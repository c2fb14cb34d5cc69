// The definitions of what driftcorr/optim/online_corrector.h declares.
#include "driftcorr/optim/online_corrector.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"
#include "online_chain.h"

namespace driftcorr {
namespace {

bool Finite(const PlanarPose& p) {
    return std::isfinite(p.t_s) && p.p_en.allFinite() && std::isfinite(p.up_m) &&
           (!p.yaw_rad || std::isfinite(*p.yaw_rad));
}

double SecondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

PushResult Rejected(PushStatus status, std::string message) {
    PushResult r;
    r.status = status;
    r.message = std::move(message);
    return r;
}

// Counts an output's age into `stats`.
void CountOutput(const PushResult& r, OnlineStatistics& stats) {
    ++stats.poses;
    if (!r.fresh) ++stats.stale_poses;
    if (r.ahead_of_real_time) ++stats.ahead_poses;
    stats.max_age_epochs = std::max(stats.max_age_epochs, r.correction_age_epochs);
    stats.max_age_s = std::max(stats.max_age_s, r.correction_age_s);
}

}  // namespace

OnlineCorrector::OnlineCorrector(const TraversableField* field, const OnlineConfig& config)
    : cfg_(config) {
    DRIFTCORR_CHECK(config.Validate().empty(), "invalid OnlineConfig");
    const std::vector<double>& starts = cfg_.corrector.start_scales;
    if (starts.size() == 1) {
        chains_.emplace_back(
            new OnlineChain(field, cfg_, starts.front(), false, cfg_.first_solve_at_chunk));
        return;
    }
    // The start nearest the scale prior's mean (the first of equally near ones) solves from the
    // first pose and gives the outputs until every chain has solved; the others solve first at
    // the chunk rule.
    const double mean = cfg_.corrector.model.scale_prior_mean;
    for (std::size_t k = 1; k < starts.size(); ++k) {
        if (std::abs(starts[k] - mean) < std::abs(starts[chosen_] - mean)) chosen_ = k;
    }
    for (std::size_t k = 0; k < starts.size(); ++k) {
        chains_.emplace_back(new OnlineChain(field, cfg_, starts[k], true, k != chosen_));
    }
}

OnlineCorrector::~OnlineCorrector() = default;  // each chain stops its worker

std::size_t OnlineCorrector::size() const { return chains_.front()->size(); }

// The input's pace is measured here once, for every chain (each one's own time would count the
// others' as time outside Push).
PushResult OnlineCorrector::Push(const PlanarPose& pose) {
    if (finished_) return Rejected(PushStatus::kRejectedFinished, "Push after Finish()");
    if (!Finite(pose))
        return Rejected(PushStatus::kRejectedNonFinite, "pose has a NaN or inf value");
    if (auto rejected = chains_.front()->Validate(pose)) return *rejected;  // the others' alike
    const bool ahead = AheadOfRealTime(pose.t_s);
    PushResult r =
        chains_.size() == 1 ? chains_.front()->Take(pose, ahead) : TakeHypotheses(pose, ahead);
    push_returned_ = std::chrono::steady_clock::now();
    return r;
}

PushResult OnlineCorrector::TakeHypotheses(const PlanarPose& pose, bool ahead_of_real_time) {
    std::vector<PushResult> results;
    results.reserve(chains_.size());
    double waited_s = 0.0;
    for (const auto& h : chains_) {
        results.push_back(h->Take(pose, ahead_of_real_time));
        waited_s += results.back().waited_s;
    }
    ChooseChain();
    const PoseCovariance mixture = MixtureCovariance(results);
    // A hypothesis nearly as likely (NLL within 3 of the chosen one's; all alike before the first
    // choice) that puts the pose outside the chosen output's own 95 % region.
    const PushResult& chosen = results[chosen_];
    unsigned doubt = 0;
    for (std::size_t k = 0; k < results.size() && chosen.covariance_ok; ++k) {
        const bool near = weights_.empty() || weights_[k] >= std::exp(-3.0) * weights_[chosen_];
        if (k != chosen_ && near &&
            !InsideRegion95(results[k].corrected.p_en - chosen.corrected.p_en,
                            chosen.covariance.xy_m2)) {
            doubt = kDoubtHypotheses;
        }
    }
    PushResult r = std::move(results[chosen_]);
    r.waited_s = waited_s;
    r.doubt |= doubt;
    if (r.covariance_ok) r.covariance = mixture;
    std::lock_guard<std::mutex> lock(stats_mutex_);
    CountOutput(r, output_stats_);
    return r;
}

// The latest solve end with an NLL from every chain (ends newer than the last choice only); the
// chain of lowest NLL there is chosen. Holds every chain's lock, in order (their workers only
// ever take their own).
void OnlineCorrector::ChooseChain() {
    std::vector<std::unique_lock<std::mutex>> locks;
    for (const auto& h : chains_) locks.push_back(h->Lock());
    const auto& newest = chains_.front()->NllAt();
    for (auto it = newest.rbegin(); it != newest.rend() && it->first > chosen_at_; ++it) {
        std::vector<double> nll;
        for (const auto& h : chains_) {
            const auto& at_end = h->NllAt();
            const auto found = std::lower_bound(at_end.begin(), at_end.end(), it->first,
                                                [](const std::pair<std::size_t, double>& a,
                                                   std::size_t end) { return a.first < end; });
            if (found == at_end.end() || found->first != it->first) break;
            nll.push_back(found->second);
        }
        if (nll.size() < chains_.size()) continue;
        // The chosen hypothesis stays unless another's NLL is lower by more than kNllTie
        // (relative): hypotheses that met in one basin differ only by the solver's rounding,
        // and switching between them would only add jumps.
        const std::size_t best =
            static_cast<std::size_t>(std::min_element(nll.begin(), nll.end()) - nll.begin());
        if (nll[best] < nll[chosen_] - kNllTie * std::abs(nll[chosen_])) chosen_ = best;
        chosen_at_ = it->first;
        weights_.clear();
        for (const double v : nll) weights_.push_back(std::exp(-(v - nll[best])));
        return;
    }
}

// The covariance about the chosen output of the mixture of every hypothesis's output (weights_,
// equal before the first choice): sum of w_k (C_k + d_k d_k^T) / sum of w_k, d_k the offset of
// hypothesis k's pose from the chosen one's (East, North, up, yaw). Only the chosen one's
// covariance when another's is not known.
PoseCovariance OnlineCorrector::MixtureCovariance(const std::vector<PushResult>& results) const {
    const PushResult& chosen = results[chosen_];
    PoseCovariance m;
    double total = 0.0;
    for (std::size_t k = 0; k < results.size(); ++k) {
        const PushResult& h = results[k];
        if (!h.covariance_ok) return chosen.covariance;
        const double w = weights_.empty() ? 1.0 : weights_[k];
        const Eigen::Vector2d d = h.corrected.p_en - chosen.corrected.p_en;
        const double dz = h.corrected.up_m - chosen.corrected.up_m;
        const double dyaw = AngleDiff(*h.corrected.yaw_rad, *chosen.corrected.yaw_rad);
        m.xy_m2 += w * (h.covariance.xy_m2 + d * d.transpose());
        m.z_m2 += w * (h.covariance.z_m2 + dz * dz);
        m.yaw_rad2 += w * (h.covariance.yaw_rad2 + dyaw * dyaw);
        m.xy_yaw_m_rad += w * (h.covariance.xy_yaw_m_rad + d * dyaw);
        total += w;
    }
    m.xy_m2 /= total, m.z_m2 /= total, m.yaw_rad2 /= total, m.xy_yaw_m_rad /= total;
    return m;
}

// The input's pace over the last kPaceWindow poses (stream time against wall time outside Push),
// the wall time since the last accepted Push returned added first.
bool OnlineCorrector::AheadOfRealTime(double t_s) {
    if (!pace_.empty()) outside_s_ += SecondsSince(push_returned_);
    pace_.emplace_back(t_s, outside_s_);
    if (pace_.size() > kPaceWindow + 1) pace_.pop_front();
    if (pace_.size() < 3) return false;  // two intervals at least
    return t_s - pace_.front().first > kAheadFactor * (outside_s_ - pace_.front().second);
}

OnlineStatistics OnlineCorrector::Statistics() const {
    if (chains_.size() == 1) return chains_.front()->Statistics();
    // The ages of the outputs returned (each from its chosen chain), the solves and waits of
    // every chain.
    OnlineStatistics all;
    {
        std::lock_guard<std::mutex> lock(stats_mutex_);
        all = output_stats_;
    }
    for (const auto& h : chains_) {
        const OnlineStatistics s = h->Statistics();
        all.requests += s.requests;
        all.solves += s.solves;
        all.failed_solves += s.failed_solves;
        all.prior_solves += s.prior_solves;
        all.relocalisations += s.relocalisations;
        all.relocalised += s.relocalised;
        all.relocalise_s += s.relocalise_s;
        all.solve_s.insert(all.solve_s.end(), s.solve_s.begin(), s.solve_s.end());
        all.waits += s.waits;
        all.wait_s += s.wait_s;
        if (all.worker_error.empty()) all.worker_error = s.worker_error;
    }
    return all;
}

CorrectionResult OnlineCorrector::Finish() {
    for (const auto& h : chains_) h->StopWorker();
    finished_ = true;
    return chains_.front()->SolveWhole(cfg_.corrector);  // every chain has the poses
}

}  // namespace driftcorr
