// The definitions of what driftcorr/optim/online_corrector.h declares.
#include "driftcorr/optim/online_corrector.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"
#include "driftcorr/core/format.h"
#include "driftcorr/optim/incremental_corrector.h"

namespace driftcorr {
namespace {

bool Finite(const PlanarPose& p) {
    return std::isfinite(p.t_s) && p.p_en.allFinite() && std::isfinite(p.up_m) &&
           (!p.yaw_rad || std::isfinite(*p.yaw_rad));
}

// The worker runs the solves at a lower scheduling priority than the thread that calls Push, so
// that on a busy or single core an arriving pose pre-empts a running solve instead of waiting for
// its time slice (the output latency is the Push path's, not the solver's): nice + 10, and the
// batch policy (SCHED_BATCH: the scheduler treats the thread as CPU-bound and never lets it
// pre-empt the caller mid-Push; with the nice value alone, one pushed line in about a hundred
// waited out a 1.5 ms slice of the solver on one core). Its fair share of a loaded machine
// is unchanged. Best effort: where the system refuses, the worker keeps the caller's priority.
void LowerWorkerPriority() {
#if defined(__linux__)
    sched_param param{};
    param.sched_priority = 0;
    pthread_setschedparam(pthread_self(), SCHED_BATCH, &param);
    const auto tid = static_cast<id_t>(syscall(SYS_gettid));
    const int nice = getpriority(PRIO_PROCESS, tid);
    setpriority(PRIO_PROCESS, tid, std::min(nice + 10, 19));
#endif
}

double SecondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

PlanarPose ToPlanarPose(double t_s, const PoseState& s) {
    PlanarPose out;
    out.t_s = t_s;
    out.p_en = s.p.head<2>();
    out.up_m = s.p.z();
    out.yaw_rad = s.yaw_rad;
    return out;
}

}  // namespace

std::optional<ParamProblem> OnlineConfig::FindProblem() const {
    return CheckRows(kOnlineParams, *this);
}

std::string OnlineConfig::Validate() const {
    if (std::string m = corrector.Validate(); !m.empty()) return m;
    return ToMessage(kOnlineParams.section, FindProblem());
}

OnlineCorrector::OnlineCorrector(const TraversableField* field, const OnlineConfig& config)
    : field_(field), cfg_(config), fix_height_(!field || field->planar()) {
    DRIFTCORR_CHECK(config.Validate().empty(), "invalid OnlineConfig");
    const std::vector<double>& starts = cfg_.corrector.start_scales;
    if (starts.size() > 1) {
        // The start nearest the scale prior's mean (the first of equally near ones) solves from
        // the first pose and gives the outputs until every hypothesis has solved.
        const double mean = cfg_.corrector.model.scale_prior_mean;
        for (std::size_t k = 1; k < starts.size(); ++k) {
            if (std::abs(starts[k] - mean) < std::abs(starts[chosen_] - mean)) chosen_ = k;
        }
        for (std::size_t k = 0; k < starts.size(); ++k) {
            OnlineConfig one = cfg_;
            one.corrector.start_scales = {starts[k]};
            hypotheses_.emplace_back(new OnlineCorrector(field, one, starts[k], k != chosen_));
        }
        return;
    }
    start_scale_ = starts.front();
    StartSolving();
}

OnlineCorrector::OnlineCorrector(const TraversableField* field, const OnlineConfig& config,
                                 double start_scale, bool first_at_chunk)
    : field_(field),
      cfg_(config),
      fix_height_(!field || field->planar()),
      start_scale_(start_scale),
      record_nll_(true),
      first_at_chunk_(first_at_chunk) {
    StartSolving();
}

void OnlineCorrector::StartSolving() {
    front_scales_ = {start_scale_};
    if (!cfg_.synchronous) worker_ = std::thread([this] { WorkerLoop(); });
}

OnlineCorrector::~OnlineCorrector() { StopWorker(); }

void OnlineCorrector::StopWorker() {
    if (!worker_.joinable()) return;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;  // a running solve is finished; no further ones
    }
    wake_.notify_all();
    worker_.join();
}

