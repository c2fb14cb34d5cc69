// The definitions of what online_chain.h declares.
#include "online_chain.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <string>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "driftcorr/core/angles.h"
#include "driftcorr/core/format.h"
#include "driftcorr/optim/corrector.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/incremental_corrector.h"

namespace driftcorr {
namespace {

// kDoubtOdometry: the input's speed is compared over windows of kSpeedWindowS (three KITTI
// frames, as the verdict's input-jump test and the dropped-step repair do), and a jump keeps the
// outputs in doubt for kSpeedEpisodeS (the longest episode the repair takes), and beyond it until
// a solve has seen the estimate turn by kFixingTurnRad from its heading at the episode's end:
// what the dropped steps lost, and the step-length scale the windows took from them, lie along
// the track, which the map fixes only where the road turns after the episode.
constexpr double kSpeedWindowS = 0.3, kSpeedEpisodeS = 10.0;
constexpr double kFixingTurnRad = 30.0 * kPi / 180.0;
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

// Whether a solve moved a pose by `d` outside the 95 % region of its covariance `xy_m2`, which
// must be known (`ok`) and positive definite (kDoubtMoved, relocalise_when_moved).
bool MovedOutside(const Eigen::Vector2d& d, const Eigen::Matrix2d& xy_m2, bool ok) {
    return ok && xy_m2.determinant() > 0.0 && !InsideRegion95(d, xy_m2);
}

// The bins of the outputs' normalised squared differences (OnlineChain::Settled::bins):
// kBinsPerDecade bins per decade of d^T Sigma^-1 d from 10^kLowestDecade; smaller values count
// in the first bin, larger ones in the last.
constexpr int kBinsPerDecade = 20, kLowestDecade = -6;
// chi2 with 2 degrees of freedom at 0.95: the 95 % region's bound on d^T Sigma^-1 d.
constexpr double kChi2Two95 = 5.991;
// The fewest outputs whose 95 % quantile leaves one beyond it.
constexpr std::size_t kMinSettled = 20;

template <std::size_t N>
void Count(std::array<std::size_t, N>& bins, double nis) {
    const double at = (std::log10(std::max(nis, 1e-300)) - kLowestDecade) * kBinsPerDecade;
    const double clamped = std::clamp(at, 0.0, double(N - 1));
    ++bins[static_cast<std::size_t>(clamped)];
}

// The factor on the outputs' covariance (OnlineConfig::calibrate_covariance): the upper edge
// of the bin that holds the 95 % quantile of the `n` values counted, over kChi2Two95; at least
// 1.
template <std::size_t N>
double QuantileFactor(const std::array<std::size_t, N>& bins, std::size_t n) {
    if (n < kMinSettled) return 1.0;
    const auto rank = static_cast<std::size_t>(std::ceil(0.95 * double(n)));
    std::size_t seen = 0;
    for (std::size_t b = 0; b < N; ++b) {
        seen += bins[b];
        if (seen >= rank) {
            const double upper = std::pow(10.0, kLowestDecade + double(b + 1) / kBinsPerDecade);
            return std::max(1.0, upper / kChi2Two95);
        }
    }
    return 1.0;
}

void Scale(PoseCovariance& c, double k) {
    c.xy_m2 *= k;
    c.z_m2 *= k;
    c.yaw_rad2 *= k;
    c.xy_yaw_m_rad *= k;
}

}  // namespace

OnlineChain::OnlineChain(const TraversableField* field, const OnlineConfig& config,
                         double start_scale, bool record_nll, bool first_at_chunk)
    : field_(field),
      cfg_(config),
      fix_height_(!field || field->planar()),
      start_scale_(start_scale),
      record_nll_(record_nll),
      first_at_chunk_(first_at_chunk) {
    front_scales_ = {start_scale_};
    next_check_m_ = cfg_.relocalise_min_m;
    if (!cfg_.synchronous) worker_ = std::thread([this] { WorkerLoop(); });
}

OnlineChain::~OnlineChain() { StopWorker(); }

void OnlineChain::StopWorker() {
    if (!worker_.joinable()) return;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;  // a running solve is finished; no further ones
    }
    wake_.notify_all();
    worker_.join();
}

