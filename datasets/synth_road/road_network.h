#pragma once
// The synthetic road network of driftcorr_make_road_scenario, built in the local East-North plane
// [m] around the scenario anchor. Deterministic: it does not depend on the seed.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace driftcorr::synth {

/// A map node: OSM id and position in the local East-North plane [m].
struct RoadNode {
    std::int64_t id = 0;
    Eigen::Vector2d p_en = Eigen::Vector2d::Zero();
};

/// An OSM way: ordered indices into RoadNetwork::nodes, with its `highway` and `name` tags.
struct RoadWay {
    std::int64_t id = 0;
    std::string highway;
    std::string name;
    std::vector<int> node_indices;
};

/// A node that carries a `highway` tag itself (a street lamp) and belongs to no way.
struct TaggedNode {
    int node_index = 0;
    std::string highway;
};

struct RoadNetwork {
    std::vector<RoadNode> nodes;
    std::vector<RoadWay> ways;
    std::vector<TaggedNode> tagged_nodes;
};

/// Named places of the network that the drive refers to (East-North [m]).
struct NetworkLandmarks {
    Eigen::Vector2d curve_apex_en;    ///< the easternmost node of the curved road
    double parallel_north_y_m = 0.0;  ///< northing of the northern street of the close pair
    double parallel_south_y_m = 0.0;  ///< northing of the southern street of the close pair
};

/// True for the highway classes a car may drive on (residential, tertiary, secondary, service).
bool IsVehicleRoad(const std::string& highway);

/// Builds the whole network: an irregular street grid (about 1.2 km x 1.0 km), one secondary and
/// one tertiary through-road, a curved road (half ellipse, a node every ~5 m), two parallel streets
/// 25 m apart, footway/cycleway ways 6.5-7 m beside roads, a dead-end service road and one street
/// lamp node. Junctions are shared nodes; node and way ids are positive and unique.
RoadNetwork BuildRoadNetwork();

/// The landmarks of the network built by BuildRoadNetwork().
NetworkLandmarks RoadNetworkLandmarks();

}  // namespace driftcorr::synth
