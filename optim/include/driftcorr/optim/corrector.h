#pragma once
// The batch corrector: processes the trajectory incrementally (extend by a chunk, initialise the
// new poses by composing odometry onto the corrected end, re-solve a trailing window), then
// refines the whole trajectory in one solve. No I/O: progress goes through a callback, the outcome
// into CorrectionResult.
#include <functional>
#include <string>
#include <vector>

#include "driftcorr/core/types.h"
#include "driftcorr/mapping/traversable_field.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/ipopt_solver.h"
#include "driftcorr/optim/model_config.h"

namespace driftcorr {

struct CorrectorConfig {
    ModelConfig model;
    double chunk_m = 80.0;           ///< estimated path added per incremental step [m]
    double window_m = 240.0;         ///< trailing path re-solved per incremental step [m]
    std::size_t max_chunk_poses = 400;   ///< cap per chunk (long stops) [poses]
    std::size_t max_window_poses = 1500; ///< cap per window [poses]
    bool refine = true;              ///< final whole-trajectory solve
    /// A window whose solution leaves more than restart_offroad_share of its poses farther than
    /// restart_offroad_m from every road, or whose NLL per pose exceeds restart_nll_per_pose, is
    /// re-solved from these step-length scale hypotheses
    /// (multiplying the current scale); the lowest NLL wins. Empty: no restarts.
    std::vector<double> restart_scale_factors = {1.3, 0.8, 1.7};
    double restart_offroad_m = 6.0;      ///< [m]
    double restart_offroad_share = 0.05; ///< [-]
    double restart_nll_per_pose = 0.3;   ///< [-]
    double stationary_m = 1e-3;      ///< steps shorter than this are stops [m]
    IpoptOptions window_ipopt{50, 30.0, 1e-6, 1e-4, 1e-4, 0};
    IpoptOptions refine_ipopt{200, 120.0, 1e-6, 1e-4, 1e-4, 0};
    /// Per-pose covariance of the corrected trajectory (optim/covariance.h) into
    /// CorrectionResult::covariance. Linear in the number of poses; KITTI 00 (4541 poses):
    /// 15-20 ms, about 2 % of the correction.
    bool compute_covariance = true;
    CovarianceConfig covariance;

    /// Empty if valid, else a message naming the bad field.
    std::string Validate() const;
};

struct CorrectionProgress {
    std::string stage;          ///< "incremental" or "refine"
    std::size_t poses_done = 0;
    std::size_t poses_total = 0;
};
using ProgressCallback = std::function<void(const CorrectionProgress&)>;

struct CorrectionResult {
    SolveStatus status = SolveStatus::kFailed;
    std::string message;            ///< human-readable outcome, names the failing stage
    PlanarTrajectory corrected;     ///< valid only when Usable(status)
    std::size_t windows = 0;
    std::size_t window_retries = 0;    ///< windows re-solved without hard constraints
    std::size_t window_failures = 0;   ///< windows that failed even then
    std::size_t window_restarts = 0;   ///< extra window solves from other scale hypotheses
    int iterations = 0;                ///< Ipopt iterations, all solves
    std::size_t constrained_poses = 0; ///< poses with the hard corridor constraint (refine)
    double scale_min = 1.0, scale_max = 1.0;  ///< estimated step-length scale range
    /// The odometry's step lengths as the model observed them [m], one per pose (step into pose
    /// i; [0] = 0): the estimate's, except the dropped steps RepairSpeedEpisodes replaced.
    std::vector<double> step_length_m;
    std::size_t repaired_steps = 0;  ///< steps whose length was replaced
    SolveReport refine_report;
    double incremental_s = 0.0;        ///< wall time of the incremental pass [s]
    double refine_s = 0.0;             ///< wall time of the refinement [s]
    /// Marginal covariance of every corrected pose; status kNotComputed unless
    /// config.compute_covariance and the correction is usable.
    CovarianceResult covariance;
    double covariance_s = 0.0;  ///< wall time of the covariance [s]
    /// Degenerate input or outcome worth a user's attention, one sentence each (the map covers
    /// none or little of the drive, the estimate does not move, the scale hit its bound, steps
    /// treated as discontinuities). The correction may still be usable.
    std::vector<std::string> warnings;
};

/// Fills result.warnings from the estimate, the field and the outcome (see CorrectionResult).
void DiagnoseCorrection(const PlanarTrajectory& estimate, const TraversableField* field,
                        const CorrectorConfig& config, CorrectionResult& result);

/// Corrects `estimate` (world ENU plane, >= 3 poses) against `field` (may be null: odometry
/// only). Pose 0 is the known initial position and heading and stays fixed.
CorrectionResult CorrectTrajectory(const PlanarTrajectory& estimate, const TraversableField* field,
                                   const CorrectorConfig& config,
                                   const ProgressCallback& progress = {});

}  // namespace driftcorr
