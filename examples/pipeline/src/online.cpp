#include "driftcorr/pipeline/online.h"

#include <stdexcept>
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

}  // namespace driftcorr::pipeline
