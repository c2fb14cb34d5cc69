#pragma once
// The baseline: the solver of P. Navard and A. Yilmaz, "A Probabilistic-based Drift Correction
// Module for Visual Inertial SLAMs" (arXiv:2404.10140, 2024), kept as a reference mode
// (`driftcorr correct --solver paper`, and a column of `driftcorr eval`): an epoch-by-epoch filter.
// Per epoch i the previous poses stay fixed, the new position starts at the previous corrected pose
// composed with the observed step, and plain fixed-step gradient descent (learning rate 0.01, as
// published, no line search) minimises four weighted terms of that one position:
//
//   E_i(p) = w_t (c_i - c_{i-1} - dc_i)^2 / 2 sigma_t^2     turn angle        (HeadingChangeTerm)
//          + w_s (|p - p_{i-1}| - L_i)^2 / 2 sigma_s^2      step length       (StepLengthTerm)
//          + w_m min(d(p), h(p))^2 / 2 sigma_m^2            truncated distance
//          + w_p (c_i - c_{i-1})^2 / 2 sigma_p^2            heading preservation
//          (HeadingPreservationTerm)
//
// c_i = atan2(p - p_{i-1}) is the course (heading derived from the step direction), dc_i and L_i
// the estimate's course change and step length, d the distance to the nearest road centre line
// from the bilinearly interpolated grid (InterpolatedField::QueryBilinear) and h the road's
// half-width there: the map term pulls a pose towards the centre line while it is on the road and
// lets go (flat) once it is off it. No I/O.
// It shares only the solver-neutral result types with the batch corrector (correction_result.h)
// and does not depend on the Ipopt adapter.
#include <optional>
#include <string>

#include "driftcorr/core/params.h"
#include "driftcorr/core/types.h"
#include "driftcorr/mapping/traversable_field.h"
#include "driftcorr/optim/correction_result.h"
#include "driftcorr/optim/model_config.h"

namespace driftcorr {

struct PaperSolverConfig {
    double learning_rate = 0.01;  ///< fixed gradient step [m^2 per unit cost], as published
    /// Gradient steps per epoch. 100: with the defaults below the stiffest direction (the step
    /// length) converges in one step (learning_rate * w_s / sigma_s^2 = 1) and the lateral
    /// direction in about 20, so 100 leaves the descent converged to < 1 mm on KITTI and PDR.
    int iterations_per_epoch = 100;
    double turn_weight = 1.0;          ///< w_t in [0, 1]
    double step_weight = 1.0;          ///< w_s in [0, 1]
    double map_weight = 1.0;           ///< w_m in [0, 1]
    double preservation_weight = 1.0;  ///< w_p in [0, 1]
    /// sigma_t [rad]. Not ModelConfig's heading random walk (that one is per sqrt(s) and ~1e-3 rad
    /// per step, far too stiff for a fixed learning rate of 0.01): the turn term's curvature in
    /// position is w_t / (sigma_t * L)^2, so sigma_t * min_step_m must stay >= ~0.07 m.
    double turn_sigma_rad = 0.2;
    double step_sigma_m = 0.1;                       ///< sigma_s [m] (see iterations_per_epoch)
    double map_sigma_m = ModelConfig{}.map_sigma_m;  ///< sigma_m [m]
    double preservation_sigma_rad = ModelConfig{}.preservation_sigma_rad;  ///< sigma_p [rad]
    /// Truncation h of the map distance [m]; 0: the road's own half-width at p, read from the
    /// field (centre distance minus signed corridor distance).
    double map_truncation_m = 0.0;
    /// Observed steps shorter than this [m] are composed onto the previous pose without descent:
    /// the course of a short step is ill-defined and its turn-term curvature would make the fixed
    /// learning rate diverge.
    double min_step_m = 0.5;
    double stationary_m = 1e-3;  ///< steps shorter than this are stops [m]

    /// The first value kPaperSolverParams or a rule between its values does not allow, including
    /// settings for which the fixed-step descent is unstable (learning_rate * curvature >= 2 on the
    /// step or turn term).
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "paper.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// Params.yaml section `paper`.
inline constexpr Param<PaperSolverConfig> kPaperSolverParamRows[] = {
    {"learning_rate", Field<&PaperSolverConfig::learning_rate>(), kPositive,
     "fixed gradient step, as published"},
    {"iterations_per_epoch", Field<&PaperSolverConfig::iterations_per_epoch>(), Between(1, 1e6),
     "gradient steps per epoch"},
    {"turn_weight", Field<&PaperSolverConfig::turn_weight>(), kShare, "w_t"},
    {"step_weight", Field<&PaperSolverConfig::step_weight>(), kShare, "w_s"},
    {"map_weight", Field<&PaperSolverConfig::map_weight>(), kShare, "w_m"},
    {"preservation_weight", Field<&PaperSolverConfig::preservation_weight>(), kShare, "w_p"},
    {"turn_sigma_rad", Field<&PaperSolverConfig::turn_sigma_rad>(), kPositive, "sigma_t"},
    {"step_sigma_m", Field<&PaperSolverConfig::step_sigma_m>(), kPositive, "sigma_s"},
    {"map_sigma_m", Field<&PaperSolverConfig::map_sigma_m>(), kPositive, "sigma_m"},
    {"preservation_sigma_rad", Field<&PaperSolverConfig::preservation_sigma_rad>(), kPositive,
     "sigma_p"},
    {"map_truncation_m", Field<&PaperSolverConfig::map_truncation_m>(), kNonNegative,
     "truncation h of the map distance; 0: the road's own half-width"},
    {"min_step_m", Field<&PaperSolverConfig::min_step_m>(), kPositive,
     "shorter observed steps are composed without descent; >= stationary_m"},
    {"stationary_m", Field<&PaperSolverConfig::stationary_m>(), kPositive,
     "steps shorter than this are stops"},
};
inline constexpr ParamTable<PaperSolverConfig> kPaperSolverParams{"paper", kPaperSolverParamRows};

/// Corrects `estimate` (world ENU plane, >= 3 poses) against `field` (may be null: odometry only)
/// with the paper's method. Pose 0 is the known initial pose and stays fixed. Returns the same
/// result struct as CorrectTrajectory: status kSuccess with `corrected` (positions, heights of the
/// estimate, yaw = estimate yaw turned by the course correction), `iterations` = gradient steps
/// in all, `incremental_s` = wall time; status kFailed with a message naming the epoch when the
/// descent produced a non-finite position. Progress is reported as stage "paper".
CorrectionResult CorrectWithPaperMethod(const PlanarTrajectory& estimate,
                                        const TraversableField* field,
                                        const PaperSolverConfig& config,
                                        const ProgressCallback& progress = {});

}  // namespace driftcorr
