#pragma once
// The correction as a nonlinear program over a window of poses [first, last] of a trajectory,
// solver-independent: objective (the weighted NLL), its gradient and exact Hessian, and the
// hard corridor constraints with their Jacobian and Hessians, in sparse triplet form.
// Pose first-1 and everything before it is held fixed, at the values the state has when the
// problem is built; with a boundary prior (a fixed-lag window whose earlier poses are
// marginalised) pose first-1 is a variable too, tied to the window by the terms of step `first`
// and to the past by the prior (core PosePriorTerm); a prior joint with the scale of pose
// first-1's segment makes that scale a variable as well, and replaces its walk and range terms.
//
// Variables: per pose (x, y, z, yaw) in the ENU map frame, then one scale per scale segment
// touched by the window's steps, then one heading-rate bias per bias segment they touch.
#include <array>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <new>
#include <optional>
#include <utility>
#include <vector>

#include "driftcorr/core/cost_terms.h"
#include "driftcorr/core/observables.h"
#include "driftcorr/mapping/traversable_field.h"
#include "driftcorr/optim/model_config.h"
#include "driftcorr/optim/term_block.h"

namespace driftcorr {

struct PoseState {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();  ///< ENU [m]
    double yaw_rad = 0.0;                         ///< unwrapped heading
};

/// The whole trajectory's state and its fixed inputs; windows read and write it.
struct TrajectoryState {
    std::vector<StepObservation> obs;  ///< obs[i]: step into pose i
    std::vector<int> scale_segment;    ///< scale segment of step i (obs index)
    std::vector<PoseState> poses;
    std::vector<double> scales;  ///< one per scale segment
    /// Heading-rate bias segment of step i (obs index), ascending; empty: no bias variables.
    std::vector<int> bias_segment;
    std::vector<double> biases;  ///< one per bias segment [rad/s]
    bool fix_height = true;      ///< planar mode: heights stay as initialised
    /// Steps whose height change is read as settled (obs index; empty: none): a window's floor
    /// restarts (CorrectorConfig::restart_height_gains) neither count nor re-read them.
    std::vector<std::uint8_t> height_settled;
};

/// Assigns scale segments from the estimated path length (one per `segment_m`).
std::vector<int> ScaleSegments(const std::vector<StepObservation>& obs, double segment_m);
/// The estimated path from pose 0 to each pose [m]: the sum of the step lengths obs[1..i].
std::vector<double> PathPositions(const std::vector<StepObservation>& obs);
/// The standard deviations of one step's odometry terms under `model`: its length (looser for a
/// repaired step), its lateral offset, its heading change and its height change.
struct StepNoise {
    double length_m = 0.0, lateral_m = 0.0, heading_rad = 0.0, height_m = 0.0;
};
StepNoise StepNoiseOf(const ModelConfig& model, const StepObservation& step);

/// Assigns heading-rate bias segments from the time (one per `segment_s`); empty if segment_s
/// is 0 (no bias).
std::vector<int> BiasSegments(const std::vector<StepObservation>& obs, double segment_s);

/// What a WindowProblem is built for: kSolve also builds the sparsity of the Hessian (Ipopt needs
/// it; a hash map of ~50 entries per pose), kLinearise only what LineariseTerms needs.
enum class WindowUse { kSolve, kLinearise };

class WindowProblem {
public:
    /// `constrained[k]` (k = pose - first) marks poses that carry the hard corridor constraint.
    /// Preconditions: 1 <= first <= last < poses.size(); field may be null (no map terms);
    /// HessianValues only with use == kSolve (with kLinearise HessianStructure() is empty).
    /// `boundary_prior`: pose first-1 becomes a variable with this prior (its map term is not
    /// added: the prior summarises it), and so does the scale of segment
    /// boundary_prior->scale_segment when the prior carries it (its walk and range terms are not
    /// added either); none: pose first-1 is held fixed.
    WindowProblem(TrajectoryState& state, const TraversableField* field, const ModelConfig& cfg,
                  std::size_t first, std::size_t last, std::vector<std::uint8_t> constrained,
                  WindowUse use = WindowUse::kSolve,
                  std::optional<PosePriorTerm> boundary_prior = std::nullopt);

    ~WindowProblem();
    WindowProblem(const WindowProblem&) = delete;
    WindowProblem& operator=(const WindowProblem&) = delete;

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
    /// Objective(x), returned, with Gradient(x) and HessianValues(x, 1, none) in one pass over
    /// the blocks (each evaluated once); the same values to the last bit. Precondition:
    /// use == kSolve.
    double ObjectiveGradientHessian(const double* x, double* grad, double* values) const;

