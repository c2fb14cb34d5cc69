#pragma once
// Where the start of a trajectory fits the map: the leading part of the estimate is turned about
// the trajectory frame's origin, where the anchor puts it (and shifted, when a position search
// radius is given) and scored by its distance to the nearest traversable place. Serves two
// purposes:
//  - `yaw_deg: auto` (and `position_search_m`): the start is estimated from the map;
//  - the anchor check: a given anchor whose start lies far from every road while another heading
//    or position fits well is reported (the correction cannot repair a wrong start).
// A straight leading path fits a road in both directions, and a grid of streets fits every 90 deg:
// the result names the best placement clearly apart from the best one (the runner-up), so the
// caller can tell an ambiguous start. No I/O.
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/params.h"
#include "driftcorr/core/types.h"
#include "driftcorr/mapping/traversable_field.h"

namespace driftcorr {

struct AnchorFitConfig {
    double lead_path_m = 400.0;     ///< leading path of the estimate matched to the map [m]
    double sample_spacing_m = 2.0;  ///< one pose per this much path is scored [m]
    double yaw_step_deg = 2.0;      ///< coarse heading grid; refined to ~0.1 deg [deg]
    double position_step_m = 4.0;   ///< coarse position grid; refined to ~0.25 m [m]
    /// Distances are truncated here: a pose farther from every traversable place (or outside
    /// the field) counts as off the map [m].
    double reach_m = 8.0;
    /// Two placements are distinct when their headings differ by more than this... [deg]
    double distinct_yaw_deg = 15.0;
    /// ...or their positions by more than this [m].
    double distinct_position_m = 10.0;
    /// The anchor check of a given start also searches positions within this radius at the given
    /// heading (a position a few tens of metres off, e.g. a fix of the wrong end of a car park)
    /// [m].
    double check_position_radius_m = 25.0;