std::size_t OnlineCorrector::size() const {
    return hypotheses_.empty() ? t_s_.size() : hypotheses_.front()->size();
}

PushResult OnlineCorrector::Reject(PushStatus status, std::string message) const {
    PushResult r;
    r.status = status;
    r.message = std::move(message);
    return r;
}

// The reasons a pose is not accepted, or nullopt.
std::optional<PushResult> OnlineCorrector::Validate(const PlanarPose& pose) const {
    if (finished_) return Reject(PushStatus::kRejectedFinished, "Push after Finish()");
    if (!Finite(pose)) return Reject(PushStatus::kRejectedNonFinite, "pose has a NaN or inf value");
    if (!t_s_.empty() && !(pose.t_s > last_t_s_)) {
        return Reject(PushStatus::kRejectedTime, "timestamp " + FormatFixed(pose.t_s, 6) +
                                                     " is not after the previous one (" +
                                                     FormatFixed(last_t_s_, 6) + ")");
    }
    if (has_yaw_ && *has_yaw_ != pose.yaw_rad.has_value()) {
        return Reject(PushStatus::kRejectedHeading,
                      *has_yaw_ ? "pose has no heading, the stream started with headings"
                                : "pose has a heading, the stream started without");
    }
    return std::nullopt;
}

// The step from the previous accepted pose (same formulas as ComputeObservations).
OnlineCorrector::Entry OnlineCorrector::MakeEntry(const PlanarPose& pose, double yaw_u) {
    Entry e;
    e.initial.p = Eigen::Vector3d(pose.p_en.x(), pose.p_en.y(), pose.up_m);
    e.initial.yaw_rad = yaw_u;
    if (t_s_.empty()) return e;
    StepObservation& o = e.step;
    const Eigen::Vector2d d = pose.p_en - last_p_.head<2>();
    o.dt_s = pose.t_s - last_t_s_;
    o.length_m = d.norm();
    o.stationary = o.length_m <= cfg_.corrector.stationary_m;
    o.direction_rad = o.stationary ? 0.0 : AngleDiff(std::atan2(d.y(), d.x()), last_yaw_u_);
    o.dheading_rad = yaw_u - last_yaw_u_;
    o.dup_m = pose.up_m - last_p_.z();
    if (o.stationary) o.length_m = 0.0;
    return e;
}

double OnlineCorrector::FrontScale(int segment) const {
    return segment < static_cast<int>(front_scales_.size()) ? front_scales_[segment]
                                                            : front_scales_.back();
}

double OnlineCorrector::FrontBias(int segment) const {
    if (front_biases_.empty()) return 0.0;
    return segment < static_cast<int>(front_biases_.size()) ? front_biases_[segment]
                                                            : front_biases_.back();
}

// The input's pace is measured here once, for the hypotheses too (each one's own Push time would
// count the others' as time outside Push).
PushResult OnlineCorrector::Push(const PlanarPose& pose) {
    const OnlineCorrector& first = hypotheses_.empty() ? *this : *hypotheses_.front();
    if (auto rejected = first.Validate(pose)) return *rejected;  // the hypotheses' alike
    const bool ahead = AheadOfRealTime(pose.t_s);
    PushResult r = hypotheses_.empty() ? Take(pose, ahead) : TakeHypotheses(pose, ahead);
    push_returned_ = std::chrono::steady_clock::now();
    return r;
}

