#pragma once
// Writers of the generated scenario folder: OSM XML, TUM trajectories and scenario.yaml
// (see docs/FORMAT.md). Every file is written to a temporary name and renamed when
// complete, so a failed run leaves no half-written file.
#include <string>
#include <vector>

#include "driftcorr/mapping/geodesy.h"
#include "drive.h"
#include "road_network.h"
#include "synth_common.h"

namespace driftcorr::synth {

/// Writes `net` as OSM XML 0.6, nodes converted from East-North (plane's origin) to WGS84.
/// Throws std::runtime_error naming the file when it cannot be written.
void WriteOsmFile(const std::string& path, const RoadNetwork& net, const LocalTangentPlane& plane);

/// Writes "t x y z qx qy qz qw" lines (z = 0, orientation = yaw about z). Throws like WriteOsmFile.
void WriteTumFile(const std::string& path, const std::vector<DrivePose>& poses);

/// Writes scenario.yaml (mode road2d, frame enu, the given anchor with yaw 0, files estimate.tum,
/// ground_truth.tum, map.osm) after `header_comment` (lines without the leading "# ").
void WriteScenarioYaml(const std::string& path, const GeoPoint& anchor,
                       const std::vector<std::string>& header_comment);

}  // namespace driftcorr::synth
