// The definitions of what driftcorr/optim/model_config.h declares.
#include "driftcorr/optim/model_config.h"

namespace driftcorr {

std::optional<ParamProblem> ModelConfig::FindProblem() const {
    if (auto problem = CheckRows(kModelParams, *this)) return problem;
    if (!(scale_range_min <= scale_range_max)) {
        return RelationProblem("scale_range_min", scale_range_min, "<=", "scale_range_max",
                               scale_range_max);
    }
    return std::nullopt;
}

std::string ModelConfig::Validate() const { return ToMessage(kModelParams.section, FindProblem()); }

ModelConfig ModelConfig::Pedestrian() {
    ModelConfig m;
    m.step_sigma_m = 0.05;
    m.step_sigma_rel = 0.05;
    m.step_length_exponent = 0.25;
    m.lateral_sigma_m = 0.05;
    m.lateral_sigma_rel = 0.05;
    m.heading_rw_rad_per_sqrt_s = 0.03;
    m.height_sigma_m = 0.05;
    m.height_sigma_rel = 0.25;
    m.floor_sigma_m = 0.2;
    m.heading_bias_segment_s = 0.0;
    m.scale_range_min = 0.9;
    m.scale_range_max = 1.5;
    m.map_sigma_m = 1.0;
    m.map_giveup_m = 3.0;
    m.lift_sigma_m = 1.0;
    m.lift_giveup_m = 10.0;
    m.scale_segment_m = 30.0;
    m.scale_rw_sigma = 0.01;
    m.scale_prior_sigma = 0.3;
    m.corridor_gate_m = 1.0;
    m.max_speed_mps = 10.0;
    return m;
}

}  // namespace driftcorr
