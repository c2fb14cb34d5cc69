#pragma once
// What the online (streaming) mode needs from a scenario: the frame conventions, the anchor and
// the map field, without a trajectory (the poses arrive one by one), plus single-pose conversions
// between a trajectory frame and the world plane.
#include <string>
#include <utility>

#include "driftcorr/optim/online_corrector.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::pipeline {

struct StreamSetup {
    io::Scenario scenario;
    PlanarAnchor anchor;  ///< trajectory frame -> world plane
    RoadNetwork network;
    TraversableField field;  ///< over the whole road network (the route is not known in advance)
    double scale = 1.0;      ///< the anchor's `scale`: a pose's position times it is metres
};

/// Loads a scenario's map (its estimate and ground truth are not read) and rasterises the field
/// over the network's bounds grown by config.field.margin_m. Throws InputError as RunCorrection.
StreamSetup LoadStreamSetup(const std::string& scenario_path, const PipelineConfig& config);

/// The same for a scenario already in memory (its estimate and ground truth are not read).
StreamSetup LoadStreamSetup(io::Scenario scenario, const PipelineConfig& config);

/// One pose of the setup's trajectory frame in the world plane (heading from the orientation;
/// the position times setup.scale).
PlanarPose ToPlanarPose(double t_s, const Eigen::Vector3d& p_frame,
                        const Eigen::Quaterniond& q_frame_body, const StreamSetup& setup);

/// Inverse for a corrected pose: position from `corrected`, orientation `q_frame_body` turned
/// about Up by corrected.yaw - reference.yaw (as FromPlanar). Returns (p_frame, q_frame_body).
std::pair<Eigen::Vector3d, Eigen::Quaterniond> FromPlanarPose(
    const PlanarPose& corrected, const PlanarPose& reference, const Eigen::Vector3d& p_frame,
    const Eigen::Quaterniond& q_frame_body, FrameAxes axes, const PlanarAnchor& anchor);

}  // namespace driftcorr::pipeline