// The reasons a pose cannot follow the accepted ones, or nullopt.
std::optional<PushResult> OnlineChain::Validate(const PlanarPose& pose) const {
    auto reject = [](PushStatus status, std::string message) {
        PushResult r;
        r.status = status;
        r.message = std::move(message);
        return r;
    };
    if (!t_s_.empty() && !(pose.t_s > last_t_s_)) {
        return reject(PushStatus::kRejectedTime, "timestamp " + FormatFixed(pose.t_s, 6) +
                                                     " is not after the previous one (" +
                                                     FormatFixed(last_t_s_, 6) + ")");
    }
    if (has_yaw_ && *has_yaw_ != pose.yaw_rad.has_value()) {
        return reject(PushStatus::kRejectedHeading,
                      *has_yaw_ ? "pose has no heading, the stream started with headings"
                                : "pose has a heading, the stream started without");
    }
    return std::nullopt;
}

// The output pose: moved into the corridor (project_output, where the final solve's hard
// constraint would hold it: within corridor_gate_m); false where it lies outside the map field.
bool OnlineChain::ProjectOutput(PoseState& pose) const {
    if (!field_) return true;
    const auto q = field_->Query(pose.p);
    if (!q) return false;
    const ModelConfig& m = cfg_.corrector.model;
    if (cfg_.project_output && m.hard_corridor && q->corridor.value <= m.corridor_gate_m)
        MoveIntoCorridor(*field_, *q, m.corridor_slack_m, pose.p);
    return true;
}

OnlineStatistics OnlineChain::Statistics() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stats_;
}