PushResult OnlineCorrector::Take(const PlanarPose& pose, bool ahead_of_real_time) {
    PushResult r;
    r.start_scale = start_scale_;
    r.ahead_of_real_time = ahead_of_real_time;
    WaitForSolver(r);
    if (!has_yaw_) has_yaw_ = pose.yaw_rad.has_value();
    double yaw_u = last_yaw_u_;
    bool first_heading = false;
    if (pose.yaw_rad) {
        yaw_u = t_s_.empty() ? *pose.yaw_rad : last_yaw_u_ + AngleDiff(*pose.yaw_rad, last_yaw_u_);
    } else if (!t_s_.empty()) {
        const Eigen::Vector2d d = pose.p_en - last_p_.head<2>();
        if (d.norm() > cfg_.corrector.stationary_m) {
            const double dir = std::atan2(d.y(), d.x());
            first_heading = !heading_known_;
            if (first_heading) last_yaw_u_ = dir;  // the poses before take its direction
            yaw_u = last_yaw_u_ + AngleDiff(dir, last_yaw_u_);
            heading_known_ = true;
        }
    }
    const Entry entry = MakeEntry(pose, yaw_u);
    r.index = t_s_.size();
    r.gap = !t_s_.empty() && entry.step.dt_s > cfg_.gap_warn_s;
    const int segment =
        r.index == 0 ? 0 : static_cast<int>(path_m_ / cfg_.corrector.model.scale_segment_m);
    const double bias_segment_s = cfg_.corrector.model.heading_bias_segment_s;
    const int bias_segment = r.index == 0 || !(bias_segment_s > 0.0)
                                 ? 0
                                 : static_cast<int>((last_t_s_ - t_s_.front()) / bias_segment_s);
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (first_heading) {
            for (Entry& e : pending_) e.initial.yaw_rad = last_yaw_u_;
            for (Entry& e : entries_) e.initial.yaw_rad = last_yaw_u_;
            for (PoseState& s : current_) s.yaw_rad = last_yaw_u_;
        }
        current_.push_back(entry.initial);
        pending_.push_back(entry);
        steps_.push_back(entry.step);
        segment_.push_back(segment);
        bias_segment_.push_back(bias_segment);
        if (r.index > 0) ChainPose(r.index);
    }
    entries_.push_back(entry);
    t_s_.push_back(pose.t_s);
    last_t_s_ = pose.t_s;
    last_p_ = entry.initial.p;
    last_yaw_u_ = yaw_u;
    path_m_ += entry.step.length_m;
    const std::size_t requested_before = last_request_end_;
    UpdateSchedule(r.index);  // synchronous: solves here
    PoseState out;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        out = current_[r.index];
        r.correction_age_epochs = r.index - std::min(solved_end_, r.index);
        r.fresh = solved_end_ >= requested_before;
        r.covariance = ToPoseCovariance(chain_sigma_);
        r.covariance_ok = chain_sigma_ok_;
        r.correction_age_s = pose.t_s - t_s_[r.index - r.correction_age_epochs];
        ++stats_.poses;
        if (!r.fresh) ++stats_.stale_poses;
        if (r.ahead_of_real_time) ++stats_.ahead_poses;
        stats_.max_age_epochs = std::max(stats_.max_age_epochs, r.correction_age_epochs);
        stats_.max_age_s = std::max(stats_.max_age_s, r.correction_age_s);
    }
    if (!ProjectOutput(out)) {
        r.outside_map = true;
        r.message = "pose is outside the map: corrected by odometry only";
    }
    r.corrected = ToPlanarPose(pose.t_s, out);
    if (r.gap) {
        const std::string msg =
            "gap of " + FormatFixed(entry.step.dt_s, 3) + " s since the previous pose";
        r.message = r.message.empty() ? msg : msg + "; " + r.message;
    }
    return r;
}

