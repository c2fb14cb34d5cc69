// The definitions of what driftcorr/pipeline/online.h declares.
#include "driftcorr/pipeline/online.h"

#include <stdexcept>
#include <tuple>
#include <utility>

#include "driftcorr/core/errors.h"

namespace driftcorr::pipeline {

StreamSetup LoadStreamSetup(const std::string& scenario_path, const PipelineConfig& config) {
    return LoadStreamSetup(io::LoadScenario(scenario_path), config);
}

StreamSetup LoadStreamSetup(io::Scenario scenario, const PipelineConfig& config) {
    StreamSetup setup;
    setup.scenario = std::move(scenario);
    const io::Scenario& sc = setup.scenario;
    if (!sc.anchor.yaw_deg || sc.anchor.position_search_m > 0.0) {
        throw InputError(sc.yaml_path, 0,
                         sc.anchor.yaw_deg ? "anchor.position_search_m" : "anchor.yaw_deg",
                         "a start estimated from the map (yaw_deg: auto, position_search_m) needs "
                         "the whole trajectory: use correct, or give the start for stream");
    }
    if (sc.anchor.scale_auto) {
        throw InputError(sc.yaml_path, 0, "anchor.scale",
                         "scale: auto finds the scale from the drive's leading kilometre, which a "
                         "stream does not have yet: correct a recording with scale: auto, then "
                         "stream with the scale it found (scale: S)");
    }
    setup.scale = sc.anchor.scale;
    std::unique_ptr<WorldFrame> world;
    try {
        world = std::make_unique<WorldFrame>(sc.anchor);
    } catch (const InputError& e) {
        throw InputError(sc.yaml_path, 0, e.key(), e.what());
    }
    setup.anchor = world->planar_anchor();
    // The route is not known in advance: the field covers the whole map (for roads, the region
    // is unbounded and RasteriseRoads clips it to the network's extent).
    const Eigen::AlignedBox2d everywhere(Eigen::Vector2d(-1e7, -1e7), Eigen::Vector2d(1e7, 1e7));
    setup.field = LoadMapField(sc, *world, config, everywhere, sc.anchor.z_m, setup.network);
    return setup;
}

PlanarPose ToPlanarPose(double t_s, const Eigen::Vector3d& p_frame,
                        const Eigen::Quaterniond& q_frame_body, const StreamSetup& setup) {
    Trajectory one;
    one.t_s = {t_s};
    one.p_frame = {setup.scale * p_frame};
    one.q_frame_body = {q_frame_body};
    const PlanarTrajectory planar = ToPlanar(one, setup.scenario.frame, setup.anchor);
    PlanarPose out;
    out.t_s = t_s;
    out.p_en = planar.p_en[0];
    out.up_m = planar.up_m[0];
    out.yaw_rad = planar.yaw_rad[0];
    return out;
}

std::pair<Eigen::Vector3d, Eigen::Quaterniond> FromPlanarPose(
    const PlanarPose& corrected, const PlanarPose& reference, const Eigen::Vector3d& p_frame,
    const Eigen::Quaterniond& q_frame_body, FrameAxes axes, const PlanarAnchor& anchor) {
    auto planar = [](const PlanarPose& p) {
        PlanarTrajectory t;
        t.t_s = {p.t_s};
        t.p_en = {p.p_en};
        t.up_m = {p.up_m};
        if (p.yaw_rad) t.yaw_rad = {*p.yaw_rad};
        return t;
    };
    Trajectory original;
    original.t_s = {reference.t_s};
    original.p_frame = {p_frame};
    original.q_frame_body = {q_frame_body};
    const Trajectory out = FromPlanar(planar(corrected), planar(reference), original, axes, anchor);
    return {out.p_frame[0], out.q_frame_body[0]};
}

StreamSession::StreamSession(StreamSetup setup, const OnlineConfig& config,
                             const VerdictConfig& verdict)
    : setup_(std::make_unique<StreamSetup>(std::move(setup))),
      config_(config),
      verdict_(verdict),
      corrector_(std::make_unique<OnlineCorrector>(&setup_->field, config)) {}

StreamSession::~StreamSession() = default;

StreamSession::Output StreamSession::Push(double t_s, const Eigen::Vector3d& p_frame,
                                          const Eigen::Quaterniond& q_frame_body) {
    Output out;
    out.input = ToPlanarPose(t_s, p_frame, q_frame_body, *setup_);
    const std::lock_guard<std::mutex> lock(mutex_);
    out.result = corrector_->Push(out.input);
    if (!out.result.Accepted()) return out;
    std::tie(out.p_frame, out.q_frame_body) =
        FromPlanarPose(out.result.corrected, out.input, p_frame, q_frame_body,
                       setup_->scenario.frame, setup_->anchor);
    accepted_.t_s.push_back(t_s);
    accepted_.p_frame.push_back(p_frame);
    accepted_.q_frame_body.push_back(q_frame_body);
    reference_.t_s.push_back(out.input.t_s);
    reference_.p_en.push_back(out.input.p_en);
    reference_.up_m.push_back(out.input.up_m);
    reference_.yaw_rad.push_back(*out.input.yaw_rad);
    causal_.t_s.push_back(out.result.corrected.t_s);
    causal_.p_en.push_back(out.result.corrected.p_en);
    causal_.up_m.push_back(out.result.corrected.up_m);
    return out;
}

std::optional<StreamSession::Ending> StreamSession::Finish() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return std::nullopt;
    finished_ = true;
    Ending end;
    end.result = corrector_->Finish();
    if (!Usable(end.result.status)) return end;
    end.judged = JudgeOnline(reference_, causal_, &setup_->field, config_.corrector.model,
                             end.result, verdict_);
    end.smoothed = FromPlanar(end.result.corrected, reference_, accepted_, setup_->scenario.frame,
                              setup_->anchor);
    return end;
}

OnlineStatistics StreamSession::Statistics() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return corrector_->Statistics();
}

std::size_t StreamSession::size() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return corrector_->size();
}

std::size_t StreamSession::accepted() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return accepted_.size();
}

}  // namespace driftcorr::pipeline
