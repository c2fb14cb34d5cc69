#pragma once
// The correction as a nonlinear program over a window of poses [first, last] of a trajectory,
// solver-independent: objective (the weighted NLL), its gradient and exact Hessian, and the
// hard corridor constraints with their Jacobian and Hessians, in sparse triplet form.
// Pose first-1 and everything before it is held fixed; with a boundary prior (a fixed-lag window
// whose earlier poses are marginalised) pose first-1 is a variable too, tied to the window by the
// step and heading terms of step `first` and to the past by the prior (core PosePriorTerm).
//
// Variables: per pose (x, y, z, yaw) in the ENU map frame (from pose first-1 with a boundary
// prior), then one scale per scale segment touched by the window's steps.
#include <array>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "driftcorr/core/cost_terms.h"
#include "driftcorr/core/observables.h"
#include "driftcorr/mapping/traversable_field.h"
#include "driftcorr/optim/model_config.h"

namespace driftcorr {

struct PoseState {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();  ///< ENU [m]
    double yaw_rad = 0.0;                         ///< unwrapped heading
};

/// The whole trajectory's state and its fixed inputs; windows read and write it.
struct TrajectoryState {
    std::vector<StepObservation> obs;   ///< obs[i]: step into pose i
    std::vector<int> scale_segment;     ///< scale segment of step i (obs index)
    std::vector<PoseState> poses;
    std::vector<double> scales;         ///< one per scale segment
    bool fix_height = true;             ///< planar mode: heights stay as initialised
};

/// Bounds of the step-length scale variables: a scale at a bound means the map and the odometry
/// disagree (a wrong anchor, a map of another place, an estimate that is not odometry).
constexpr double kScaleMin = 0.25, kScaleMax = 4.0;

/// The families of the NLL's terms (core/cost_terms.h).
enum class TermFamily : int {
    kStepLength,
    kStepDirection,
    kHeadingChange,
    kHeadingPreservation,
    kHeightChange,
    kSpeedChange,
    kMapDistance,
    kScaleWalk,  ///< the random walk between scale segments and the prior on the first
    /// The map's lateral offset process of the covariance's model (optim/covariance.h); not a
    /// term of the objective.
    kMapOffset,
    /// The prior on a fixed-lag window's boundary pose (its marginalised past).
    kBoundaryPrior,
};
constexpr int kTermFamilies = 10;
const char* ToString(TermFamily family);

/// One term of the objective linearised at a point (core Linearisation), over the window's
/// variables: jacobian[k] = dr / d(variable var[k]), k < size (for a map term within a centre
/// line's rounding band the line's unit normal, see LineariseTerms); variables held fixed outside
/// the window (pose first-1, earlier scales) are left out, as are entries whose derivative is zero.
struct LinearisedTerm {
    TermFamily family = TermFamily::kStepLength;
    int pose = -1;  ///< the pose of a map distance or boundary prior term; -1 for the others
    int size = 0;
    std::array<int, 12> var{};
    std::array<double, 12> jacobian{};
    double residual = 0.0, information = 0.0, chi2 = 0.0;
};

/// Assigns scale segments from the estimated path length (one per `segment_m`).
std::vector<int> ScaleSegments(const std::vector<StepObservation>& obs, double segment_m);

/// What a WindowProblem is built for: kSolve also builds the sparsity of the Hessian (Ipopt needs
/// it; a hash map of ~50 entries per pose), kLinearise only what LineariseTerms needs.
enum class WindowUse { kSolve, kLinearise };

class WindowProblem {
public:
    /// `constrained[k]` (k = pose - first) marks poses that carry the hard corridor constraint.
    /// Preconditions: 1 <= first <= last < poses.size(); field may be null (no map terms);
    /// HessianValues only with use == kSolve (with kLinearise HessianStructure() is empty).
    /// `boundary_prior`: pose first-1 becomes a variable with this prior (its map term is not
    /// added: the prior summarises it); none: pose first-1 is held fixed.
    WindowProblem(TrajectoryState& state, const TraversableField* field, const ModelConfig& cfg,
                  std::size_t first, std::size_t last, std::vector<std::uint8_t> constrained,
                  WindowUse use = WindowUse::kSolve,
                  std::optional<PosePriorTerm> boundary_prior = std::nullopt);

    int NumVariables() const { return n_vars_; }
    int NumConstraints() const { return static_cast<int>(constraint_pose_.size()); }
    void InitialPoint(double* x) const;
    void Bounds(double* x_l, double* x_u, double* g_l, double* g_u) const;

    double Objective(const double* x) const;
    void Gradient(const double* x, double* grad) const;
    void Constraints(const double* x, double* g) const;

    const std::vector<std::pair<int, int>>& JacobianStructure() const { return jac_; }
    void JacobianValues(const double* x, double* values) const;
    /// Lower triangle (row >= col).
    const std::vector<std::pair<int, int>>& HessianStructure() const { return hess_; }
    void HessianValues(const double* x, double obj_factor, const double* lambda,
                       double* values) const;

