#include "driftcorr/optim/online_corrector.h"

#include "driftcorr/core/format.h"

#include <cassert>
#include <cmath>
#include <exception>

#include "driftcorr/core/angles.h"

namespace driftcorr {
namespace {

bool Finite(const PlanarPose& p) {
    return std::isfinite(p.t_s) && p.p_en.allFinite() && std::isfinite(p.up_m) &&
           (!p.yaw_rad || std::isfinite(*p.yaw_rad));
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

std::string OnlineConfig::Validate() const {
    if (std::string m = corrector.Validate(); !m.empty()) return m;
    if (!(gap_warn_s > 0.0)) return "online.gap_warn_s: must be > 0";
    if (!(update_fraction >= 0.0 && update_fraction <= 1.0)) {
        return "online.update_fraction: must be in [0, 1]";
    }
    return "";
}

OnlineCorrector::OnlineCorrector(const TraversableField* field, const OnlineConfig& config)
    : field_(field), cfg_(config), fix_height_(!field || field->planar()) {
    assert(config.Validate().empty() && "invalid OnlineConfig");
    if (!cfg_.synchronous) worker_ = std::thread([this] { WorkerLoop(); });
}

OnlineCorrector::~OnlineCorrector() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
        jobs_.clear();  // queued solves are not needed any more
    }
    wake_.notify_all();
    if (worker_.joinable()) worker_.join();
}

std::size_t OnlineCorrector::size() const { return t_s_.size(); }

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
        return Reject(PushStatus::kRejectedTime,
                      "timestamp " + FormatFixed(pose.t_s, 6) + " is not after the previous one (" +
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

PushResult OnlineCorrector::Push(const PlanarPose& pose) {
    if (auto rejected = Validate(pose)) return *rejected;
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
    PushResult r;
    r.index = t_s_.size();
    r.gap = !t_s_.empty() && entry.step.dt_s > cfg_.gap_warn_s;
    const int segment =
        r.index == 0 ? 0 : static_cast<int>(path_m_ / cfg_.corrector.model.scale_segment_m);
    PoseState out;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (first_heading) {
            for (Entry& e : pending_) e.initial.yaw_rad = last_yaw_u_;
            for (PoseState& s : current_) s.yaw_rad = last_yaw_u_;
        }
        out = r.index == 0 ? entry.initial
                           : ComposeStep(current_.back(), entry.step, FrontScale(segment),
                                         fix_height_, entry.initial.p.z(), front_bias_rad_s_);
        pending_.push_back(entry);
        current_.push_back(out);
        steps_.push_back(entry.step);
        segment_.push_back(segment);
    }
    t_s_.push_back(pose.t_s);
    last_t_s_ = pose.t_s;
    last_p_ = entry.initial.p;
    last_yaw_u_ = yaw_u;
    path_m_ += entry.step.length_m;
    UpdateChunks(r.index);
    if (cfg_.synchronous) out = current_[r.index];  // solved if this pose completed a chunk
    if (!ProjectOutput(out)) {
        r.outside_map = true;
        r.message = "pose is outside the map: corrected by odometry only";
    }
    r.corrected = ToPlanarPose(pose.t_s, out);
    if (r.gap) {
        const std::string msg = "gap of " + FormatFixed(entry.step.dt_s, 3) + " s since the previous pose";
        r.message = r.message.empty() ? msg : msg + "; " + r.message;
    }
    return r;
}

bool OnlineCorrector::ProjectOutput(PoseState& pose) const {
    if (!field_) return true;
    auto q = field_->Query(pose.p);
    if (!q) return false;
    const ModelConfig& m = cfg_.corrector.model;
    if (!cfg_.project_output || !m.hard_corridor || q->corridor.value > m.corridor_gate_m) return true;
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

// Completes a chunk at `index` by the batch rule and hands it to the solver; otherwise, every
// update_fraction * chunk_m of path, asks for a preview ending at `index`. Without headings,
// nothing is solved before the first moving step (the poses' heading is not known yet).
void OnlineCorrector::UpdateChunks(std::size_t index) {
    if (index == 0 || (has_yaw_ && !*has_yaw_ && !heading_known_)) return;
    if (path_m_ - chunk_start_path_m_ >= cfg_.corrector.chunk_m ||
        index - chunk_start_ >= cfg_.corrector.max_chunk_poses) {
        chunk_start_ = index;
        chunk_start_path_m_ = path_m_;
        update_path_m_ = path_m_;
        Schedule({index, false});
    } else if (cfg_.update_fraction > 0.0 &&
               path_m_ - update_path_m_ >= cfg_.update_fraction * cfg_.corrector.chunk_m) {
        update_path_m_ = path_m_;
        Schedule({index, true});
    }
}

void OnlineCorrector::Schedule(Job job) {
    if (cfg_.synchronous) {
        RunJob(job);
        return;
    }
    {
        std::lock_guard<std::mutex> lock(mutex_);
        jobs_.push_back(job);
    }
    wake_.notify_one();
}

void OnlineCorrector::WorkerLoop() {
    for (;;) {
        Job job;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
            if (jobs_.empty()) return;  // stop_ and nothing queued
            job = jobs_.front();
            jobs_.pop_front();
            // A preview is worth its solve only while nothing newer waits; at the end
            // (stop_), only the chunks matter.
            if (job.preview && (stop_ || !jobs_.empty())) continue;
        }
        try {
            RunJob(job);
        } catch (const std::exception& e) {
            std::lock_guard<std::mutex> lock(mutex_);
            worker_error_ = std::string("window solve failed: ") + e.what();
            jobs_.clear();
            return;
        }
    }
}

// Creates the solver from the first accepted pose (removed from `entries`).
void OnlineCorrector::EnsureSolver(std::vector<Entry>& entries) {
    if (solver_ || entries.empty()) return;
    solver_ = std::make_unique<IncrementalCorrector>(entries.front().initial, fix_height_, field_,
                                                     cfg_.corrector);
    entries.erase(entries.begin());
}

// Hands the queued poses up to `end` to the solver (holding the mutex only to take them).
void OnlineCorrector::AppendQueued(std::size_t end) {
    std::vector<Entry> entries;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        while (pending_first_ <= end) {
            entries.push_back(pending_.front());
            pending_.pop_front();
            ++pending_first_;
        }
    }
    EnsureSolver(entries);
    for (const Entry& e : entries) solver_->Append(e.initial, e.step);
}

