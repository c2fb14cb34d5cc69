#include "driftcorr/pipeline/online.h"

#include <stdexcept>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/osm_reader.h"

namespace driftcorr::pipeline {
namespace {

// Road map of all osm layers. Throws InputError when no layer yields a usable road.
// (The same rules as RunCorrection's loader in pipeline.cpp.)
RoadNetwork LoadStreamRoads(const io::Scenario& sc, const WorldFrame& world,
                            const RoadClassConfig& roads) {
    RoadNetwork net;
    for (const io::MapLayerSpec& layer : sc.map) {
        if (layer.format != io::MapFormat::kOsm) {
            throw InputError(sc.yaml_path, 0, "map",
                             "road2d mode reads OpenStreetMap layers only; '" + layer.path +
                                 "' is " + io::ToString(layer.format));
        }
        const OsmRoads osm = ReadOsmRoads(layer.path);
        RoadNetwork part = BuildRoadNetwork(
            osm, [&](const GeoPoint& g) { return world.ToEn(g); }, roads);
        if (part.roads.empty()) {
            throw InputError(layer.path, 0, "", "no usable roads in the '" + roads.profile +
                                                    "' profile");
        }
        for (auto& r : part.roads) net.roads.push_back(std::move(r));
    }
    return net;
}

}  // namespace

StreamSetup LoadStreamSetup(const std::string& scenario_path, const PipelineConfig& config) {
    StreamSetup setup;
    setup.scenario = io::LoadScenario(scenario_path);
    const io::Scenario& sc = setup.scenario;
    if (sc.mode != io::ScenarioMode::kRoad2d) {
        throw InputError(sc.yaml_path, 0, "mode", "indoor3d scenarios are not supported yet");
    }
    std::unique_ptr<WorldFrame> world;
    try {
        world = std::make_unique<WorldFrame>(sc.anchor);
    } catch (const InputError& e) {
        throw InputError(sc.yaml_path, 0, e.key(), e.what());
    }
    setup.anchor = world->planar_anchor();
    setup.network = LoadStreamRoads(sc, *world, config.roads);
    try {
        setup.field = RasteriseRoads(setup.network, setup.network.Bounds(), config.field);
    } catch (const std::invalid_argument& e) {
        throw InputError(sc.yaml_path, 0, "map", e.what());
    }
    return setup;
}

PlanarPose ToPlanarPose(double t_s, const Eigen::Vector3d& p_frame,
                        const Eigen::Quaterniond& q_frame_body, FrameAxes axes,
                        const PlanarAnchor& anchor) {
    Trajectory one;
    one.t_s = {t_s};
    one.p_frame = {p_frame};
    one.q_frame_body = {q_frame_body};
    const PlanarTrajectory planar = ToPlanar(one, axes, anchor);
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
    const Trajectory out =
        FromPlanar(planar(corrected), planar(reference), original, axes, anchor);
    return {out.p_frame[0], out.q_frame_body[0]};
}

}  // namespace driftcorr::pipeline