PushResult OnlineCorrector::TakeHypotheses(const PlanarPose& pose, bool ahead_of_real_time) {
    std::vector<PushResult> results;
    results.reserve(hypotheses_.size());
    double waited_s = 0.0;
    for (const auto& h : hypotheses_) {
        results.push_back(h->Take(pose, ahead_of_real_time));
        waited_s += results.back().waited_s;
    }
    ChooseHypothesis();
    const PoseCovariance mixture = MixtureCovariance(results);
    PushResult r = std::move(results[chosen_]);
    r.waited_s = waited_s;
    if (r.covariance_ok) r.covariance = mixture;
    std::lock_guard<std::mutex> lock(mutex_);  // the outputs' ages (the solves': Statistics)
    ++stats_.poses;
    if (!r.fresh) ++stats_.stale_poses;
    if (r.ahead_of_real_time) ++stats_.ahead_poses;
    stats_.max_age_epochs = std::max(stats_.max_age_epochs, r.correction_age_epochs);
    stats_.max_age_s = std::max(stats_.max_age_s, r.correction_age_s);
    return r;
}

// The latest solve end with an NLL from every hypothesis (ends newer than the last choice only);
// the hypothesis of lowest NLL there is chosen. Locks every hypothesis's mutex, in order (their
// workers only ever lock their own).
void OnlineCorrector::ChooseHypothesis() {
    std::vector<std::unique_lock<std::mutex>> locks;
    for (const auto& h : hypotheses_) locks.emplace_back(h->mutex_);
    const auto& newest = hypotheses_.front()->nll_at_;
    for (auto it = newest.rbegin(); it != newest.rend() && it->first > chosen_at_; ++it) {
        std::vector<double> nll;
        for (const auto& h : hypotheses_) {
            const auto& at_end = h->nll_at_;
            const auto found = std::lower_bound(at_end.begin(), at_end.end(), it->first,
                                                [](const std::pair<std::size_t, double>& a,
                                                   std::size_t end) { return a.first < end; });
            if (found == at_end.end() || found->first != it->first) break;
            nll.push_back(found->second);
        }
        if (nll.size() < hypotheses_.size()) continue;
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

// Back-pressure, before a pose is taken: waits while the previous pose is more than
// max_lag_epochs past the last solved pose and the worker has a solve to do (a request or a
// running solve); only while the input runs ahead of real time unless hold_live_input; never
// waits for a solve that nobody asked for (no path since the last one), nor after a worker
// failure.
void OnlineCorrector::WaitForSolver(PushResult& r) {
    if (cfg_.synchronous || cfg_.max_lag_epochs == 0 || t_s_.empty()) return;
    if (!cfg_.hold_live_input && !r.ahead_of_real_time) return;
    const std::size_t index = t_s_.size() - 1;
    const auto t0 = std::chrono::steady_clock::now();  // the lock is part of the wait
    std::unique_lock<std::mutex> lock(mutex_);
    auto caught_up = [&] {
        return index - std::min(solved_end_, index) <= cfg_.max_lag_epochs ||
               !(requested_ || busy_) || !stats_.worker_error.empty();
    };
    if (caught_up()) return;
    solved_.wait(lock, caught_up);
    r.waited_s = SecondsSince(t0);
    ++stats_.waits;
    stats_.wait_s += r.waited_s;
}

bool OnlineCorrector::ProjectOutput(PoseState& pose) const {
    if (!field_) return true;
    auto q = field_->Query(pose.p);
    if (!q) return false;
    const ModelConfig& m = cfg_.corrector.model;
    if (!cfg_.project_output || !m.hard_corridor || q->corridor.value > m.corridor_gate_m)
        return true;
    // Only the horizontal position moves. Where the corridor distance falls mostly with height
    // (a pose between floors, on stairs) its horizontal slope is small and a Newton step along it
    // would be long: on a real walk one went 165 m. So a step is taken only where the slope is at
    // least kMinSlope (a step is then at most excess / kMinSlope long, the excess being at most
    // corridor_gate_m), and kept only when it lowers the corridor distance.
    constexpr double kMinSlope = 0.5;
    for (int k = 0; k < 3 && q->corridor.value > m.corridor_slack_m; ++k) {
        const Eigen::Vector2d g = q->corridor.gradient.head<2>();
        const double slope = g.norm();
        if (!(slope >= kMinSlope)) break;
        Eigen::Vector3d p = pose.p;
        p.head<2>() -= (q->corridor.value - m.corridor_slack_m) / slope * (g / slope);
        const auto next = field_->Query(p);
        if (!next || !(next->corridor.value < q->corridor.value)) break;
        pose.p = p;
        q = next;
    }
    return true;
}

// Requests a solve every update_fraction * chunk_m of path, with restarts where the batch rule
// completes a chunk (chunk_m of path or max_chunk_poses poses). Without headings, nothing is
// solved before the first moving step (the poses' heading is not known yet).
void OnlineCorrector::UpdateSchedule(std::size_t index) {
    if (index == 0 || (has_yaw_ && !*has_yaw_ && !heading_known_)) return;
    if (path_m_ - chunk_start_path_m_ >= cfg_.corrector.chunk_m ||
        index - chunk_start_ >= cfg_.corrector.max_chunk_poses) {
        chunk_start_ = index;
        chunk_start_path_m_ = path_m_;
        update_path_m_ = path_m_;
        Request(index, true);
    } else if (cfg_.update_fraction > 0.0 && !(first_at_chunk_ && last_request_end_ == 0) &&
               path_m_ - update_path_m_ >= cfg_.update_fraction * cfg_.corrector.chunk_m) {
        update_path_m_ = path_m_;
        Request(index, false);
    }
}

void OnlineCorrector::Request(std::size_t end, bool restarts) {
    last_request_end_ = end;
    if (cfg_.synchronous) {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            ++stats_.requests;
        }
        RunSolve(end, restarts);
        return;
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        ++stats_.requests;
        requested_ = true;
        request_restarts_ = request_restarts_ || restarts;
        request_end_ = end;
    }
    wake_.notify_one();
}

// Takes the newest request: the window that ends at the newest accepted pose (requests made
// while a solve was running are merged into it: skipped, not queued).
void OnlineCorrector::WorkerLoop() {
    LowerWorkerPriority();
    for (;;) {
        std::size_t end = 0;
        bool restarts = false;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [this] { return stop_ || requested_; });
            if (stop_) return;  // Finish solves the whole trajectory itself
            end = std::max(request_end_, pending_first_ + pending_.size() - 1);
            restarts = request_restarts_;
            requested_ = request_restarts_ = false;
            busy_ = true;
        }
        try {
            RunSolve(end, restarts);
        } catch (const std::exception& e) {
            std::lock_guard<std::mutex> lock(mutex_);
            stats_.worker_error = std::string("window solve failed: ") + e.what();
            busy_ = false;
            solved_.notify_all();
            return;
        }
    }
}

