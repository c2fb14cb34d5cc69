#pragma once
// The batch corrector's settings (optim/corrector.h; the online corrector uses them too): chunks,
// windows, restarts, the Ipopt limits, the model and the covariance.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/params.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/ipopt_solver.h"
#include "driftcorr/optim/model_config.h"

namespace driftcorr {

struct CorrectorConfig {
    ModelConfig model;
    double chunk_m = 80.0;                ///< estimated path added per incremental step [m]
    double window_m = 240.0;              ///< trailing path re-solved per incremental step [m]
    std::size_t max_chunk_poses = 400;    ///< cap per chunk (long stops) [poses]
    std::size_t max_window_poses = 1500;  ///< cap per window [poses]
    bool refine = true;                   ///< final whole-trajectory solve
    /// A drive of more poses has its final solve in consecutive blocks of this many poses (each
    /// overlapping the one before by a tenth), which bounds its memory; shorter drives are solved
    /// whole.
    std::size_t refine_block_poses = 100000;
    /// A window whose solution leaves more than restart_offroad_share of its poses farther than
    /// restart_offroad_m from every road, or whose NLL per pose exceeds restart_nll_per_pose, is
    /// re-solved from these step-length scale hypotheses
    /// (multiplying the current scale); the lowest NLL wins. Empty: no restarts.
    std::vector<double> restart_scale_factors = {1.3, 0.8, 1.7};
    /// The step-length scales the batch correction starts from (CorrectTrajectory). With more
    /// than one, the whole correction runs from each and the lowest NLL of the corrected
    /// trajectory wins: the scale is what a walk's first windows settle, and a map that lets a
    /// squeezed or stretched path fit as well as the true one (a building's dense corridors)
    /// keeps the basin it starts in. A start's windows hold the scale prior about the start's
    /// scale (a prior about 1 pulled every start back to the same basin along a corridor whose
    /// side doors repeat); its final solve holds it about 1, as every start's does, so their NLLs
    /// compare. Time: one correction per start.
    std::vector<double> start_scales = {1.0};
    /// A window whose observed height changes add up to restart_height_change_m or more (it
    /// changes floor; 3D modes only) is also solved from starts whose height changes are read
    /// with these gains: a barometer reads a floor change 0.75-1.1x (the two real HCU walks), so
    /// the floor nearest to the reading can be the wrong one; the lowest NLL wins. Empty: none.
    std::vector<double> restart_height_gains = {0.7, 0.85, 1.2, 1.4};
    double restart_height_change_m = 2.0;  ///< [m]
    /// The batch correction's floor hypotheses (CorrectFromStarts): after each floor change of
    /// the estimate, the whole correction is re-run on each other floor that the change reaches
    /// when read with a gain within the range of restart_height_gains (empty: none); one is kept
    /// when its NLL is lower by more than floor_hypothesis_margin. On floors alike near their
    /// lifts the solves' own basins move the NLL by tens of units either way (a generated walk
    /// whose right floor's correction came out 13.4 above its wrong one's): only a larger
    /// difference, a walk that the other floor explains far better, changes the floor the
    /// windows chose. Time: one correction per floor tried.
    double floor_hypothesis_margin = 15.0;  ///< [-]
    /// One barometer reads a walk's floor changes of one kind alike: the floor hypotheses are
    /// scored by their NLL plus that of the changes' gains (the corrected floor change over the
    /// estimate's, of each change of restart_height_change_m or more) about one gain per kind, a
    /// lift ride (ModelConfig ride_*: RideSpans) or a walked change, log-normal with this sigma.
    /// A barometer's gain holds within a walk, but differs between a stair hall and a lift shaft
    /// (the real Zero2four walk: stairs 0.81x, lift 1.12x). 0: NLL alone.
    double floor_gain_sigma = 0.0;        ///< [-] (of the log gain)
    double restart_offroad_m = 6.0;       ///< [m]
    double restart_offroad_share = 0.05;  ///< [-]
    double restart_nll_per_pose = 0.3;    ///< [-]
    double stationary_m = 1e-3;           ///< steps shorter than this are stops [m]
    /// The windows' soft solves by the banded Newton solver (optim/newton_solver.h, with
    /// window_ipopt's iteration limit and tolerances); false: by Ipopt.
    bool window_newton = true;
    /// The final solve starts from its soft terms' minimum (Newton); Ipopt solves the constrained
    /// program only when a constrained pose lies outside its corridor there.
    bool refine_newton = true;
    /// The final solve's Newton stops where its scaled gradient (Ipopt's measure of `tol`) is at
    /// most this; the windows keep window_ipopt's 1e-6. The final solve's result is the output,
    /// so what stopping earlier leaves is how far the next steps would still move the poses:
    /// at 1e-4, less than 1 mm on the generated road and building scenarios (one Newton step
    /// fewer in most drives, docs/results.md).
    double refine_newton_tolerance = 1e-4;
    IpoptOptions window_ipopt{50, 30.0, 1e-6, 1e-4, 1e-4, 0, {}};
    IpoptOptions refine_ipopt{200, 120.0, 1e-6, 1e-4, 1e-4, 0, {}};
    /// Per-pose covariance of the corrected trajectory (optim/covariance.h) into
    /// CorrectionResult::covariance. Linear in the number of poses; KITTI 00 (4541 poses):
    /// 15-20 ms, about 2 % of the correction.
    bool compute_covariance = true;
    CovarianceConfig covariance;
    /// Do no harm: when the share of the input's poses inside the correction's own 95 % region
    /// (its covariance) is not significantly below 95 % (one-sided, 5 %, over the path's number
    /// of map-offset correlation lengths), what the map says cannot tell the input wrong, and the
    /// input itself is the result (CorrectionResult::input_kept). Needs compute_covariance.
    /// The input is also the result when its NLL under the model is lower than the
    /// correction's (the solve ended in a poorer basin than the one it started from).
    bool keep_agreeing_input = true;
    /// The heading-rate bias (ModelConfig::heading_bias_segment_s) as a freedom decided per
    /// input: the correction runs without it, its final solve is repeated with the bias's
    /// unknowns added, and the bias is kept only when that lowers the NLL by more than
    /// k / 2 ln n (the Bayesian information criterion; k bias unknowns, n poses). false: the
    /// bias is in every solve when the model has it.
    bool decide_heading_bias = false;
    /// The step-length scale walk (ModelConfig::scale_segment_m) as a freedom decided per input:
    /// the drive is first corrected with one scale for all of it; its final solve is repeated
    /// with the walk's segments, and when that lowers the NLL by more than the walk's price
    /// ((k - 1) / 2 ln n, k segments, n poses), the whole correction is run again with the walk.
    /// The lowest NLL plus price of the three is kept. Applies with one start scale and no
    /// floor hypotheses (else the walk is always in).
    bool decide_scale_walk = false;
    /// A second start for a road correction with the scale walk: its solution is solved again
    /// with one scale for the whole drive (the median of the walk's), a solution of the same
    /// model; where its NLL is the lower, the walk's solution lies in a poorer basin (the windows
    /// of a long straight can stretch its last segments into one), and the one-scale solution,
    /// refined with the walk, is kept. Applies as decide_scale_walk does, which runs instead.
    bool one_scale_start = true;
    /// The reading of the step lengths (ModelConfig::step_length_exponent below 1: about the
    /// walk's median step) as a freedom decided per input: the drive is corrected with the
    /// exponent and with the step lengths as read (exponent 1); the correction as read is kept
    /// when its NLL is lower by more than the price of one unknown, 1/2 ln n (n poses), each
    /// NLL with its step-length terms' normalisation (sum of ln sigma: the two readings observe
    /// steps of different lengths). Not with decide_scale_walk (that decision runs instead).
    /// No effect where the exponent is 1 (the road default).
    bool decide_step_reading = true;

