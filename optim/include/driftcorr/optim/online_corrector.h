#pragma once
// The online (streaming) corrector: Push(pose) returns a causal corrected estimate of that pose at
// once; Finish() returns the smoothed whole trajectory. The same cost terms, map field and
// incremental machinery as the batch corrector (IncrementalCorrector).
//
// How a pose is estimated
//  - Push computes the observation of the new step (from the previous accepted pose) and returns
//    the pose dead-reckoned by composing that odometry onto the latest corrected pose with the
//    latest step-length scale: O(1), no solve on the Push path (in the default, threaded mode).
//  - When a chunk of chunk_m path (or max_chunk_poses poses) is complete, the trailing window of
//    window_m is re-solved by IncrementalCorrector::SolveChunk, warm-started from the previous
//    solution plus the dead-reckoned new poses. Its solution replaces the causal estimates of the
//    window's poses, and the poses pushed meanwhile are re-composed onto it, so later outputs
//    continue from the corrected state. Already returned outputs are not changed (causal).
//  - Between chunk ends, every update_fraction * chunk_m of path, the trailing window ending at
//    the newest pose is solved once more for the causal output only (a preview:
//    IncrementalCorrector::SolvePreview, on a copy, one solve without restarts; the chunk sequence
//    is unchanged). Its poses replace the causal estimates as a chunk solve's would, so the output
//    follows the map between chunks instead of dead-reckoning up to chunk_m. In the threaded mode
//    a preview that is no longer the newest queued job is skipped.
//  - Poses leaving the window are summarised, not forgotten, in what the window keeps fixed: the
//    boundary pose (treated as exact: no marginalisation prior/covariance is carried) and the
//    step-length scale of earlier segments, tied to the window's scale by the scale random walk.
//  - The chunk boundaries follow the batch rule exactly, so the sequence of window solves does not
//    depend on timing: Finish() (last partial chunk + the hard-corridor refinement) gives the batch
//    result when the input carries headings (up to Ipopt's own run-to-run variation).
//
// Headings: with an orientation (PlanarPose::yaw_rad) the observation of a step is causal as in
// the batch mode. Without one, the batch mode takes a pose's heading from the *next* step
// (non-causal); here the heading of pose i is the direction of the step *into* pose i (carried
// across stops; the poses before the first moving step take its direction), so turns are seen
// one step late. Do not mix poses with and without heading in one stream.
//
// Threading model (synchronous = false): one worker thread owns the IncrementalCorrector and runs
// the window solves. Push (the caller's thread) and the worker share, under one mutex: the queue
// of poses not yet handed to the solver, the queue of completed chunk ends, and the causal
// estimates with the latest scales. Push holds the mutex for O(1) work; the worker holds it only
// to take the queued poses of one chunk and to merge a solution (O(window) copies), never while
// solving. If the worker falls behind, chunks queue up and are solved in order; outputs meanwhile
// are dead-reckoned. Push and Finish must be called from one thread (or serialised by the caller).
// With synchronous = true no thread is started and Push solves a completed chunk before it returns
// (deterministic, but that Push takes as long as the solve).
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "driftcorr/optim/corrector.h"
#include "driftcorr/optim/incremental_corrector.h"

namespace driftcorr {

struct OnlineConfig {
    CorrectorConfig corrector;   ///< chunk_m, window_m, model, ... exactly as in batch mode
    bool synchronous = false;    ///< solve inside Push (no worker thread)
    double gap_warn_s = 1.0;     ///< Push flags a step longer than this in time [s]
    /// The returned causal pose is moved into the traversable corridor when it lies outside it but
    /// within corridor.model.corridor_gate_m (what the refinement's hard constraint does to the
    /// smoothed poses), horizontally along the corridor distance gradient, in at most 3 Newton
    /// steps, each taken only where the horizontal slope is >= 0.5 and kept only when it lowers
    /// the distance. Only the output is moved; the solver state is not.
    bool project_output = true;
    /// Path between look-ahead solves for the causal output, as a share of corrector.chunk_m
    /// (0.125: every 10 m with the road chunks of 80 m); 0: only the chunk solves.
    double update_fraction = 0.125;

