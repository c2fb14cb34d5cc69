// The definitions of what driftcorr/core/observables.h declares.
#include "driftcorr/core/observables.h"

#include <algorithm>
#include <cmath>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"

namespace driftcorr {
namespace {

// Heading of each pose from the step directions: pose i looks along the next moving step; poses
// after the last moving step keep the last direction; no moving step at all gives heading 0.
std::vector<double> HeadingsFromSteps(const PlanarTrajectory& traj, double stationary_m) {
    const std::size_t n = traj.size();
    std::vector<double> yaw(n, 0.0);
    bool have = false;
    double next = 0.0;
    for (std::size_t k = n - 1; k-- > 0;) {
        const Eigen::Vector2d d = traj.p_en[k + 1] - traj.p_en[k];
        if (d.norm() > stationary_m) {
            next = std::atan2(d.y(), d.x());
            have = true;
        }
        yaw[k] = next;
    }
    yaw[n - 1] = n >= 2 ? yaw[n - 2] : 0.0;
    for (std::size_t k = n - 1; k > 0 && have; --k) {
        if ((traj.p_en[k] - traj.p_en[k - 1]).norm() > stationary_m) {
            yaw[n - 1] = std::atan2((traj.p_en[k] - traj.p_en[k - 1]).y(),
                                    (traj.p_en[k] - traj.p_en[k - 1]).x());
            break;
        }
    }
    return yaw;
}

}  // namespace

std::vector<double> UnwrappedHeadings(const PlanarTrajectory& traj, double stationary_m) {
    std::vector<double> yaw = traj.HasYaw() ? traj.yaw_rad : HeadingsFromSteps(traj, stationary_m);
    for (std::size_t i = 1; i < yaw.size(); ++i)
        yaw[i] = yaw[i - 1] + AngleDiff(yaw[i], yaw[i - 1]);
    return yaw;
}

std::vector<StepObservation> ComputeObservations(const PlanarTrajectory& traj,
                                                 double stationary_m) {
    DRIFTCORR_CHECK(traj.size() >= 2, "a trajectory needs at least two poses");
    const std::vector<double> yaw = UnwrappedHeadings(traj, stationary_m);
    std::vector<StepObservation> obs(traj.size());
    for (std::size_t i = 1; i < traj.size(); ++i) {
        StepObservation& o = obs[i];
        const Eigen::Vector2d d = traj.p_en[i] - traj.p_en[i - 1];
        o.dt_s = traj.t_s[i] - traj.t_s[i - 1];
        o.length_m = d.norm();
        o.stationary = o.length_m <= stationary_m;
        o.direction_rad = o.stationary ? 0.0 : AngleDiff(std::atan2(d.y(), d.x()), yaw[i - 1]);
        o.dheading_rad = yaw[i] - yaw[i - 1];
        o.dup_m = traj.up_m[i] - traj.up_m[i - 1];
        if (o.stationary) o.length_m = 0.0;
    }
    return obs;
}

namespace {

// A boundary after step k where the mean speed changes by dv [m/s] (RepairSpeedEpisodes).
struct SpeedEdge {
    std::size_t k;
    double dv;
};

}  // namespace

std::size_t RepairSpeedEpisodes(std::vector<StepObservation>& obs, double max_accel_mps2,
                                double window_s, double max_episode_s, double deviation) {
    const std::size_t n = obs.size();
    if (n < 4 || !(max_accel_mps2 > 0.0)) return 0;
    std::vector<double> len(n, 0.0), time(n, 0.0);  // prefix sums over steps 1..i
    for (std::size_t i = 1; i < n; ++i) {
        len[i] = len[i - 1] + obs[i].length_m;
        time[i] = time[i - 1] + std::max(obs[i].dt_s, 0.0);
    }
    if (!(time[n - 1] > 0.0)) return 0;
    const auto w =
        static_cast<std::size_t>(std::max(1L, std::lround(window_s * double(n - 1) / time[n - 1])));
    // Mean speed of steps a+1..b.
    auto speed = [&](std::size_t a, std::size_t b) {
        const double dt = time[b] - time[a];
        return dt > 0.0 ? (len[b] - len[a]) / dt : 0.0;
    };
    std::vector<SpeedEdge> edges;  // one per run of same-signed boundaries: the largest change
    for (std::size_t k = w; k + w < n; ++k) {
        const double dv = speed(k, k + w) - speed(k - w, k);
        const double gap_s = 0.5 * (time[k + w] - time[k - w]);
        if (!(gap_s > 0.0) || std::abs(dv) / gap_s <= max_accel_mps2) continue;
        if (!edges.empty() && k - edges.back().k <= w && (dv < 0.0) == (edges.back().dv < 0.0)) {
            if (std::abs(dv) > std::abs(edges.back().dv)) edges.back() = {k, dv};
            continue;
        }
        edges.push_back({k, dv});
    }
    std::size_t episodes = 0;
    for (std::size_t e = 0; e + 1 < edges.size(); ++e) {
        const SpeedEdge a = edges[e], b = edges[e + 1];
        if (!(a.dv < 0.0) || !(b.dv > 0.0) || time[b.k] - time[a.k] > max_episode_s) continue;
        const double v0 = speed(a.k - w, a.k), v1 = speed(b.k, std::min(b.k + w, n - 1));
        const double t0 = time[a.k], t1 = time[b.k];
        bool any = false;
        for (std::size_t i = a.k - w + 1; i <= std::min(b.k + w, n - 1); ++i) {
            StepObservation& o = obs[i];
            if (o.repaired || !(o.dt_s > 0.0)) continue;
            const double u = t1 > t0 ? std::clamp((time[i] - t0) / (t1 - t0), 0.0, 1.0) : 0.0;
            const double v_ref = (1.0 - u) * v0 + u * v1;
            if (!(v_ref > 0.0) || std::abs(o.length_m / o.dt_s - v_ref) <= deviation * v_ref)
                continue;
            o.observed_length_m = o.length_m;
            o.length_m = v_ref * o.dt_s;
            o.repaired = true;
            o.stationary = false;
            any = true;
        }
        if (any) ++episodes;
        ++e;  // b closes this episode
    }
    return episodes;
}

std::vector<std::uint8_t> LevelSpans(const std::vector<double>& t_s,
                                     const std::vector<double>& up_m, double window_s,
                                     double height_m) {
    DRIFTCORR_CHECK(t_s.size() == up_m.size(), "one time per height");
    const std::size_t n = t_s.size();
    const double half_s = 0.5 * window_s;
    std::vector<std::uint8_t> level(n, 0);
    // Indices of the span's running minimum and maximum (monotone queues over [lo, hi]).
    std::vector<std::size_t> lows, highs;
    std::size_t low_head = 0, high_head = 0, lo = 0, hi = 0;
    for (std::size_t i = 0; i < n; ++i) {
        for (; hi < n && t_s[hi] <= t_s[i] + half_s; ++hi) {
            while (lows.size() > low_head && up_m[lows.back()] >= up_m[hi]) lows.pop_back();
            while (highs.size() > high_head && up_m[highs.back()] <= up_m[hi]) highs.pop_back();
            lows.push_back(hi);
            highs.push_back(hi);
        }
        while (t_s[lo] < t_s[i] - half_s) ++lo;
        while (lows[low_head] < lo) ++low_head;
        while (highs[high_head] < lo) ++high_head;
        level[i] = up_m[highs[high_head]] - up_m[lows[low_head]] <= height_m;
    }
    return level;
}

std::vector<std::uint8_t> RideSpans(const std::vector<StepObservation>& obs, double min_s,
                                    double min_height_m, double gap_s, double lag_s) {
    const std::size_t n = obs.size();
    std::vector<std::uint8_t> ride(n, 0);
    std::vector<double> t_s(n, 0.0), up_m(n, 0.0);
    for (std::size_t i = 1; i < n; ++i) {
        t_s[i] = t_s[i - 1] + std::max(obs[i].dt_s, 0.0);
        up_m[i] = up_m[i - 1] + obs[i].dup_m;
    }
    auto still = [&](std::size_t i) { return obs[i].stationary || obs[i].dt_s > gap_s; };
    for (std::size_t i = 1; i < n;) {
        if (!still(i)) {
            ++i;
            continue;
        }
        const std::size_t a = i - 1;  // the run's poses: a .. b
        std::size_t b = i;
        while (b + 1 < n && still(b + 1)) ++b;
        i = b + 1;
        if (t_s[b] - t_s[a] < min_s) continue;
        double change_m = 0.0;
        for (std::size_t j = a; j < n && t_s[j] <= t_s[b] + lag_s; ++j) {
            change_m = std::max(change_m, std::abs(up_m[j] - up_m[a]));
        }
        if (change_m < min_height_m) continue;
        std::fill(ride.begin() + a, ride.begin() + b + 1, std::uint8_t(1));
    }
    return ride;
}

std::size_t MoveRideLag(std::vector<StepObservation>& obs, double min_s, double min_height_m,
                        double gap_s, double lag_s) {
    const std::vector<std::uint8_t> ride = RideSpans(obs, min_s, min_height_m, gap_s, lag_s);
    const std::size_t n = obs.size();
    std::size_t rides = 0;
    for (std::size_t a = 0; a < n;) {  // a ride's poses: a .. b
        if (!ride[a]) {
            ++a;
            continue;
        }
        std::size_t b = a;
        while (b + 1 < n && ride[b + 1]) ++b;
        // The ride's last step that changes height by at least half its largest change: the
        // cabin arrives there; what the steps after it read is lag.
        double largest_m = 0.0;
        for (std::size_t i = a + 1; i <= b; ++i)
            largest_m = std::max(largest_m, std::abs(obs[i].dup_m));
        std::size_t main = b;
        while (std::abs(obs[main].dup_m) < 0.5 * largest_m) --main;
        auto move = [&](std::size_t i) {
            obs[main].dup_m += obs[i].dup_m;
            obs[i].dup_m = 0.0;
        };
        for (std::size_t i = main + 1; i <= b; ++i) move(i);
        double after_s = 0.0;  // up to the next ride at most
        for (std::size_t i = b + 1; i < n && !ride[i]; ++i) {
            after_s += std::max(obs[i].dt_s, 0.0);
            if (after_s > lag_s) break;
            move(i);
        }
        ++rides;
        a = b + 1;
    }
    return rides;
}

std::size_t MarkStairTreads(std::vector<StepObservation>& obs, double tread_m, double window_s,
                            double min_rate_mps, double gap_s) {
    // Building codes ask three risers of a flight at least: fewer steps amid a height change are
    // the barometer's (a door, a draught), not stairs.
    constexpr std::size_t kMinRisers = 3;
    const std::size_t n = obs.size();
    auto walking = [&](std::size_t i) { return !obs[i].stationary && obs[i].dt_s <= gap_s; };
    std::vector<double> t_s(n, 0.0);
    for (std::size_t i = 1; i < n; ++i) t_s[i] = t_s[i - 1] + std::max(obs[i].dt_s, 0.0);
    // Prefix sums over the walking steps: height change and time.
    std::vector<double> up_m(n + 1, 0.0), walk_s(n + 1, 0.0);
    for (std::size_t i = 1; i < n; ++i) {
        const bool w = walking(i);
        up_m[i + 1] = up_m[i] + (w ? obs[i].dup_m : 0.0);
        walk_s[i + 1] = walk_s[i] + (w ? obs[i].dt_s : 0.0);
    }
    std::vector<std::uint8_t> tread(n, 0);
    std::size_t lo = 1, hi = 1, count = 0;  // the steps of [lo, hi) lie within the window
    for (std::size_t i = 1; i < n; ++i) {
        while (hi < n && t_s[hi] <= t_s[i] + 0.5 * window_s) ++hi;
        while (t_s[lo] < t_s[i] - 0.5 * window_s) ++lo;
        const double rise_m = up_m[hi] - up_m[lo], time_s = walk_s[hi] - walk_s[lo];
        tread[i] = walking(i) && time_s > 0.0 && std::abs(rise_m) >= min_rate_mps * time_s;
    }
    for (std::size_t a = 1; a < n;) {  // a flight: the treads a .. b - 1, at least kMinRisers
        if (!tread[a]) {
            ++a;
            continue;
        }
        std::size_t b = a;
        while (b < n && tread[b]) ++b;
        for (std::size_t i = a; b - a >= kMinRisers && i < b; ++i) {
            StepObservation& o = obs[i];
            if (o.tread) continue;
            if (!o.repaired) o.observed_length_m = o.length_m;
            o.length_m = tread_m;
            o.tread = true;
            ++count;
        }
        a = b;
    }
    return count;
}

bool GaitStep(const StepObservation& o, double max_speed_mps) {
    return !o.stationary && !o.repaired && !o.tread && o.length_m > 0.0 &&
           !IsJump(o, max_speed_mps);
}

void RunningMedian::Add(double value) {
    // upper_ holds ceil(n / 2) values, each at least every one of lower_.
    if (!upper_.empty() && value < upper_.top()) {
        lower_.push(value);
    } else {
        upper_.push(value);
    }
    if (lower_.size() > upper_.size()) {
        upper_.push(lower_.top());
        lower_.pop();
    } else if (upper_.size() > lower_.size() + 1) {
        lower_.push(upper_.top());
        upper_.pop();
    }
}

double MedianGaitStep(const std::vector<StepObservation>& obs, double max_speed_mps) {
    std::vector<double> lengths;
    for (std::size_t i = 1; i < obs.size(); ++i) {
        if (GaitStep(obs[i], max_speed_mps)) lengths.push_back(obs[i].length_m);
    }
    if (lengths.empty()) return 0.0;
    auto mid = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
    std::nth_element(lengths.begin(), mid, lengths.end());
    return *mid;
}

void ReadAtGait(StepObservation& o, double median_m, double exponent, double max_speed_mps) {
    if (exponent == 1.0 || !(median_m > 0.0) || !GaitStep(o, max_speed_mps)) return;
    o.observed_length_m = o.length_m;
    o.length_m = std::pow(median_m, 1.0 - exponent) * std::pow(o.length_m, exponent);
}

double NearestFloor(const std::vector<double>& floor_heights_m, double up_m) {
    DRIFTCORR_CHECK(!floor_heights_m.empty(), "no floor");
    return *std::min_element(
        floor_heights_m.begin(), floor_heights_m.end(),
        [up_m](double a, double b) { return std::abs(a - up_m) < std::abs(b - up_m); });
}

GradeBound BoundGrades(const std::vector<Eigen::Vector2d>& en, double stretch_m, double max_grade,
                       std::vector<double>& up_m) {
    DRIFTCORR_CHECK(en.size() == up_m.size(), "one height per position");
    GradeBound bound;
    if (!(max_grade > 0.0) || en.size() < 2) return bound;
    const std::vector<double> in = up_m;
    std::size_t a = 0;
    while (a + 1 < en.size()) {
        std::size_t b = a;
        double run_m = 0.0;
        while (b + 1 < en.size() && run_m < stretch_m) {
            run_m += (en[b + 1] - en[b]).norm();
            ++b;
        }
        const double rise_m = in[b] - in[a];
        double f = 1.0;
        if (std::abs(rise_m) > max_grade * run_m) {
            f = max_grade * run_m / std::abs(rise_m);
            ++bound.limited;
        }
        for (std::size_t k = a + 1; k <= b; ++k) up_m[k] = up_m[a] + f * (in[k] - in[a]);
        ++bound.stretches;
        a = b;
    }
    return bound;
}

}  // namespace driftcorr
