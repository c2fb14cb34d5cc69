#pragma once
// The stress variants of one scenario (datasets/README.md, "Stress variants"): each is the input
// with one fault injected, or the reason why it cannot be made.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "scenario_output.h"
#include "stress_transforms.h"

namespace driftcorr::stress {

/// Every parameter of the generator; defaults written once here.
struct StressConfig {
    std::uint64_t seed = 1;  ///< drop_steps episodes and the anchor_off direction
    DropStepsConfig drop;
    std::vector<double> heading_bias_deg_per_s = {0.1, 0.3, 0.5};
    std::vector<double> yaw_offset_deg = {10.0, 20.0, 30.0};
    double anchor_offset_m = 20.0;
    /// road_removed: a ground-truth pose counts as on a way within this distance of its polyline.
    double road_radius_m = 5.0;
    /// Monocular variants (only these are written when any is asked for): the global scales of
    /// the estimate, and its scale's random walk [share per sqrt(100 m)] (ScaleLikeMonocular).
    std::vector<double> monocular_scales;
    double monocular_drift_per_100m = 0.02;
};

/// One variant, or why it was skipped.
struct VariantOutcome {
    std::string name;
    std::optional<VariantSpec> spec;  ///< nullopt: skipped
    std::string note;                 ///< a one-line summary, or the reason for the skip
};

/// All variants, in a fixed order: clean, drop_steps, heading_bias_*, yaw_off_*, anchor_off_*,
/// road_removed; or, when config.monocular_scales is not empty, only mono_<scale> (the anchor as
/// given) and mono_<scale>_auto (the anchor with `scale: auto`) for each scale. Throws InputError
/// naming the file for bad input found on the way (a map that cannot be read, an unknown CRS).
std::vector<VariantOutcome> MakeVariants(const InputScenario& input, const StressConfig& config);

}  // namespace driftcorr::stress