    /// Empty if valid, else a message naming the bad field.
    std::string Validate() const;
};

/// One pose in the world plane (ENU at the anchor).
struct PlanarPose {
    double t_s = 0.0;
    Eigen::Vector2d p_en = Eigen::Vector2d::Zero();  ///< [m]
    double up_m = 0.0;                               ///< [m]
    std::optional<double> yaw_rad;  ///< heading, CCW from East [rad]; nullopt: from the steps
};

enum class PushStatus {
    kAccepted,
    kRejectedTime,       ///< timestamp not after the previous accepted one (out of order/repeated)
    kRejectedNonFinite,  ///< NaN or inf in any field
    kRejectedHeading,    ///< with a heading when the stream started without one, or vice versa
    kRejectedFinished,   ///< Push after Finish()
};

struct PushResult {
    PushStatus status = PushStatus::kAccepted;
    std::string message;      ///< why rejected, or a warning (gap, outside map); empty otherwise
    std::size_t index = 0;    ///< index of the accepted pose in the stream
    PlanarPose corrected;     ///< causal estimate (valid when accepted); yaw_rad always set
    bool gap = false;         ///< the step took longer than gap_warn_s
    bool outside_map = false; ///< the corrected pose lies outside the map field (odometry only)
    bool Accepted() const { return status == PushStatus::kAccepted; }
};

class OnlineCorrector {
public:
    /// `field` may be null (odometry only) and must outlive this object. Precondition:
    /// config.Validate() is empty.
    OnlineCorrector(const TraversableField* field, const OnlineConfig& config);
    ~OnlineCorrector();  ///< stops the worker (a running solve is finished first)
    OnlineCorrector(const OnlineCorrector&) = delete;
    OnlineCorrector& operator=(const OnlineCorrector&) = delete;

    /// Adds the next pose and returns its causal estimate. Rejected poses leave the state
    /// unchanged; the stream continues with the next valid pose.
    PushResult Push(const PlanarPose& pose);

    /// Waits for queued solves, solves the last partial chunk and refines the whole trajectory
    /// (if config.corrector.refine). Needs >= 3 accepted poses, else status kFailed with a
    /// message. A worker failure is reported in the status and message. Call once.
    CorrectionResult Finish();

    std::size_t size() const;  ///< accepted poses

private:
    struct Entry {  ///< one accepted pose, as handed to the solver
        PoseState initial;
        StepObservation step;
    };
    PushResult Reject(PushStatus status, std::string message) const;
    std::optional<PushResult> Validate(const PlanarPose& pose) const;
    Entry MakeEntry(const PlanarPose& pose, double yaw_unwrapped);
    double FrontScale(int segment) const;
    /// The output pose: `pose` moved into the corridor (project_output); false outside the map.
    bool ProjectOutput(PoseState& pose) const;
    struct Job {  ///< a solve for the worker: a chunk end, or a preview ending at `end`
        std::size_t end = 0;
        bool preview = false;
    };
    void UpdateChunks(std::size_t index);
    void Schedule(Job job);
    void WorkerLoop();
    void RunJob(const Job& job);
    void AppendQueued(std::size_t end);
    void EnsureSolver(std::vector<Entry>& entries);
    void Recompose(std::size_t end);
    void Merge();
    void MergePreview(std::size_t end, const IncrementalCorrector::Preview& p);

    const TraversableField* field_;
    OnlineConfig cfg_;
    bool fix_height_ = true;
    bool finished_ = false;

    // Push-thread-only state (never touched by the worker).
    std::optional<bool> has_yaw_;
    bool heading_known_ = false;  ///< without yaw: a moving step has been seen
    double last_t_s_ = 0.0, last_yaw_u_ = 0.0, path_m_ = 0.0, chunk_start_path_m_ = 0.0,
           update_path_m_ = 0.0;
    Eigen::Vector3d last_p_ = Eigen::Vector3d::Zero();
    std::size_t chunk_start_ = 0;
    std::vector<double> t_s_;

    // Shared with the worker, guarded by mutex_.
    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<Entry> pending_;           ///< accepted poses not yet handed to the solver
    std::size_t pending_first_ = 0;       ///< stream index of pending_.front()
    std::deque<Job> jobs_;                ///< solves not yet run, in order
    std::vector<PoseState> current_;      ///< latest estimate of every accepted pose
    std::vector<StepObservation> steps_;  ///< observation of every accepted pose
    std::vector<int> segment_;            ///< scale segment of every accepted pose
    std::vector<double> front_scales_{1.0};  ///< solved scales, up to the last solved segment
    double front_bias_rad_s_ = 0.0;          ///< the latest solved heading-rate bias
    bool stop_ = false;
    std::string worker_error_;

    // Worker-only (or Finish after the worker stopped).
    std::unique_ptr<IncrementalCorrector> solver_;
    std::thread worker_;
};

}  // namespace driftcorr