    /// Every term of the objective linearised at x, appended to `terms`. The sum over the terms
    /// of information * J J^T is the Gauss-Newton Hessian of the objective: positive
    /// semi-definite, and equal to HessianValues(x, 1, 0) wherever every residual is zero and
    /// the map distance is exact.
    /// The map distance is interpolated: within about one cell of a centre line the B-spline
    /// rounds its V, so there grad d shrinks to zero and turns along the line (65-78 % of the
    /// corrected KITTI poses lie in that band). On such a grad d the Gauss-Newton curvature would
    /// lose the road's cross-track information and gain along-track information that is not in
    /// the map. There the map term's Jacobian is the line's unit normal, read from grad d at two
    /// probes across the line where the field is exact (MapJacobian): the curvature the Gaussian
    /// on the true distance has. Where the probes do not find one line (a junction, a field
    /// smoothed more widely, as the indoor field over its 0.5 m layers) grad d stays.
    void LineariseTerms(const double* x, std::vector<LinearisedTerm>& terms) const;

    /// The variable of component c (0..3: x, y, z, yaw) of window pose `pose`, -1 when held
    /// fixed (before first(), or before first()-1 with a boundary prior). Precondition:
    /// pose <= last().
    int PoseVar(std::size_t pose, int component) const;
    /// The variable of scale segment `segment`, -1 before the window's first segment.
    /// Precondition: segment <= the segment of step last().
    int ScaleVar(int segment) const;

    /// Writes a solution back into the trajectory state.
    void Store(const double* x) const;
    /// Corridor signed distance of each constrained pose at x (for reports).
    std::size_t first() const { return first_; }
    std::size_t last() const { return last_; }

private:
    struct StepSlots {
        int var[kStepVars];
        int hess_slot[kStepVars][kStepVars];  // lower triangle, -1 if not a variable pair
    };
    struct SpeedSlots {
        int var[12];
        int hess_slot[12][12];  // lower triangle, -1 if not a variable pair
    };
    ScaleRandomWalkTerm ScaleTerm(int segment) const;
    /// A step faster than max_speed_mps is a discontinuity of the estimate (a relocalisation, a
    /// reset), not odometry: its length is not scaled and no speed continuity spans it.
    bool IsJump(std::size_t i) const;
    bool HasSpeedTerm(std::size_t i) const;
    SpeedVector GatherSpeed(const double* x, std::size_t i) const;
    SpeedChangeTerm SpeedTerm(std::size_t i) const;
    int Slot(std::unordered_map<std::int64_t, int>& slots, int r, int c);
    void LineariseStep(std::size_t i, const StepVector& v,
                       std::vector<LinearisedTerm>& terms) const;
    Eigen::Vector3d MapJacobian(const Eigen::Vector3d& p, const FieldSample& centre) const;
    StepVector GatherStep(const double* x, std::size_t i) const;
    struct StepTerms {
        StepLengthTerm length;
        StepDirectionTerm direction;
        HeadingChangeTerm heading;
        HeadingPreservationTerm preservation;
        HeightChangeTerm height;  ///< used when heights are free
    };
    StepTerms TermsOfStep(std::size_t i) const;
    double StepCost(std::size_t i, const StepVector& v, StepVector* g, StepMatrix* h) const;
    Eigen::Vector3d PosePosition(const double* x, std::size_t pose) const;
    PoseVector BoundaryPose(const double* x) const;  ///< pose first-1's variables (with a prior)
    /// Map field samples of every window pose at x, queried once per distinct x (Ipopt evaluates
    /// objective, gradient, constraints and Hessians at the same point).
    const std::vector<std::optional<TraversableSample>>& Samples(const double* x) const;
    void BuildStructure(WindowUse use);

    TrajectoryState& state_;
    const TraversableField* field_;
    ModelConfig cfg_;
    std::size_t first_, last_;
    std::optional<PosePriorTerm> prior_;
    std::size_t var_first_;  ///< first pose with variables: first_, or first_-1 with a prior
    std::array<int, 10> prior_hess_slot_{};  ///< lower triangle of the prior's 4x4 block
    int seg_first_ = 0, seg_last_ = 0, n_vars_ = 0;
    std::vector<std::size_t> constraint_pose_;
    std::vector<StepSlots> steps_;
    std::vector<SpeedSlots> speeds_;  // per step i in [first, last]; used when HasSpeedTerm(i)
    std::vector<std::pair<int, int>> jac_, hess_;
    std::vector<std::array<int, 6>> pose_hess_slot_;
    std::vector<std::array<int, 3>> scale_hess_slot_;
    mutable std::vector<double> cache_x_;
    mutable std::vector<std::optional<TraversableSample>> cache_samples_;
};

}  // namespace driftcorr