// The step from the previous accepted pose (same formulas as ComputeObservations).
OnlineChain::Entry OnlineChain::MakeEntry(const PlanarPose& pose, double yaw_u) {
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

double OnlineChain::FrontScale(int segment) const {
    return segment < static_cast<int>(front_scales_.size()) ? front_scales_[segment]
                                                            : front_scales_.back();
}

double OnlineChain::FrontBias(int segment) const {
    if (front_biases_.empty()) return 0.0;
    return segment < static_cast<int>(front_biases_.size()) ? front_biases_[segment]
                                                            : front_biases_.back();
}

PushResult OnlineChain::Take(const PlanarPose& pose, bool ahead_of_real_time) {
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
        entries_.push_back(entry);
        t_s_.push_back(pose.t_s);
    }
    last_t_s_ = pose.t_s;
    last_p_ = entry.initial.p;
    last_yaw_u_ = yaw_u;
    path_m_ += entry.step.length_m;
    if (SpeedJump(pose.t_s)) {
        odometry_doubt_until_s_ = pose.t_s + kSpeedEpisodeS;
        episode_yaw_u_.reset();
        fixing_turn_.reset();
        awaiting_turn_ = true;
    }
    if (awaiting_turn_ && !episode_yaw_u_ && pose.t_s > odometry_doubt_until_s_) {
        episode_yaw_u_ = yaw_u;
    }
    if (episode_yaw_u_ && !fixing_turn_ && std::abs(yaw_u - *episode_yaw_u_) >= kFixingTurnRad) {
        fixing_turn_ = r.index;
    }
    const std::size_t requested_before = last_request_end_;
    UpdateSchedule(r.index);  // synchronous: solves here
    PoseState out;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        // A solve merged since the previous output: where it puts that pose now, against the
        // region the output claimed.
        if (r.index > 0 && stats_.solves != solves_seen_) {
            moved_by_m_ = current_[r.index - 1].p.head<2>() - last_out_en_;
            moved_ = MovedOutside(moved_by_m_, last_out_xy_m2_, last_out_cov_ok_);
        }
        // The outputs whose poses no window solves any more: their final estimates against
        // what the outputs claimed.
        while (!unsettled_.empty() && unsettled_.front().index < settled_before_) {
            const Output& o = unsettled_.front();
            const Eigen::Vector2d d = current_[o.index].p.head<2>() - o.p_en;
            const double nis = d.dot(o.xy_m2.inverse() * d);
            const auto add = [nis](Settled& s) {
                Count(s.bins, nis);
                s.factor = QuantileFactor(s.bins, ++s.count);
            };
            add(settled_[0]);
            if (o.odometry_doubt) add(settled_[1]);
            unsettled_.pop_front();
        }
        solves_seen_ = stats_.solves;
        if (awaiting_turn_ && fixing_turn_ && solved_end_ >= *fixing_turn_) awaiting_turn_ = false;
        const bool odometry = pose.t_s <= odometry_doubt_until_s_ || awaiting_turn_;
        if (odometry) r.doubt |= kDoubtOdometry;
        out = current_[r.index];
        r.correction_age_epochs = r.index - std::min(solved_end_, r.index);
        r.fresh = solved_end_ >= requested_before;
        r.covariance = ToPoseCovariance(chain_sigma_);
        r.covariance_ok = chain_sigma_ok_;
        if (stats_.solves == 0) {
            // Before the first solve the output is the odometry from the start at the prior's
            // step-length scale, which errs by scale_prior_sigma of the displacement so far.
            const Eigen::Vector2d d = out.p.head<2>() - current_.front().p.head<2>();
            const double sd = cfg_.corrector.model.scale_prior_sigma;
            r.covariance.xy_m2 += sd * sd * d * d.transpose();
        }
        last_out_en_ = out.p.head<2>();
        last_out_xy_m2_ = r.covariance.xy_m2;  // the model's: kDoubtMoved judges against it
        last_out_cov_ok_ = r.covariance_ok;
        if (cfg_.calibrate_covariance && r.covariance_ok) {
            if (r.covariance.xy_m2.determinant() > 0.0) {
                unsettled_.push_back({r.index, last_out_en_, r.covariance.xy_m2, odometry});
            }
            Scale(r.covariance,
                  odometry ? std::max(settled_[0].factor, settled_[1].factor) : settled_[0].factor);
        }
        if (moved_) {
            // Two estimates of the chain, the newest solve's and the one before, each as likely:
            // their mixture about the newest.
            r.doubt |= kDoubtMoved;
            if (r.covariance_ok) r.covariance.xy_m2 += 0.5 * moved_by_m_ * moved_by_m_.transpose();
        }
        if (chain_poor_) r.doubt |= kDoubtPoorWindow;
        if (relocalised_) r.doubt |= kDoubtRelocalised;
        relocalised_ = false;
        const ModelConfig& m = cfg_.corrector.model;
        const double scale = FrontScale(segment_[r.index]);
        if (scale < m.scale_range_min || scale > m.scale_range_max) r.doubt |= kDoubtScale;
        r.correction_age_s = pose.t_s - t_s_[r.index - r.correction_age_epochs];
        ++stats_.poses;
        if (!r.fresh) ++stats_.stale_poses;
        if (r.ahead_of_real_time) ++stats_.ahead_poses;
        stats_.max_age_epochs = std::max(stats_.max_age_epochs, r.correction_age_epochs);
        stats_.max_age_s = std::max(stats_.max_age_s, r.correction_age_s);
    }
    if (!ProjectOutput(out)) {
        r.outside_map = true;
        r.doubt |= kDoubtOffMap;
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

// Back-pressure, before a pose is taken: waits while the previous pose is more than
// max_lag_epochs past the last solved pose and the worker has a solve to do (a request or a
// running solve); only while the input runs ahead of real time unless hold_live_input; never
// waits for a solve that nobody asked for (no path since the last one), nor after a worker
// failure.
void OnlineChain::WaitForSolver(PushResult& r) {
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

// Whether the input's speed over the last kSpeedWindowS changed faster than
// model.outlier_accel_mps2 against the kSpeedWindowS before it (the verdict's input-jump test and
// the dropped-step repair's, made causal). Caller thread.
bool OnlineChain::SpeedJump(double t_s) {
    recent_path_.emplace_back(t_s, path_m_);
    while (recent_path_.size() > 2 && recent_path_[1].first <= t_s - 2.0 * kSpeedWindowS) {
        recent_path_.pop_front();
    }
    const auto& [t0, p0] = recent_path_.front();
    if (t_s - t0 < 2.0 * kSpeedWindowS - 1e-9) return false;  // not two windows of input yet
    // The pose nearest the middle of the span.
    auto mid = recent_path_.begin();
    for (auto it = recent_path_.begin(); it != recent_path_.end(); ++it) {
        if (std::abs(it->first - (t_s - kSpeedWindowS)) <
            std::abs(mid->first - (t_s - kSpeedWindowS)))
            mid = it;
    }
    if (!(mid->first > t0 && t_s > mid->first)) return false;
    const double before = (mid->second - p0) / (mid->first - t0);
    const double after = (path_m_ - mid->second) / (t_s - mid->first);
    return std::abs(after - before) / (0.5 * (t_s - t0)) > cfg_.corrector.model.outlier_accel_mps2;
}

// Requests a solve every update_fraction * chunk_m of path and where the batch rule completes a
// chunk (chunk_m of path or max_chunk_poses poses). Without headings, nothing is solved before
// the first moving step (the poses' heading is not known yet).
void OnlineChain::UpdateSchedule(std::size_t index) {
    if (index == 0 || (has_yaw_ && !*has_yaw_ && !heading_known_)) return;
    if (path_m_ - chunk_start_path_m_ >= cfg_.corrector.chunk_m ||
        index - chunk_start_ >= cfg_.corrector.max_chunk_poses) {
        chunk_start_ = index;
        chunk_start_path_m_ = path_m_;
        update_path_m_ = path_m_;
        Request(index);
    } else if (cfg_.update_fraction > 0.0 && !(first_at_chunk_ && last_request_end_ == 0) &&
               path_m_ - update_path_m_ >= cfg_.update_fraction * cfg_.corrector.chunk_m) {
        update_path_m_ = path_m_;
        Request(index);
    }
}

void OnlineChain::Request(std::size_t end) {
    last_request_end_ = end;
    if (cfg_.synchronous) {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            ++stats_.requests;
        }
        RunSolve(end);
        return;
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        ++stats_.requests;
        requested_ = true;
        request_end_ = end;
    }
    wake_.notify_one();
}

// Takes the newest request: the window that ends at the newest accepted pose (requests made
// while a solve was running are merged into it: skipped, not queued).
void OnlineChain::WorkerLoop() {
    LowerWorkerPriority();
    for (;;) {
        std::size_t end = 0;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [this] { return stop_ || requested_; });
            if (stop_) return;  // Finish solves the whole trajectory itself
            end = std::max(request_end_, pending_first_ + pending_.size() - 1);
            requested_ = false;
            busy_ = true;
        }
        try {
            RunSolve(end);
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
void OnlineChain::RunSolve(std::size_t end) {
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
    // Every window is checked as the batch's windows are, and re-solved from the other scale
    // hypotheses where it fell into a wrong basin (SolveSoftWindow): a chain that took a turn
    // before its junction, its scale collapsing to hold the poses on the road they left, would
    // otherwise carry that scale on through the boundary prior.
    FixedLagSolution solution = solver_->Solve(end, true);
    const double solve_s = SecondsSince(t0);
    bool relocalised = false;
    if (cfg_.relocalise_min_m > 0.0 && field_ && solution.usable) {
        const ModelConfig& m = cfg_.corrector.model;
        const double scale = solution.scales.back();
        const double path = solver_->PathTo(end);
        bool moved = false;  // the solve puts pose `end` outside the chain's region for it
        if (cfg_.relocalise_when_moved && end >= solution.first) {
            std::lock_guard<std::mutex> lock(mutex_);
            const Eigen::Matrix2d xy_m2 = ToPoseCovariance(chain_sigma_).xy_m2;
            moved = end < current_.size() &&
                    MovedOutside(solution.poses[end - solution.first].p.head<2>() -
                                     current_[end].p.head<2>(),
                                 xy_m2, chain_sigma_ok_);
        }
        if ((solution.poor || scale < m.scale_range_min || scale > m.scale_range_max || moved) &&
            path >= next_check_m_) {
            next_check_m_ = path + std::max(cfg_.relocalise_min_m, cfg_.relocalise_share * path);
            const auto t1 = std::chrono::steady_clock::now();
            if (std::optional<FixedLagSolution> adopted = Relocalise(end)) {
                solution = std::move(*adopted);
                relocalised = true;
            }
            std::lock_guard<std::mutex> lock(mutex_);
            ++stats_.relocalisations;
            stats_.relocalise_s += SecondsSince(t1);
        }
    }
    const bool record = record_nll_ && solution.usable;
    const double nll = record ? solver_->Nll(solution.end) : 0.0;
    std::lock_guard<std::mutex> lock(mutex_);
    if (relocalised) {
        ++stats_.relocalised;
        relocalised_ = true;
    }
    Merge(solution, solve_s);
    if (record) nll_at_.emplace_back(solution.end, nll);
    busy_ = false;
    solved_.notify_all();
}

// The prefix [0, end] corrected as the batch corrects a drive, from the chain's start scale. The
// chain continues from that correction when its own poses (each as its last window solved it)
// score an NLL more than relocalise_nll_ratio times the correction's (both as
// FixedLagSmoother::Nll scores them): the chain lost the map, not a window's worth of detail.
std::optional<FixedLagSolution> OnlineChain::Relocalise(std::size_t end) {
    CorrectorConfig config = cfg_.corrector;
    config.start_scales = {start_scale_};
    config.compute_covariance = true;
    std::optional<TrajectoryState> initial;
    std::vector<double> t_s;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        t_s.assign(t_s_.begin(), t_s_.begin() + end + 1);
        initial = BatchStateOf(end, config);
    }
    CorrectionResult result;
    const IncrementalCorrector inc =
        CorrectFromStarts(std::move(*initial), t_s, field_, config, result);
    if (!Usable(result.status)) return std::nullopt;
    TrajectoryState solved = inc.state();
    const double nll = SoftNll(solved, field_, cfg_.corrector.model, end);
    if (!(solver_->Nll(end) > cfg_.relocalise_nll_ratio * nll)) return std::nullopt;
    std::vector<double> scales(end + 1), biases;
    for (std::size_t i = 0; i <= end; ++i) scales[i] = solved.scales[solved.scale_segment[i]];
    if (!solved.bias_segment.empty()) {
        biases.resize(end + 1);
        for (std::size_t i = 0; i <= end; ++i) biases[i] = solved.biases[solved.bias_segment[i]];
    }
    FixedLagSolution adopted = solver_->Adopt(solved.poses, scales, biases);
    if (result.covariance.status == CovarianceStatus::kOk) {
        adopted.end_covariance = result.covariance.poses[end];
        adopted.end_covariance_ok = true;
    }
    return adopted;
}

// Replaces the causal estimates of the solved window and re-composes the poses pushed since.
// Caller holds mutex_.
void OnlineChain::Merge(const FixedLagSolution& sol, double solve_s) {
    ++stats_.solves;
    stats_.solve_s.push_back(solve_s);
    if (sol.boundary_prior) ++stats_.prior_solves;
    if (!sol.usable) ++stats_.failed_solves;
    for (std::size_t i = sol.first; i <= sol.end; ++i) current_[i] = sol.poses[i - sol.first];
    front_scales_ = sol.scales;
    front_biases_ = sol.biases;
    solved_end_ = sol.end;
    settled_before_ = sol.first;
    chain_poor_ = sol.poor;
    chain_sigma_ok_ = sol.end_covariance_ok;
    if (chain_sigma_ok_) chain_sigma_ = ToPoseMatrix(sol.end_covariance);
    Recompose(sol.end);
}

// Re-composes the causal estimates after `end` onto the (newly solved) pose `end`, and carries
// its covariance (chain_sigma_, set to pose end's) to the newest pose. Caller holds mutex_.
void OnlineChain::Recompose(std::size_t end) {
    for (std::size_t i = end + 1; i < current_.size(); ++i) ChainPose(i);
}

// Pose i's estimate composed onto pose i-1's with the newest solved scale and heading-rate bias,
// and chain_sigma_ carried through that step (current_[i] holds its height in planar mode).
// Caller holds mutex_.
void OnlineChain::ChainPose(std::size_t i) {
    const double scale = FrontScale(segment_[i]);
    chain_sigma_ = PropagateStep(chain_sigma_, current_[i - 1], steps_[i], scale, fix_height_,
                                 cfg_.corrector.model);
    current_[i] = ComposeStep(current_[i - 1], steps_[i], scale, fix_height_, current_[i].p.z(),
                              FrontBias(bias_segment_[i]));
}

// The batch's initial state of poses [0, end] as pushed (pose 0 the start).
TrajectoryState OnlineChain::BatchStateOf(std::size_t end, const CorrectorConfig& config) const {
    std::vector<StepObservation> obs(1);
    std::vector<PoseState> poses(1, entries_.front().initial);
    for (std::size_t i = 1; i <= end; ++i) {
        obs.push_back(entries_[i].step);
        poses.push_back(entries_[i].initial);
    }
    return BatchState(std::move(obs), std::move(poses), config, fix_height_);
}

CorrectionResult OnlineChain::SolveWhole(const CorrectorConfig& config) const {
    CorrectionResult result;
    if (t_s_.size() < 3) {
        result.message = "need at least 3 accepted poses, have " + std::to_string(t_s_.size());
        return result;
    }
    // The batch solve over the same observations (the online solves do not change it).
    CorrectWithStepReading(
        [&](const CorrectorConfig& c) { return BatchStateOf(entries_.size() - 1, c); }, t_s_,
        field_, config, result);
    // The input as pushed, judged against the correction as the batch judges it.
    PlanarTrajectory input;
    input.t_s = t_s_;
    for (const Entry& e : entries_) {
        input.p_en.push_back(e.initial.p.head<2>());
        input.up_m.push_back(e.initial.p.z());
        input.yaw_rad.push_back(e.initial.yaw_rad);
    }
    KeepAgreeingInput(input, field_, config, result);
    DiagnoseCorrection(input, field_, config, result);
    return result;
}

}  // namespace driftcorr
