#include "driftcorr/mapping/traversable_field.h"

#include <cassert>

namespace driftcorr {

TraversableField::TraversableField(InterpolatedField centre, InterpolatedField corridor,
                                   double truncation_m)
    : centre_(std::move(centre)), corridor_(std::move(corridor)), truncation_m_(truncation_m) {
    assert(centre_.spec().size() == corridor_.spec().size() && "fields must share one grid");
}

std::optional<TraversableSample> TraversableField::Query(const Eigen::Vector3d& p_enu) const {
    thread_local std::vector<FieldSample> samples;
    if (!InterpolatedField::QueryMany({&centre_, &corridor_}, p_enu, samples)) return std::nullopt;
    return TraversableSample{samples[0], samples[1]};
}

}  // namespace driftcorr
