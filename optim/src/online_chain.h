#pragma once
// One causal chain of the online corrector (OnlineCorrector holds one per start scale): takes the
// accepted poses, schedules the fixed-lag window solves (optim/fixed_lag.h), runs them on a worker
// thread of lower scheduling priority (or inside Take when synchronous), holds back input that
// runs ahead of the solver (back-pressure), and returns each pose composed onto the newest solved
// window with its covariance carried there. How it schedules, chains and threads its solves:
// docs/method.md, "The online corrector".
#include <array>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "driftcorr/optim/fixed_lag.h"
#include "driftcorr/optim/online_types.h"

namespace driftcorr {

class OnlineChain {
public:
    /// `field` may be null and must outlive this object; `config.corrector.start_scales` is not
    /// read: the chain starts from `start_scale`. With `record_nll` it records the NLL of its
    /// poses after each usable solve (NllAt); with `first_at_chunk` its first solve is at the
    /// chunk rule, none before it. Starts the worker unless config.synchronous.
    OnlineChain(const TraversableField* field, const OnlineConfig& config, double start_scale,
                bool record_nll, bool first_at_chunk);
    ~OnlineChain();  ///< stops the worker (a running solve is finished first)
    OnlineChain(const OnlineChain&) = delete;
    OnlineChain& operator=(const OnlineChain&) = delete;

    /// Why `pose` cannot follow the accepted ones (time, non-finite, heading), or nullopt.
    std::optional<PushResult> Validate(const PlanarPose& pose) const;
    /// Takes a validated pose and returns its causal estimate (waits first for back-pressure).
    PushResult Take(const PlanarPose& pose, bool ahead_of_real_time);
    void StopWorker();  ///< a running solve is finished first; no further ones

    std::size_t size() const { return t_s_.size(); }  ///< accepted poses (the caller's thread)
    OnlineStatistics Statistics() const;
    /// The batch correction (CorrectFromStarts under `config`) of every accepted pose.
    CorrectionResult SolveWhole(const CorrectorConfig& config) const;

    /// (end, NLL of poses [1, end]) after each usable solve, ends increasing (record_nll); read
    /// under the lock that Lock returns.
    const std::vector<std::pair<std::size_t, double>>& NllAt() const { return nll_at_; }
    std::unique_lock<std::mutex> Lock() const { return std::unique_lock<std::mutex>(mutex_); }

private:
    struct Entry {  ///< one accepted pose, as handed to the solver
        PoseState initial;
        StepObservation step;
    };
    Entry MakeEntry(const PlanarPose& pose, double yaw_unwrapped);
    double FrontScale(int segment) const;
    double FrontBias(int segment) const;  ///< solved heading-rate bias (0: none solved)
    /// The output pose: `pose` moved into the corridor (project_output); false outside the map.
    bool ProjectOutput(PoseState& pose) const;
    void UpdateSchedule(std::size_t index);
    bool SpeedJump(double t_s);
    void Request(std::size_t end);
    void WaitForSolver(PushResult& r);
    void WorkerLoop();
    void RunSolve(std::size_t end);
    /// The whole prefix [0, end] solved as the batch solves it, and the solution the chain
    /// continues from if it does (OnlineConfig::relocalise_min_m). Worker.
    std::optional<FixedLagSolution> Relocalise(std::size_t end);
    /// The batch's initial state (BatchState) of the accepted poses [0, end]; reads entries_
    /// (the worker: under mutex_).
    TrajectoryState BatchStateOf(std::size_t end, const CorrectorConfig& config) const;
    void Merge(const FixedLagSolution& solution, double solve_s);
    void Recompose(std::size_t end);
    void ChainPose(std::size_t i);

    const TraversableField* field_;
    OnlineConfig cfg_;
    bool fix_height_ = true;
    double start_scale_ = 1.0;
    bool record_nll_ = false;
    bool first_at_chunk_ = false;