    /// The first value kAnchorFitParams does not allow.
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "anchor_fit.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// The anchor fit's settings (not a params.yaml section: the pipeline sets reach_m from the
/// mode's map_giveup_m).
inline constexpr Param<AnchorFitConfig> kAnchorFitParamRows[] = {
    {"lead_path_m", Field<&AnchorFitConfig::lead_path_m>(), kPositive,
     "leading path of the estimate matched to the map"},
    {"sample_spacing_m", Field<&AnchorFitConfig::sample_spacing_m>(), kPositive,
     "one pose per this much path is scored"},
    {"yaw_step_deg", Field<&AnchorFitConfig::yaw_step_deg>(), ParamRange{0.0, 45.0, true, false},
     "coarse heading grid"},
    {"position_step_m", Field<&AnchorFitConfig::position_step_m>(), kPositive,
     "coarse position grid"},
    {"reach_m", Field<&AnchorFitConfig::reach_m>(), kPositive,
     "a pose farther from every traversable place counts as off the map"},
    {"distinct_yaw_deg", Field<&AnchorFitConfig::distinct_yaw_deg>(), kPositive,
     "placements whose headings differ by more are distinct"},
    {"distinct_position_m", Field<&AnchorFitConfig::distinct_position_m>(), kPositive,
     "placements whose positions differ by more are distinct"},
    {"check_position_radius_m", Field<&AnchorFitConfig::check_position_radius_m>(), kNonNegative,
     "the anchor check also searches positions within this radius"},
};
inline constexpr ParamTable<AnchorFitConfig> kAnchorFitParams{"anchor_fit", kAnchorFitParamRows};

/// One placement of the leading path: turned by `dyaw_rad` about the pivot (the frame origin) and
/// moved by `offset_en`, relative to the estimate as handed in.
struct AnchorPlacement {
    double dyaw_rad = 0.0;
    Eigen::Vector2d offset_en = Eigen::Vector2d::Zero();  ///< [m]
    double rms_m = 0.0;      ///< RMS of the truncated distance over the scored poses [m]
    double off_share = 0.0;  ///< share of scored poses beyond reach_m or outside the field
};

struct AnchorFitResult {
    AnchorPlacement given;                     ///< the estimate as handed in (dyaw 0, offset 0)
    AnchorPlacement best;                      ///< lowest RMS found
    std::optional<AnchorPlacement> runner_up;  ///< lowest RMS among placements distinct from best
    std::size_t samples = 0;                   ///< poses scored
    double lead_path_m = 0.0;                  ///< path length they cover [m]
};

/// Scores placements of `estimate` (world ENU plane, >= 2 poses) against `field`: headings over
/// the whole circle when `search_yaw`, else only the given one; positions within `radius_m` of the
/// given one (0: only the given position). Precondition: config.Validate() is empty.
/// Placements turn about `pivot_en` (the trajectory frame's origin in the world plane).
AnchorFitResult FitAnchor(const PlanarTrajectory& estimate, const Eigen::Vector2d& pivot_en,
                          const TraversableField& field, bool search_yaw, double radius_m,
                          const AnchorFitConfig& config);

/// One global scale of the estimate and where its leading path then fits best.
struct ScaleCandidate {
    double scale = 1.0;
    AnchorPlacement placement;  ///< of the estimate scaled by `scale` (ScaleAbout)
    /// The NLL of the whole correction at this scale, where the caller compared candidates by
    /// it (NaN: not computed; infinity: the correction failed).
    double nll = std::numeric_limits<double>::quiet_NaN();
};

/// The global scale of an estimate whose size is unknown (a monocular tracker's), as the fit of
/// its leading path to the map tells it.
struct ScaleFitResult {
    std::vector<double> scales;  ///< the log-spaced grid searched
    std::vector<double> rms_m;   ///< per grid scale, its best placement's RMS (FitAnchor)
    /// The grid's local minima, each refined between its neighbours, lowest RMS first; no two
    /// within two grid steps of each other.
    std::vector<ScaleCandidate> candidates;
    std::size_t kept = 0;  ///< the candidate the caller kept (its scale refined by the caller)
};

/// Scores the estimate scaled about (pivot_en, pivot_up_m) by every scale of a log-spaced grid from
/// min_scale to max_scale (ratio step_ratio > 1 between neighbours) as FitAnchor does (config's
/// lead_path_m of the scaled path; every heading when `search_yaw`), and returns at most
/// `max_candidates` local minima. Precondition: 0 < min_scale <= max_scale, config valid.
ScaleFitResult FitScale(const PlanarTrajectory& estimate, const Eigen::Vector2d& pivot_en,
                        double pivot_up_m, const TraversableField& field, bool search_yaw,
                        double min_scale, double max_scale, double step_ratio,
                        std::size_t max_candidates, const AnchorFitConfig& config);

/// How the map fits a trajectory at other sizes: its positions scaled about its first pose by
/// factors g from 1 / (1 + range) to 1 + range (log-spaced, neighbours moving the pose farthest
/// from the start by at most config.reach_m), the poses one per config.sample_spacing_m of the
/// whole path, each size scored as FitAnchor scores a placement (RMS of the distance to the
/// nearest traversable centre, truncated at config.reach_m).
struct SizeFit {
    double rms_m = 0.0;       ///< the trajectory at its own size (g = 1)
    double farthest_m = 0.0;  ///< the farthest pose from the start [m]
    /// The size of lowest RMS among the local minima that move the farthest pose by more than
    /// 2 config.reach_m (a placement the map tells apart from g = 1), refined between its
    /// neighbours: its factor g and RMS (placement.rms_m; no turn or shift). None when no such
    /// minimum exists.
    std::optional<ScaleCandidate> other;
};
/// Precondition: t has >= 2 poses, range > 0, config valid.
SizeFit FitSizes(const PlanarTrajectory& t, const TraversableField& field, double range,
                 const AnchorFitConfig& config);

/// `estimate` with its positions scaled by `scale` about (pivot_en, pivot_up_m); headings and
/// times unchanged.
PlanarTrajectory ScaleAbout(const PlanarTrajectory& estimate, const Eigen::Vector2d& pivot_en,
                            double pivot_up_m, double scale);

/// `estimate` turned by placement.dyaw_rad about `pivot_en` and moved by placement.offset_en
/// (positions and headings).
PlanarTrajectory ApplyPlacement(const PlanarTrajectory& estimate, const Eigen::Vector2d& pivot_en,
                                const AnchorPlacement& placement);

}  // namespace driftcorr