// Runs one solve and merges its solution. On the worker (or inside Push when synchronous); holds
// the mutex only to take the poses and to merge, never while solving.
void OnlineCorrector::RunJob(const Job& job) {
    AppendQueued(job.end);
    if (job.preview) {
        const IncrementalCorrector::Preview p = solver_->SolvePreview(job.end);
        std::lock_guard<std::mutex> lock(mutex_);
        MergePreview(job.end, p);
        return;
    }
    solver_->SolveChunk(job.end);
    std::lock_guard<std::mutex> lock(mutex_);
    Merge();
}

// Re-composes the causal estimates after `end` onto the (newly solved) pose `end`.
// Caller holds mutex_.
void OnlineCorrector::Recompose(std::size_t end) {
    for (std::size_t i = end + 1; i < current_.size(); ++i) {
        current_[i] = ComposeStep(current_[i - 1], steps_[i], FrontScale(segment_[i]), fix_height_,
                                  current_[i].p.z(), front_bias_rad_s_);
    }
}

// Replaces the causal estimates of the solved window and re-composes the poses pushed since.
// Caller holds mutex_.
void OnlineCorrector::Merge() {
    const TrajectoryState& s = solver_->state();
    const std::size_t end = solver_->done();
    for (std::size_t i = solver_->last_window_first(); i <= end; ++i) current_[i] = s.poses[i];
    front_scales_.assign(s.scales.begin(), s.scales.begin() + s.scale_segment[end] + 1);
    front_bias_rad_s_ = s.bias_segment.empty() ? 0.0 : s.biases[s.bias_segment[end]];
    Recompose(end);
}

// The same for a preview (nothing to merge when its solve failed). Caller holds mutex_.
void OnlineCorrector::MergePreview(std::size_t end, const IncrementalCorrector::Preview& p) {
    if (p.poses.empty()) return;
    for (std::size_t i = p.first; i <= end; ++i) current_[i] = p.poses[i - p.first];
    front_scales_ = p.scales;
    front_bias_rad_s_ = p.bias_rad_s;
    Recompose(end);
}

CorrectionResult OnlineCorrector::Finish() {
    if (worker_.joinable()) {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            stop_ = true;  // the worker solves the queued chunks, then exits
        }
        wake_.notify_all();
        worker_.join();
    }
    finished_ = true;
    CorrectionResult result;
    if (!worker_error_.empty()) {
        result.message = worker_error_;
        return result;
    }
    if (t_s_.size() < 3) {
        result.message = "need at least 3 accepted poses, have " + std::to_string(t_s_.size());
        return result;
    }
    std::vector<Entry> entries(pending_.begin(), pending_.end());
    pending_.clear();
    pending_first_ = t_s_.size();
    EnsureSolver(entries);
    for (const Entry& e : entries) solver_->Append(e.initial, e.step);
    solver_->SolveRemaining();
    return solver_->Finish(t_s_);
}

}  // namespace driftcorr