// Hands the queued poses up to `end` to the solver (holding the mutex only to take them), solves
// the window ending at `end` and merges it. On the worker (or inside Push when synchronous).
void OnlineCorrector::RunSolve(std::size_t end, bool restarts) {
    std::vector<Entry> entries;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        while (pending_first_ <= end) {
            entries.push_back(pending_.front());
            pending_.pop_front();
            ++pending_first_;
        }
    }
    std::size_t k = 0;
    if (!solver_) {
        solver_ = std::make_unique<FixedLagSmoother>(entries.front().initial, fix_height_, field_,
                                                     cfg_.corrector, cfg_.boundary_prior,
                                                     cfg_.boundary_scale, start_scale_);
        k = 1;
    }
    for (; k < entries.size(); ++k) solver_->Append(entries[k].initial, entries[k].step);
    if (end <= solver_->solved_end()) {  // nothing new to solve
        std::lock_guard<std::mutex> lock(mutex_);
        busy_ = false;
        solved_.notify_all();
        return;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const FixedLagSolution solution = solver_->Solve(end, restarts);
    const bool record = record_nll_ && solution.usable;
    const double nll = record ? solver_->Nll(solution.end) : 0.0;
    const double solve_s = SecondsSince(t0);
    std::lock_guard<std::mutex> lock(mutex_);
    Merge(solution, solve_s);
    if (record) nll_at_.emplace_back(solution.end, nll);
    busy_ = false;
    solved_.notify_all();
}

