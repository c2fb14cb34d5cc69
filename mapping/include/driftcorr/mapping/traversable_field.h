#pragma once
// The map prior as a field: where a platform can be. One interface serves the planar road mode
// (a one-slice grid) and the 3D indoor mode.
#include <optional>

#include "driftcorr/mapping/interpolated_field.h"

namespace driftcorr {

/// Two interpolated fields sampled together at a point (world ENU frame, metres):
///  - centre: distance to the nearest traversable centre (road centre line, walkway), truncated;
///  - corridor: signed distance to the traversable corridor's edge (negative inside the road or
///    walkable area, positive outside), truncated at +/- truncation.
struct TraversableSample {
    FieldSample centre;
    FieldSample corridor;
};

class TraversableField {
public:
    TraversableField() = default;
    /// Precondition: both fields share one GridSpec.
    TraversableField(InterpolatedField centre, InterpolatedField corridor, double truncation_m);

    /// std::nullopt outside the grid (closer than one cell to its border).
    std::optional<TraversableSample> Query(const Eigen::Vector3d& p_enu) const;

    const GridSpec& spec() const { return centre_.spec(); }
    bool planar() const { return spec().planar(); }
    bool empty() const { return spec().size() == 0; }
    double truncation_m() const { return truncation_m_; }
    const InterpolatedField& centre() const { return centre_; }
    const InterpolatedField& corridor() const { return corridor_; }

private:
    InterpolatedField centre_;
    InterpolatedField corridor_;
    double truncation_m_ = 0.0;
};

}  // namespace driftcorr