    /// Every term of the objective linearised at x, appended to `terms` (TermBlock::Linearise;
    /// variables held fixed outside the window and zero derivatives left out). The sum over the
    /// terms of information * J J^T is the Gauss-Newton Hessian of the objective: positive
    /// semi-definite, and equal to HessianValues(x, 1, 0) wherever every residual is zero and
    /// the map distance is exact (see MapDistanceBlock for the map term's Jacobian).
    void LineariseTerms(const double* x, std::vector<LinearisedTerm>& terms) const;

    /// The variable of component c (0..3: x, y, z, yaw) of window pose `pose`, -1 when held
    /// fixed (before first(), or before first()-1 with a boundary prior). Precondition:
    /// pose <= last().
    int PoseVar(std::size_t pose, int component) const;
    /// The variable of scale segment `segment`, -1 before the window's first segment.
    /// Precondition: segment <= the segment of step last().
    int ScaleVar(int segment) const;
    /// The variable of heading-rate bias segment `segment`, -1 before the window's first one or
    /// when the state has no bias.
    int BiasVar(int segment) const;

    /// The window's terms, each one unit (optim/term_block.h), and what they read at x.
    const std::vector<TermBlock*>& Blocks() const { return blocks_; }
    BlockContext Context(const double* x) const;

    /// Writes a solution back into the trajectory state.
    void Store(const double* x) const;
    std::size_t first() const { return first_; }
    std::size_t last() const { return last_; }

private:
    /// A step faster than max_speed_mps is a discontinuity of the estimate (a relocalisation, a
    /// reset), not odometry: its length is not scaled and no speed continuity spans it.
    bool IsJump(std::size_t i) const;
    bool HasSpeedTerm(std::size_t i) const;
    /// The blocks of step i (length, direction, heading change, preservation, height change when
    /// heights are free, speed change) appended to blocks_.
    void AddStepBlocks(std::size_t i);
    void AddScaleBlocks();
    void AddBiasBlocks();
    void AddFloorBlocks();
    void AddLiftBlocks();
    bool HasBias() const { return !state_.bias_segment.empty(); }
    /// Binds local variable k of `block` to component c of `pose` (fixed before the window).
    void BindPose(TermBlock& block, int k0, std::size_t pose) const;
    Eigen::Vector3d PosePosition(const double* x, std::size_t pose) const;
    /// Map field samples of every window pose at x, queried once per distinct x (Ipopt evaluates
    /// objective, gradient, constraints and Hessians at the same point); the corridor distance
    /// only in a window with constraints (left zero otherwise: no term reads it).
    const std::vector<std::optional<TraversableSample>>& Samples(const double* x) const;
    void BuildStructure(WindowUse use);
    /// A block of type Block made in the window's arena (freed with the window, all at once).
    template <class Block, class... Args>
    TermBlock* Make(Args&&... args) {
        return new (arena_.allocate(sizeof(Block), alignof(Block)))
            Block(std::forward<Args>(args)...);
    }
    template <class Term, int N>
    TermBlock* Core(TermFamily family, const Term& term) {
        return Make<CoreTermBlock<Term, N>>(family, term);
    }
    double AccumulateBlocks(const BlockContext& ctx, const double* x, double obj_factor,
                            double* grad, double* values) const;

    TrajectoryState& state_;
    const TraversableField* field_;
    ModelConfig cfg_;
    std::size_t first_, last_;
    std::optional<PosePriorTerm> prior_;
    std::size_t var_first_;  ///< first pose with variables: first_, or first_-1 with a prior
    int seg_first_ = 0, seg_last_ = 0, n_vars_ = 0;
    int bias_first_ = 0, bias_last_ = -1, bias_var0_ = 0;  // bias segments in the window
    std::vector<std::size_t> constraint_pose_;
    /// The blocks' memory: a window's eight or so blocks a pose, made and freed together, not
    /// one allocation each (the first buffer sized for them).
    static constexpr std::size_t kArenaBytesPerPose = 2048;
    std::pmr::monotonic_buffer_resource arena_;
    std::vector<TermBlock*> blocks_;  ///< in arena_
    /// Block b's entries, [block_entry_begin_[b], block_entry_begin_[b + 1]): the lower triangle
    /// over the variables it reads, those held fixed left out.
    std::vector<int> block_entry_begin_;
    std::vector<BlockEntry> block_entries_;
    std::vector<std::pair<int, int>> jac_, hess_;
    std::vector<std::array<int, 6>> pose_hess_slot_;
    mutable std::vector<double> cache_x_;
    mutable std::vector<std::optional<TraversableSample>> cache_samples_;
};

/// The soft objective (the NLL without the hard corridor constraint) of poses [1, last] of `s` at
/// its values, pose 0 fixed: the score that compares corrections of one trajectory from different
/// start scales. Precondition: 1 <= last < s.poses.size(). More than `block_poses` poses are
/// evaluated in consecutive windows of that many, the same sum with a window's memory.
double SoftNll(TrajectoryState& s, const TraversableField* field, const ModelConfig& model,
               std::size_t last, std::size_t block_poses = 100000);

}  // namespace driftcorr