// Replaces the causal estimates of the solved window and re-composes the poses pushed since.
// Caller holds mutex_.
void OnlineCorrector::Merge(const FixedLagSolution& sol, double solve_s) {
    ++stats_.solves;
    stats_.solve_s.push_back(solve_s);
    if (sol.boundary_prior) ++stats_.prior_solves;
    if (!sol.usable) ++stats_.failed_solves;
    for (std::size_t i = sol.first; i <= sol.end; ++i) current_[i] = sol.poses[i - sol.first];
    front_scales_ = sol.scales;
    front_biases_ = sol.biases;
    solved_end_ = sol.end;
    chain_sigma_ok_ = sol.end_covariance_ok;
    if (chain_sigma_ok_) chain_sigma_ = ToPoseMatrix(sol.end_covariance);
    Recompose(sol.end);
}

// Re-composes the causal estimates after `end` onto the (newly solved) pose `end`, and carries
// its covariance (chain_sigma_, set to pose end's) to the newest pose. Caller holds mutex_.
void OnlineCorrector::Recompose(std::size_t end) {
    for (std::size_t i = end + 1; i < current_.size(); ++i) ChainPose(i);
}

// Pose i's estimate composed onto pose i-1's with the newest solved scale and heading-rate bias,
// and chain_sigma_ carried through that step (current_[i] holds its height in planar mode).
// Caller holds mutex_.
void OnlineCorrector::ChainPose(std::size_t i) {
    const double scale = FrontScale(segment_[i]);
    chain_sigma_ = PropagateStep(chain_sigma_, current_[i - 1], steps_[i], scale, fix_height_,
                                 cfg_.corrector.model);
    current_[i] = ComposeStep(current_[i - 1], steps_[i], scale, fix_height_, current_[i].p.z(),
                              FrontBias(bias_segment_[i]));
}

OnlineStatistics OnlineCorrector::Statistics() const {
    if (hypotheses_.empty()) {
        std::lock_guard<std::mutex> lock(mutex_);
        return stats_;
    }
    // The ages of the outputs returned (each from its chosen hypothesis), the solves and waits
    // of every hypothesis.
    OnlineStatistics all;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        all = stats_;
    }
    for (const auto& h : hypotheses_) {
        const OnlineStatistics s = h->Statistics();
        all.requests += s.requests;
        all.solves += s.solves;
        all.failed_solves += s.failed_solves;
        all.prior_solves += s.prior_solves;
        all.solve_s.insert(all.solve_s.end(), s.solve_s.begin(), s.solve_s.end());
        all.waits += s.waits;
        all.wait_s += s.wait_s;
        if (all.worker_error.empty()) all.worker_error = s.worker_error;
    }
    return all;
}

CorrectionResult OnlineCorrector::Finish() {
    for (const auto& h : hypotheses_) {
        h->StopWorker();
        h->finished_ = true;
    }
    StopWorker();
    finished_ = true;
    if (hypotheses_.empty()) return SolveWhole(cfg_.corrector);
    return hypotheses_.front()->SolveWhole(cfg_.corrector);  // every hypothesis has the poses
}

CorrectionResult OnlineCorrector::SolveWhole(const CorrectorConfig& config) const {
    CorrectionResult result;
    if (t_s_.size() < 3) {
        result.message = "need at least 3 accepted poses, have " + std::to_string(t_s_.size());
        return result;
    }
    // The batch solve over the same observations (the online solves do not change it).
    std::vector<StepObservation> obs(1);
    std::vector<PoseState> poses(1, entries_.front().initial);
    for (std::size_t i = 1; i < entries_.size(); ++i) {
        obs.push_back(entries_[i].step);
        poses.push_back(entries_[i].initial);
    }
    CorrectFromStarts(BatchState(std::move(obs), std::move(poses), config, fix_height_), t_s_,
                      field_, config, result);
    return result;
}

}  // namespace driftcorr