    // Caller-thread-only state (never touched by the worker).
    std::optional<bool> has_yaw_;
    bool heading_known_ = false;  ///< without yaw: a moving step has been seen
    double last_t_s_ = 0.0, last_yaw_u_ = 0.0, path_m_ = 0.0, chunk_start_path_m_ = 0.0,
           update_path_m_ = 0.0;
    Eigen::Vector3d last_p_ = Eigen::Vector3d::Zero();
    std::size_t chunk_start_ = 0;
    // Written by the caller thread under mutex_ (read by the worker under it, by the caller
    // without it).
    std::vector<double> t_s_;
    std::vector<Entry> entries_;        ///< every accepted pose, for SolveWhole and Relocalise
    std::size_t last_request_end_ = 0;  ///< end of the newest request so far (0: none)
    /// The input's (time, path) over the last 0.6 s, and until when a speed jump in it puts the
    /// outputs in doubt (kDoubtOdometry).
    std::deque<std::pair<double, double>> recent_path_;
    double odometry_doubt_until_s_ = -1e300;
    /// Since the last speed jump: the heading (unwrapped) at the end of its episode, the first
    /// pose turned by kFixingTurnRad from it, and whether the outputs stay in doubt until a solve
    /// reaches that pose.
    std::optional<double> episode_yaw_u_;
    std::optional<std::size_t> fixing_turn_;
    bool awaiting_turn_ = false;
    /// The previous output before projection, its covariance (East-North) and whether it had one;
    /// the solves merged when it was taken; whether the newest solve since moved it outside its
    /// 95 % region, and by how much (kDoubtMoved).
    Eigen::Vector2d last_out_en_ = Eigen::Vector2d::Zero();
    Eigen::Matrix2d last_out_xy_m2_ = Eigen::Matrix2d::Zero();
    bool last_out_cov_ok_ = false;
    std::size_t solves_seen_ = 0;
    bool moved_ = false;
    Eigen::Vector2d moved_by_m_ = Eigen::Vector2d::Zero();
    /// OnlineConfig::calibrate_covariance: the outputs that a window may still move (index,
    /// position before projection, the model's covariance East-North, whether in doubt for the
    /// odometry, kDoubtOdometry), and the normalised squared differences d^T Sigma^-1 d of those
    /// that no window moves any more, counted in bins of log10 from 1e-6 to 1e6: the stream's
    /// quantiles in bounded memory: of every output ([0]), and of those in doubt for the odometry
    /// ([1]), which are scaled by the larger of the two factors.
    struct Output {
        std::size_t index = 0;
        Eigen::Vector2d p_en = Eigen::Vector2d::Zero();
        Eigen::Matrix2d xy_m2 = Eigen::Matrix2d::Zero();
        bool odometry_doubt = false;
    };
    struct Settled {
        std::array<std::size_t, 240> bins{};
        std::size_t count = 0;
        double factor = 1.0;  ///< the factor they give (QuantileFactor)
    };
    std::deque<Output> unsettled_;
    std::array<Settled, 2> settled_;

    // Shared with the worker, guarded by mutex_.
    mutable std::mutex mutex_;
    std::condition_variable wake_;           ///< a request, or stop
    std::condition_variable solved_;         ///< a solve merged (back-pressure)
    std::deque<Entry> pending_;              ///< accepted poses not yet handed to the solver
    std::size_t pending_first_ = 0;          ///< stream index of pending_.front()
    bool requested_ = false;                 ///< a solve is wanted (the newest pose's window)
    std::size_t request_end_ = 0;            ///< the requested end (synchronous mode's window end)
    bool busy_ = false;                      ///< the worker is solving
    std::vector<PoseState> current_;         ///< latest estimate of every accepted pose
    std::vector<StepObservation> steps_;     ///< observation of every accepted pose
    std::vector<int> segment_;               ///< scale segment of every accepted pose
    std::vector<int> bias_segment_;          ///< heading-rate bias segment of every accepted pose
    std::vector<double> front_scales_{1.0};  ///< solved scales, up to the last solved segment
    std::vector<double> front_biases_;       ///< solved biases, up to the last solved segment
    std::size_t solved_end_ = 0;             ///< last pose of the newest merged solve
    std::size_t settled_before_ = 0;         ///< the newest merged solve moved no pose before
    PoseMatrix chain_sigma_ = PoseMatrix::Zero();  ///< covariance of the newest pose's estimate
    bool chain_sigma_ok_ = true;
    bool stop_ = false;
    bool chain_poor_ = false;   ///< the newest merged solve failed the restart test (PoorWindow)
    bool relocalised_ = false;  ///< the chain was re-localised since the last output
    OnlineStatistics stats_;
    std::vector<std::pair<std::size_t, double>> nll_at_;

    // Worker-only.
    std::unique_ptr<FixedLagSmoother> solver_;
    double next_check_m_ = 0.0;  ///< the path from which a re-localisation may run [m]
    std::thread worker_;
};

}  // namespace driftcorr
