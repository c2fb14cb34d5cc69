#pragma once
// The edge between Python and the library: numpy arrays and dicts in, library types out, and
// back. Every conversion of a caller's argument checks it and throws pybind11::value_error (or
// type_error) whose message starts with the argument's name ("trajectory: row 3, column 2 (y) is
// NaN"); nothing is clamped or filled in.
//
// Array layouts (float64, one row per pose):
//  - a trajectory in its own frame: (N, 8) `t x y z qx qy qz qw` (TUM), or (N, 4) `t x y z`
//    without orientation. t [s] strictly increasing, positions [m], unit quaternion T_frame_body
//    (normalised on input; a zero quaternion is an error).
//  - a trajectory in the world plane (East-North-Up at the anchor): (N, 5) `t east north up yaw`
//    or (N, 4) `t east north up` without heading; yaw [rad] counter-clockwise from East.
//  - per-pose covariance: (N, 8) `t var_e cov_en var_n var_up var_yaw cov_e_yaw cov_n_yaw`
//    ([m^2], [rad^2], [m rad]).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <optional>
#include <string>

#include "driftcorr/core/metrics.h"
#include "driftcorr/core/types.h"
#include "driftcorr/io/scenario.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/online_corrector.h"
#include "driftcorr/pipeline/pipeline.h"

namespace driftcorr::python {

namespace py = pybind11;

/// A str or os.PathLike argument as a string. Throws value_error for None, type_error otherwise,
/// naming `name`.
std::string PathOf(const py::handle& value, const std::string& name);

/// A trajectory in its own frame from an (N, 8) or (N, 4) array (or anything numpy converts to
/// one), at least `min_poses` rows. Throws value_error / type_error naming `name`.
Trajectory TrajectoryFromArray(const py::handle& obj, const std::string& name,
                               std::size_t min_poses = 3);
/// (N, 8) with orientation, (N, 4) without.
py::array_t<double> TrajectoryToArray(const Trajectory& traj);

/// A world-plane trajectory from an (N, 5) or (N, 4) array. Throws naming `name`.
PlanarTrajectory PlanarFromArray(const py::handle& obj, const std::string& name);
/// (N, 5) with heading, (N, 4) without.
py::array_t<double> PlanarToArray(const PlanarTrajectory& traj);

/// One pose of a stream: 8 values `t x y z qx qy qz qw` (the stream needs the orientation).
struct FramePose {
    double t_s = 0.0;
    Eigen::Vector3d p_frame = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q_frame_body = Eigen::Quaterniond::Identity();
};
FramePose FramePoseFromArray(const py::handle& obj, const std::string& name);
py::array_t<double> FramePoseToArray(double t_s, const Eigen::Vector3d& p,
                                     const Eigen::Quaterniond& q);
py::array_t<double> PlanarPoseToArray(const PlanarPose& pose);

/// Covariance rows (layout above) with timestamps from `t_s`; precondition: same size.
py::array_t<double> CovarianceToArray(const std::vector<double>& t_s,
                                      const std::vector<PoseCovariance>& poses);
/// One pose's covariance as (7,): var_e cov_en var_n var_up var_yaw cov_e_yaw cov_n_yaw.
py::array_t<double> PoseCovarianceToArray(const PoseCovariance& c);

py::dict MetricsToDict(const ErrorMetrics& m);

/// A scenario built from Python values, as scenario.yaml would give it: `mode` ("road2d" |
/// "indoor3d"), `frame` ("kitti_camera" | "enu"), `anchor` (a dict with the keys of the
/// scenario's `anchor:` block), `map` (a layer path, or a list of paths and dicts with the keys of
/// a `map:` entry: path, format, role, floor_z_m). Relative paths are taken from the working
/// directory. Throws value_error / type_error naming the argument and key.
io::Scenario ScenarioFromParts(const std::string& name, const py::handle& mode,
                               const py::handle& frame, const py::handle& anchor,
                               const py::handle& map);

/// The parts of a loaded scenario in the form ScenarioFromParts accepts.
py::dict AnchorToDict(const io::AnchorSpec& anchor);
py::list MapToList(const std::vector<io::MapLayerSpec>& layers);

/// The run's configuration: defaults, or a params.yaml (`config`: None or a path), and the
/// solver ("driftcorr" | "paper"). Throws InputError for a bad file, value_error for `solver`.
pipeline::PipelineConfig ConfigFrom(const py::handle& config, const std::string& solver);

}  // namespace driftcorr::python