    /// The first value kCorrectorParams or a rule between its values does not allow (model and
    /// covariance are not looked at).
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "<section>.<key>: <rule> (got <value>)" for the first bad field of
    /// model, this struct (section corrector) or covariance.
    std::string Validate() const;

    /// The settings for a pedestrian indoors (the members' initialisers are those for a car on
    /// roads): ModelConfig::Pedestrian(), chunks and windows of a walk's tens of metres, restarts
    /// closer to the walkways, start scales over the pedestrian's plausible range, the floor
    /// hypotheses scored with their floor changes' gains, and the covariance's correlated step
    /// error. How each value was chosen: docs/results.md, "Indoor parameters".
    static CorrectorConfig Pedestrian();
};

/// Params.yaml section `corrector` (and `indoor_corrector`, CorrectorConfig::Pedestrian() by
/// default).
inline constexpr Param<CorrectorConfig> kCorrectorParamRows[] = {
    {"chunk_m", Field<&CorrectorConfig::chunk_m>(), kPositive,
     "estimated path added per incremental step"},
    {"window_m", Field<&CorrectorConfig::window_m>(), kPositive,
     "trailing path re-solved per incremental step; >= chunk_m"},
    {"max_chunk_poses", Field<&CorrectorConfig::max_chunk_poses>(), AtLeast(1),
     "cap on the poses of a chunk (long stops)"},
    {"max_window_poses", Field<&CorrectorConfig::max_window_poses>(), AtLeast(1),
     "cap on the poses of a window; >= max_chunk_poses"},
    {"refine", Field<&CorrectorConfig::refine>(), kNoRange, "final whole-trajectory solve"},
    {"refine_block_poses", Field<&CorrectorConfig::refine_block_poses>(), AtLeast(2),
     "a longer drive's final solve runs in overlapping blocks of this many poses"},
    {"restart_offroad_m", Field<&CorrectorConfig::restart_offroad_m>(), kNonNegative,
     "a window leaving more than restart_offroad_share of its poses this far off the map restarts"},
    {"restart_offroad_share", Field<&CorrectorConfig::restart_offroad_share>(), kShare,
     "share of off-map poses that restarts a window"},
    {"restart_nll_per_pose", Field<&CorrectorConfig::restart_nll_per_pose>(), kNonNegative,
     "a window whose NLL per pose exceeds this restarts"},
    {"floor_hypothesis_margin", Field<&CorrectorConfig::floor_hypothesis_margin>(), kNonNegative,
     "3D: a whole correction on another floor after a floor change is kept when its NLL is lower "
     "by more than this"},
    {"floor_gain_sigma", Field<&CorrectorConfig::floor_gain_sigma>(), kNonNegative,
     "3D: floor hypotheses scored with their floor changes' gains about one per kind (lift, "
     "walked), log sigma; 0: NLL alone"},
    {"stationary_m", Field<&CorrectorConfig::stationary_m>(), kNonNegative,
     "steps shorter than this are stops"},
    {"window_newton", Field<&CorrectorConfig::window_newton>(), kNoRange,
     "soft window solves by the banded Newton solver (false: Ipopt)"},
    {"refine_newton", Field<&CorrectorConfig::refine_newton>(), kNoRange,
     "final solve from its soft minimum; Ipopt only where a corridor is left"},
    {"refine_newton_tolerance", Field<&CorrectorConfig::refine_newton_tolerance>(), kPositive,
     "the final solve's Newton stops at this scaled gradient (Ipopt's tol; windows: 1e-6)"},
    {"window_max_iterations",
     Field<&CorrectorConfig::window_ipopt, &IpoptOptions::max_iterations>(), kNonNegative,
     "iterations per window solve"},
    {"window_max_cpu_time_s",
     Field<&CorrectorConfig::window_ipopt, &IpoptOptions::max_cpu_time_s>(), kPositive,
     "Ipopt time limit per window solve (window_newton false)"},
    {"refine_max_iterations",
     Field<&CorrectorConfig::refine_ipopt, &IpoptOptions::max_iterations>(), kNonNegative,
     "iterations of the final solve (Newton, then Ipopt)"},
    {"refine_max_cpu_time_s",
     Field<&CorrectorConfig::refine_ipopt, &IpoptOptions::max_cpu_time_s>(), kPositive,
     "Ipopt time limit of the final solve"},
    {"decide_heading_bias", Field<&CorrectorConfig::decide_heading_bias>(), kNoRange,
     "the heading-rate bias kept only when it lowers the NLL by more than its BIC price (its "
     "final solve repeated with it)"},
    {"decide_scale_walk", Field<&CorrectorConfig::decide_scale_walk>(), kNoRange,
     "the scale walk kept only when it lowers the NLL by more than its BIC price (one scale "
     "for the drive otherwise)"},
    {"one_scale_start", Field<&CorrectorConfig::one_scale_start>(), kNoRange,
     "the walk's solution solved again with one scale; where that NLL is lower, it is "
     "kept, refined with the walk"},
    {"decide_step_reading", Field<&CorrectorConfig::decide_step_reading>(), kNoRange,
     "with a step_length_exponent below 1: the correction with the step lengths as read kept "
     "instead when its NLL (with the step terms' normalisation) is lower by more than 1/2 ln n"},
    {"keep_agreeing_input", Field<&CorrectorConfig::keep_agreeing_input>(), kNoRange,
     "the input is the result when its share of poses inside the correction's 95 % region is "
     "not significantly below 95 % (needs compute_covariance), or when its NLL is lower"},
    {"compute_covariance", Field<&CorrectorConfig::compute_covariance>(), kNoRange,
     "per-pose covariance of the corrected trajectory"},
};
inline constexpr ParamTable<CorrectorConfig> kCorrectorParams{"corrector", kCorrectorParamRows};

}  // namespace driftcorr
