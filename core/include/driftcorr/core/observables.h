#pragma once
// What a drifting trajectory measures well, per step i (from pose i-1 to pose i): the step length,
// the step's direction relative to the heading, the heading change and the height change.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <queue>
#include <vector>

#include "driftcorr/core/types.h"

namespace driftcorr {

struct StepObservation {
    double dt_s = 0.0;      ///< t_i - t_{i-1} [s]
    double length_m = 0.0;  ///< horizontal step length [m]
    double direction_rad =
        0.0;  ///< step direction minus heading of pose i-1 [rad] (0 if stationary)
    double dheading_rad = 0.0;  ///< heading change yaw_i - yaw_{i-1}, wrapped [rad]
    double dup_m = 0.0;         ///< height change [m]
    bool stationary = false;    ///< length below the stationary threshold
    /// The odometry's length for this step was an outlier (RepairSpeedEpisodes): length_m holds
    /// the speed the neighbouring steps imply, observed_length_m what the odometry said.
    bool repaired = false;
    /// A stair tread (MarkStairTreads): length_m holds the tread's run, which the step-length
    /// scale does not scale, observed_length_m what the odometry said.
    bool tread = false;
    double observed_length_m = 0.0;  ///< [m], set when repaired, a tread or read at the gait
};

/// The horizontal length a step moves at step-length scale `scale`: a tread's run is its own.
inline double ScaledLength(const StepObservation& o, double scale) {
    return o.tread ? o.length_m : scale * o.length_m;
}

/// Observations of a planar trajectory: result[i] describes the step into pose i; result[0] is
/// all zeros. Headings come from `traj.yaw_rad` when present; otherwise from the step directions
/// (the heading of pose i is the direction of the next moving step, carried across stops).
/// Precondition: traj.size() >= 2.
std::vector<StepObservation> ComputeObservations(const PlanarTrajectory& traj,
                                                 double stationary_m = 1e-3);

/// Headings used by ComputeObservations, unwrapped (continuous, no 2*pi jumps) [rad].
std::vector<double> UnwrappedHeadings(const PlanarTrajectory& traj, double stationary_m = 1e-3);

/// Explicit outlier handling of the step lengths: odometry that drops steps (a frame-to-frame
/// registration that returns a fraction of the motion) or doubles them shows as a speed change
/// no vehicle makes. An edge is a change of the mean speed over `window_s` against the window
/// before it faster than `max_accel_mps2`; a drop edge followed by a rise edge within
/// `max_episode_s` encloses an episode of dropped steps. Doubled steps (a rise and a drop) are
/// left to the step terms: a drop whose onset stays under the threshold would pair its recovery
/// with the next drop (measured: docs/results.md, "Heavy-tailed step and scale terms on the KITTI
/// drives"). Inside it (widened by one window each side)
/// every moving step whose speed is more than `deviation` (a share) off the speed interpolated
/// between the windows before and after the episode is repaired: its length becomes that speed
/// times dt (repaired = true, observed_length_m keeps the odometry's). A lone edge (a speed that
/// changes and stays) is not repaired: nothing tells which side is wrong.
/// Returns the number of episodes. obs as ComputeObservations returns it (obs[0] unused).
std::size_t RepairSpeedEpisodes(std::vector<StepObservation>& obs, double max_accel_mps2,
                                double window_s, double max_episode_s, double deviation);

/// Where a height profile is level: result[i] is 1 when up_m stays within height_m (max - min)
/// over the samples with t in [t_s[i] - window_s / 2, t_s[i] + window_s / 2] (those the arrays
/// hold: at their ends the span is cut short). A barometer reads a level walk 0.6-0.7 m peak to
/// peak and a stair climb about 4 m in 20 s. Precondition: t_s ascending, one time per height.
std::vector<std::uint8_t> LevelSpans(const std::vector<double>& t_s,
                                     const std::vector<double>& up_m, double window_s,
                                     double height_m);

/// Lift rides: result[i] is 1 when pose i lies in a run of steps that do not walk (stationary,
/// or longer than gap_s: no step detected for that long) lasting min_s or more, over which (and
/// the lag_s after it: a barometer lags by seconds) the height changes by min_height_m or more
/// from the run's first pose: the walker stood while changing floors. A stair climb walks, and
/// waiting keeps the height. obs as ComputeObservations returns it (obs[0] unused).
std::vector<std::uint8_t> RideSpans(const std::vector<StepObservation>& obs, double min_s,
                                    double min_height_m, double gap_s, double lag_s);

/// A barometer lags a lift ride by seconds: besides the ride's own steps, the standing after it
/// and the first steps out of the cabin read part of its height change (the real Zero2four walk:
/// 8.2 m of its 13.6 m ride come in its first step out). For each ride of RideSpans (same
/// parameters), the height changes read after its last step of at least half its largest change
/// (where the cabin arrives: the standing after it, and the steps within lag_s after the ride)
/// move into that step, so the pose where it ends stands at the height the ride reached and the
/// walk after it is level. Returns the number of rides.
/// obs as ComputeObservations returns it (obs[0] unused).
std::size_t MoveRideLag(std::vector<StepObservation>& obs, double min_s, double min_height_m,
                        double gap_s, double lag_s);

/// Stair treads: a walker climbing or descending stairs steps from tread to tread, so a step's
/// horizontal run is a tread's (about 0.29 m under the step rule 2 x rise + run = 0.63 m for a
/// 0.17 m rise), while a step model reads it as a level step (the real Zero2four walk: 0.39 m a
/// step along its stairs, with their landings, against 0.84 m on its level floors, for the same
/// 0.47-0.51 m of the PDR's). A walking step (not stationary, not longer than gap_s) amid a
/// height change of at least min_rate_mps, read over the walking steps within window_s around it
/// (their height change over their time: standing, as in a lift, counts neither), in a run of
/// at least three such steps (a flight's fewest risers), becomes a tread: tread = true,
/// length_m = tread_m, observed_length_m the odometry's. Returns the number of new treads.
/// obs as ComputeObservations returns it (obs[0] unused); a lift ride's lagged reading moved
/// into the ride first (MoveRideLag), or it reads as a climb on the steps out of the cabin.
std::size_t MarkStairTreads(std::vector<StepObservation>& obs, double tread_m, double window_s,
                            double min_rate_mps, double gap_s);

/// A step faster than max_speed_mps: a discontinuity of the estimate, not motion (the model
/// neither scales it nor gives it a speed term).
inline bool IsJump(const StepObservation& o, double max_speed_mps) {
    return o.length_m > max_speed_mps * std::max(o.dt_s, 1e-9);
}

/// A step whose length a pedestrian step model reads with its gait error (ReadAtGait): moving,
/// neither repaired nor a tread, and no jump.
bool GaitStep(const StepObservation& o, double max_speed_mps);

/// The median of the values added so far, the upper one of an even count (the element at index
/// size / 2 of them sorted, as MedianGaitStep takes it), in O(log n) per value.
class RunningMedian {
public:
    void Add(double value);
    /// Precondition: a value was added.
    double Median() const { return upper_.top(); }

private:
    std::priority_queue<double> lower_;                                       ///< the smaller half
    std::priority_queue<double, std::vector<double>, std::greater<>> upper_;  ///< the rest
};

/// The median length of obs's GaitSteps [m]; 0 when there is none.
/// obs as ComputeObservations returns it (obs[0] unused).
double MedianGaitStep(const std::vector<StepObservation>& obs, double max_speed_mps);

/// A pedestrian step model's length errs with the gait far more than a walker's steps vary:
/// on the real Eight walk (../shared/datasets/hcu_eight) the surveyed level steps vary by 5 %
/// (log sd) and the PDR's by 12 %, and the log of a PDR step explains little of the surveyed
/// one's (regression slope 0.16). A GaitStep's length becomes
/// median_m^(1 - exponent) * length^exponent (observed_length_m keeps the odometry's): exponent
/// 1 reads it as it is, 0 as the median step. Nothing happens to another step, or when
/// median_m <= 0.
void ReadAtGait(StepObservation& o, double median_m, double exponent, double max_speed_mps);

/// The one of floor_heights_m nearest to up_m. Precondition: floor_heights_m not empty.
double NearestFloor(const std::vector<double>& floor_heights_m, double up_m);

/// Roads climb and fall at bounded grades. Along the horizontal path `en`, cut into stretches of
/// at least `stretch_m` (each ends at the first pose that far along from its start; the last
/// may be shorter), a stretch whose height change in `up_m` is steeper than `max_grade` (rise
/// over run) has it scaled down to the bound, the heights inside it alike; the stretches are
/// chained from the first height. `up_m` is changed in place. Returns the number of stretches
/// and of those limited. Nothing changes when max_grade <= 0. Precondition: en and up_m of one
/// size.
struct GradeBound {
    std::size_t stretches = 0, limited = 0;
};
GradeBound BoundGrades(const std::vector<Eigen::Vector2d>& en, double stretch_m, double max_grade,
                       std::vector<double>& up_m);

}  // namespace driftcorr
