#pragma once
// The online (streaming) corrector: Push(pose) returns a causal corrected estimate of that pose at
// once, composed onto the newest solved fixed-lag window (optim/fixed_lag.h), never raw dead
// reckoning; Finish() returns the smoothed whole trajectory, solved as the batch mode does
// (CorrectFromStarts). The same cost terms, map field and incremental machinery as the batch
// corrector (IncrementalCorrector). A worker thread (synchronous = false) solves the window that
// ends at the newest pose whenever it is free; Push then never solves, holds one mutex for O(1)
// work, and waits only for back-pressure on input faster than real time (synchronous = true: Push
// solves a requested window before it returns). With several start scales
// (CorrectorConfig::start_scales) one hypothesis runs per start scale and each output comes from
// the one of lowest NLL. Without headings in the input, the heading of pose i is the direction of
// the step into pose i (turns seen one step late); do not mix poses with and without heading.
// Push and Finish must be called from one thread. How it schedules, chains, scores and threads
// its solves ("How a pose is estimated", "Start scales", "Threading"): docs/method.md, "The
// online corrector"; measured: docs/results.md, "Online output".
#include <chrono>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "driftcorr/optim/correction_result.h"
#include "driftcorr/optim/online_types.h"

namespace driftcorr {

class OnlineChain;

class OnlineCorrector {
public:
    /// The input counts as faster than real time when its stream time over the last
    /// kPaceWindow poses advanced more than kAheadFactor times the wall time (outside Push).
    static constexpr std::size_t kPaceWindow = 10;
    static constexpr double kAheadFactor = 2.0;
    /// With start scales: another hypothesis replaces the chosen one only when its NLL is lower
    /// by more than this share of the chosen one's (docs/method.md, "Start scales").
    static constexpr double kNllTie = 1e-3;

    /// `field` may be null (odometry only) and must outlive this object. Precondition:
    /// config.Validate() is empty.
    OnlineCorrector(const TraversableField* field, const OnlineConfig& config);
    ~OnlineCorrector();  ///< stops the worker (a running solve is finished first)
    OnlineCorrector(const OnlineCorrector&) = delete;
    OnlineCorrector& operator=(const OnlineCorrector&) = delete;

    /// Adds the next pose and returns its causal estimate. Rejected poses leave the state
    /// unchanged; the stream continues with the next valid pose.
    PushResult Push(const PlanarPose& pose);

    /// Stops the worker (a running solve is finished first) and solves the whole trajectory as
    /// the batch mode does (from each start scale, chunks, then the hard-corridor refinement if
    /// config.corrector.refine; the lowest NLL kept).
    /// Needs >= 3 accepted poses, else status kFailed with a message. Call once.
    CorrectionResult Finish();

    std::size_t size() const;  ///< accepted poses
    OnlineStatistics Statistics() const;

private:
    bool AheadOfRealTime(double t_s);
    /// With several chains: the output of the chosen one (ChooseChain), its covariance the
    /// mixture's (MixtureCovariance).
    PushResult TakeHypotheses(const PlanarPose& pose, bool ahead_of_real_time);
    void ChooseChain();
    PoseCovariance MixtureCovariance(const std::vector<PushResult>& results) const;

    OnlineConfig cfg_;
    bool finished_ = false;
    /// One causal chain per start scale (optim/src/online_chain.h); each gets every pose.
    std::vector<std::unique_ptr<OnlineChain>> chains_;
    std::size_t chosen_ = 0;       ///< the chain whose outputs Push returns
    std::size_t chosen_at_ = 0;    ///< the solve end it was chosen at (0: not yet)
    std::vector<double> weights_;  ///< each chain's weight there (empty: not yet)
    /// With several chains: the outputs' ages (the solves' are the chains').
    mutable std::mutex stats_mutex_;
    OnlineStatistics output_stats_;

    /// The input's pace: stream time and wall time outside Push (waits excluded) of the last
    /// kPaceWindow poses, oldest first.
    std::deque<std::pair<double, double>> pace_;
    double outside_s_ = 0.0;  ///< wall time spent outside Push since the first pose [s]
    std::chrono::steady_clock::time_point push_returned_{};
};

}  // namespace driftcorr
