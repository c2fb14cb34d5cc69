#pragma once
// What the online (streaming) mode needs from a scenario: the frame conventions, the anchor and
// the map field, without a trajectory (the poses arrive one by one), plus single-pose conversions
// between a trajectory frame and the world plane.
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "driftcorr/optim/online_corrector.h"
#include "driftcorr/optim/verdict.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::pipeline {

struct StreamSetup {
    io::Scenario scenario;
    PlanarAnchor anchor;  ///< trajectory frame -> world plane
    RoadNetwork network;
    TraversableField field;  ///< over the whole road network (the route is not known in advance)
    double scale = 1.0;      ///< the anchor's `scale`: a pose's position times it is metres
    /// `scale: auto`: the scale is found from the stream's leading path (StreamSession); `scale`
    /// holds it once found.
    bool scale_auto = false;
};

/// Loads a scenario's map (its estimate and ground truth are not read) and rasterises the field
/// over the network's bounds grown by config.field.margin_m. Throws InputError as RunCorrection.
StreamSetup LoadStreamSetup(const std::string& scenario_path, const PipelineConfig& config);

/// The same for a scenario already in memory (its estimate and ground truth are not read).
StreamSetup LoadStreamSetup(io::Scenario scenario, const PipelineConfig& config);

/// One pose of the setup's trajectory frame in the world plane (heading from the orientation;
/// the position times `scale`, by default setup.scale).
PlanarPose ToPlanarPose(double t_s, const Eigen::Vector3d& p_frame,
                        const Eigen::Quaterniond& q_frame_body, const StreamSetup& setup,
                        std::optional<double> scale = std::nullopt);

/// Inverse for a corrected pose: position from `corrected`, orientation `q_frame_body` turned
/// about Up by corrected.yaw - reference.yaw (as FromPlanar). Returns (p_frame, q_frame_body).
std::pair<Eigen::Vector3d, Eigen::Quaterniond> FromPlanarPose(
    const PlanarPose& corrected, const PlanarPose& reference, const Eigen::Vector3d& p_frame,
    const Eigen::Quaterniond& q_frame_body, FrameAxes axes, const PlanarAnchor& anchor);

/// One stream on a setup's map, as `driftcorr stream` and the Python `Stream` run it: each pose
/// of the trajectory frame turned into the world plane, pushed to the online corrector, and its
/// causal output turned back into the frame; the accepted poses are kept to turn the smoothed
/// trajectory back into the frame and to judge the stream at its end (JudgeOnline). Push,
/// Finish, Statistics and the sizes may be called from several threads, one at a time: checking
/// a pose against the last one and taking it are one step.
///
/// With `scale: auto` (setup.scale_auto) the online corrector starts once the global scale is
/// found: FitGlobalScale on the poses so far, again each time their path has grown by a quarter,
/// until the best scale's leading path reaches ScaleLeadPathM(); then FindGlobalScale on them
/// (its trial corrections on the setup's field), and the corrector takes every pose so far at
/// that scale. Until then each output is the input at the best scale so far, flagged
/// kDoubtScaleSearch and without covariance, and the stream's judgement at the end leaves those
/// outputs out (the causal check compares the corrector's outputs only).
class StreamSession {
public:
    /// `pipeline` is read for the scale search of `scale: auto` only.
    StreamSession(StreamSetup setup, const OnlineConfig& config, const VerdictConfig& verdict,
                  const PipelineConfig& pipeline = PipelineConfig{});
    ~StreamSession();
    StreamSession(const StreamSession&) = delete;
    StreamSession& operator=(const StreamSession&) = delete;

    struct Output {
        PushResult result;  ///< the corrector's answer; the fields below only when Accepted()
        PlanarPose input;   ///< the pose in the world plane, as pushed
        Eigen::Vector3d p_frame = Eigen::Vector3d::Zero();  ///< the causal output in the frame
        Eigen::Quaterniond q_frame_body = Eigen::Quaterniond::Identity();
    };
    Output Push(double t_s, const Eigen::Vector3d& p_frame, const Eigen::Quaterniond& q_frame_body);

    struct Ending {
        CorrectionResult result;              ///< the smoothed whole trajectory
        std::optional<OnlineVerdict> judged;  ///< when the result is usable
        /// The smoothed trajectory in the frame, at the accepted poses, when the result is usable.
        std::optional<Trajectory> smoothed;
        /// `scale: auto`: the scale found and its search, and how many outputs came before it
        /// (kDoubtScaleSearch).
        std::optional<GlobalScale> scale;
        std::size_t outputs_before_scale = 0;
    };
    /// Ends the stream; nothing when it has ended already.
    std::optional<Ending> Finish();

    OnlineStatistics Statistics() const;
    std::size_t size() const;      ///< poses the corrector holds
    std::size_t accepted() const;  ///< poses accepted so far
    const StreamSetup& setup() const { return *setup_; }

private:
    Output PushSearchingScale(double t_s, const Eigen::Vector3d& p_frame,
                              const Eigen::Quaterniond& q_frame_body);
    /// The scale of the poses so far (ChooseGlobalScale on `fit`, or on a FitGlobalScale made
    /// here); starts the corrector with them at that scale.
    void StartAtScale(std::optional<ScaleFitResult> fit = std::nullopt);

    std::unique_ptr<StreamSetup> setup_;  ///< owns the field the corrector points to
    PipelineConfig pipeline_;             ///< for the scale search
    OnlineConfig config_;
    VerdictConfig verdict_;
    std::unique_ptr<OnlineCorrector> corrector_;  ///< null while the scale is searched
    // `scale: auto`, while the scale is searched.
    PlanarTrajectory unit_;           ///< the accepted poses in the world plane at scale 1
    double unit_path_ = 0.0;          ///< their path [units of the estimate]
    double next_fit_path_ = 0.0;      ///< the path at which the next FitGlobalScale runs
    double provisional_scale_ = 1.0;  ///< the best scale so far (1 before the first move)
    bool fitted_ = false;             ///< provisional_scale_ comes from a fit
    std::optional<GlobalScale> found_;
    std::size_t before_scale_ = 0;  ///< outputs before the corrector started
    mutable std::mutex mutex_;
    bool finished_ = false;
    Trajectory accepted_;         ///< the accepted inputs, in the frame
    PlanarTrajectory reference_;  ///< the same in the world plane
    PlanarTrajectory causal_;     ///< every causal output, in the world plane
};

}  // namespace driftcorr::pipeline
