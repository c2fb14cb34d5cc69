#include "driftcorr/optim/model_config.h"

#include <cmath>

namespace driftcorr {
namespace {

bool Positive(double v) { return std::isfinite(v) && v > 0.0; }
bool NonNegative(double v) { return std::isfinite(v) && v >= 0.0; }
bool Weight(double v) { return std::isfinite(v) && v > 0.0 && v <= 1.0; }

}  // namespace

std::string ModelConfig::Validate() const {
    struct Check { const char* name; double value; bool (*ok)(double); const char* rule; };
    const Check checks[] = {
        {"model.step_sigma_m", step_sigma_m, Positive, "> 0"},
        {"model.step_sigma_rel", step_sigma_rel, NonNegative, ">= 0"},
        {"model.lateral_sigma_m", lateral_sigma_m, Positive, "> 0"},
        {"model.step_robust_k", step_robust_k, NonNegative, ">= 0"},
        {"model.accel_sigma_mps2", accel_sigma_mps2, NonNegative, ">= 0"},
        {"model.speed_weight", speed_weight, Weight, "in (0, 1]"},
        {"model.max_speed_mps", max_speed_mps, Positive, "> 0"},
        {"model.outlier_accel_mps2", outlier_accel_mps2, NonNegative, ">= 0"},
        {"model.outlier_sigma_rel", outlier_sigma_rel, NonNegative, ">= 0"},
        {"model.lateral_sigma_rel", lateral_sigma_rel, NonNegative, ">= 0"},
        {"model.heading_rw_rad_per_sqrt_s", heading_rw_rad_per_sqrt_s, NonNegative, ">= 0"},
        {"model.heading_sigma_rel", heading_sigma_rel, NonNegative, ">= 0"},
        {"model.heading_sigma_min_rad", heading_sigma_min_rad, Positive, "> 0"},
        {"model.preservation_sigma_rad", preservation_sigma_rad, Positive, "> 0"},
        {"model.height_sigma_m", height_sigma_m, Positive, "> 0"},
        {"model.height_sigma_rel", height_sigma_rel, NonNegative, ">= 0"},
        {"model.map_sigma_m", map_sigma_m, Positive, "> 0"},
        {"model.map_giveup_m", map_giveup_m, Positive, "> 0"},
        {"model.scale_segment_m", scale_segment_m, Positive, "> 0"},
        {"model.scale_prior_sigma", scale_prior_sigma, Positive, "> 0"},
        {"model.scale_rw_sigma", scale_rw_sigma, Positive, "> 0"},
        {"model.scale_rw_robust_k", scale_rw_robust_k, NonNegative, ">= 0"},
        {"model.scale_range_min", scale_range_min, Positive, "> 0"},
        {"model.scale_range_max", scale_range_max, Positive, "> 0"},
        {"model.scale_range_sigma", scale_range_sigma, NonNegative, ">= 0"},
        {"model.heading_bias_segment_s", heading_bias_segment_s, NonNegative, ">= 0"},
        {"model.heading_bias_prior_rad_s", heading_bias_prior_rad_s, Positive, "> 0"},
        {"model.heading_bias_rw_rad_s", heading_bias_rw_rad_s, Positive, "> 0"},
        {"model.step_weight", step_weight, Weight, "in (0, 1]"},
        {"model.heading_weight", heading_weight, Weight, "in (0, 1]"},
        {"model.preservation_weight", preservation_weight, Weight, "in (0, 1]"},
        {"model.map_weight", map_weight, Weight, "in (0, 1]"},
        {"model.height_weight", height_weight, Weight, "in (0, 1]"},
        {"model.corridor_gate_m", corridor_gate_m, NonNegative, ">= 0"},
        {"model.corridor_slack_m", corridor_slack_m, NonNegative, ">= 0"},
    };
    for (const Check& c : checks) {
        if (!c.ok(c.value)) return std::string(c.name) + ": must be " + c.rule;
    }
    if (!(scale_range_min <= scale_range_max)) {
        return "model.scale_range_min: must be <= model.scale_range_max";
    }
    return "";
}

}  // namespace driftcorr
