// What a map cannot correct: the along-track error on a drive's final straight.
//
// A road (or corridor) map constrains a trajectory across the road everywhere, but along it only
// where the road turns. After the drive's last turn, no map term (and no later measurement) says
// how far the platform went: a corrector can only carry on with the estimate's steps times the
// step-length scale it learned before the straight. When the odometry's scale changes on that
// straight, the error it leaves is beyond any map-only corrector, however good.
//
// For each scenario with ground truth this prints, from the ground truth and the estimate only
// (no correction is run):
//  - the final straight: the longest tail of the drive whose ground-truth direction (over 5 m
//    chords) stays within 10 deg of the final direction; its first pose and length;
//  - the scale before it: ground-truth path / estimate path over the 500 m of path before it
//    (the best scale a corrector could have learned), and the scale on the straight itself;
//  - the bound: a corrector that is exact at the start of the straight and then moves along the
//    road by the estimate's steps times the scale before it. Its along-track error at the end is
//    the lower bound on the final error; RMS over the whole drive (zero error before the
//    straight) is the lower bound on the ATE that the straight alone contributes.
//
// And the same reasoning on every straight of the drive or walk: the drive is cut where its
// ground-truth direction has turned by more than TURN_DEG (default 30) from the direction at the
// start of the current straight, and indoors also where the true height has changed by more than
// CLIMB_M (default 0.5 m) since the last cut (stairs and lifts, which the map places too); a
// corrector exact at every cut and moving along each straight by the estimate's steps, scaled to
// the straight's true length (constant scale on it; on the last straight, which no turn ends, the
// scale before it), leaves an along-track error whose RMS over the whole drive is printed as the
// bound of every straight.
//
// And what a causal output (each pose corrected with the epochs up to it, the online mode's) cannot
// know: on the first straight, up to the first cut, nothing has yet told the step-length scale,
// so a causal corrector moves by the estimate's steps at the model's prior scale (the default
// model's ModelConfig::scale_prior_mean for the scenario's mode, or environment SCALE_PRIOR). Its
// along-track error there, with zero error everywhere else, is printed as the causal bound of the
// first straight (RMS over the whole drive or walk). After it, a causal corrector can at best carry
// the scale of the path before each straight (as on the final straight above) until the straight's
// end turn tells its length: the causal figure of every straight, an estimate of what the filter
// leaves rather than a bound (a scale that varies can be predicted better or worse).
//
// Run: build/tests/final_straight [scenario dir ...]  (default: the 7 KITTI scenarios)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "driftcorr/core/angles.h"
#include "driftcorr/pipeline/pipeline.h"
#include "scenario_list.h"

namespace {

using namespace driftcorr;

constexpr double kChordM = 5.0;  // direction of travel measured over this much path
// A straight keeps within this of the final direction [deg] (environment STRAIGHT_DEG).
double kStraightDeg = 10.0;
constexpr double kScaleWindowM = 500.0;  // path before the straight for its scale
// A new straight starts where the direction turned this much [deg] (environment TURN_DEG).
double kTurnDeg = 30.0;
// Indoors a straight also ends where the true height changed this much since the last cut [m]
// (environment CLIMB_M).
double kClimbM = 0.5;
// The causal first straight's scale when > 0 (environment SCALE_PRIOR), else the model's prior.
double kScalePrior = 0.0;

// The step scale between poses a and b: ground-truth path over the estimate's path.
double PathRatio(const std::vector<double>& sg, const std::vector<double>& se, std::size_t a,
                 std::size_t b) {
    return (sg[b] - sg[a]) / std::max(se[b] - se[a], 1e-9);
}

// The best scale a corrector could have learned before pose `from`: the PathRatio of the
// kScaleWindowM of path before it; the prior scale at the start.
double ScaleBefore(const std::vector<double>& sg, const std::vector<double>& se, std::size_t from,
                   double prior) {
    if (from == 0) return prior;
    std::size_t back = from;
    while (back > 0 && sg[from] - sg[back] < kScaleWindowM) --back;
    return PathRatio(sg, se, back, from);
}

// Direction of travel at pose i: the chord to the first pose kChordM further on (or from the
// first pose kChordM back, near the end). NaN while the platform stands.
double Direction(const PlanarTrajectory& t, const std::vector<double>& s, std::size_t i) {
    std::size_t j = i;
    while (j + 1 < t.size() && s[j] - s[i] < kChordM) ++j;
    std::size_t k = i;
    if (s[j] - s[i] < kChordM) {
        j = i;
        while (k > 0 && s[i] - s[k] < kChordM) --k;
    }
    const Eigen::Vector2d d = t.p_en[j] - t.p_en[k];
    return d.norm() < 0.5 * kChordM ? std::nan("") : std::atan2(d.y(), d.x());
}

void Evaluate(const std::string& dir) {
    const pipeline::PreparedScenario ps = pipeline::PrepareScenario(dir, {});
    if (!ps.ground_truth) {
        std::printf("%-30s no ground truth\n", ps.scenario.name.c_str());
        return;
    }
    const PlanarTrajectory& gt = *ps.ground_truth;
    const PlanarTrajectory& est = ps.estimate;
    const std::size_t n = gt.size();
    const std::vector<double> sg = DistanceTravelled(gt), se = DistanceTravelled(est);
    const double prior = kScalePrior > 0.0
                             ? kScalePrior
                             : pipeline::CorrectorFor(ps.scenario, pipeline::PipelineConfig{})
                                   .model.scale_prior_mean;
    // The final direction, from the last moving chord.
    double final_dir = std::nan("");
    for (std::size_t i = n; i-- > 0 && std::isnan(final_dir);) final_dir = Direction(gt, sg, i);
    std::size_t k = n - 1;
    while (k > 0) {
        const double d = Direction(gt, sg, k - 1);
        if (!std::isnan(d) && std::abs(AngleDiff(d, final_dir)) > DegToRad(kStraightDeg)) break;
        --k;
    }
    const double scale_before = ScaleBefore(sg, se, k, prior);
    const double scale_on = PathRatio(sg, se, k, n - 1);
    double sum_sq = 0.0, final_err = 0.0;
    for (std::size_t i = k; i < n; ++i) {
        const double e = (sg[i] - sg[k]) - scale_before * (se[i] - se[k]);
        sum_sq += e * e;
        final_err = std::abs(e);
    }
    // Every straight: cut where the direction turned by more than kTurnDeg from the straight's
    // first one; along each, the estimate's steps scaled to the straight's true length.
    // Indoors also where the true height has changed by more than kClimbM since the cut before
    // (on stairs and in lifts the map places the walker too).
    const bool indoor = ps.scenario.mode == io::ScenarioMode::kIndoor3d;
    std::vector<std::size_t> cuts = {0};
    double ref = Direction(gt, sg, 0);
    for (std::size_t i = 1; i < n; ++i) {
        if (indoor && std::abs(gt.up_m[i] - gt.up_m[cuts.back()]) > kClimbM) {
            cuts.push_back(i);
            ref = Direction(gt, sg, i);
            continue;
        }
        const double d = Direction(gt, sg, i);
        if (std::isnan(d)) continue;
        if (std::isnan(ref)) {
            ref = d;
        } else if (std::abs(AngleDiff(d, ref)) > DegToRad(kTurnDeg)) {
            cuts.push_back(i);
            ref = d;
        }
    }
    cuts.push_back(n - 1);
    // Along each straight: the estimate's steps scaled to the straight's true length (every
    // straight; the last one, which no turn ends, by the scale of the path before it, as above),
    // or by the scale of the path before it (causal). The causal first straight at the prior
    // scale, up to its turn or the first climb.
    double every_sq = 0.0, causal_sq = 0.0;
    for (std::size_t c = 0; c + 1 < cuts.size(); ++c) {
        const std::size_t from = cuts[c], to = cuts[c + 1];
        const double before = ScaleBefore(sg, se, from, prior);
        const double scale = c + 2 == cuts.size() ? before : PathRatio(sg, se, from, to);
        for (std::size_t i = from; i <= to; ++i) {
            every_sq += std::pow((sg[i] - sg[from]) - scale * (se[i] - se[from]), 2);
            causal_sq += std::pow((sg[i] - sg[from]) - before * (se[i] - se[from]), 2);
        }
    }
    const std::size_t first_end = cuts.size() > 1 ? cuts[1] : n - 1;
    double first_sq = 0.0;
    for (std::size_t i = 0; i <= first_end; ++i) first_sq += std::pow(sg[i] - prior * se[i], 2);
    std::printf(
        "%-30s straight from pose %5zu of %5zu, %6.0f m | scale before %.3f, on it %.3f | "
        "bound: final >= %6.1f m, ATE >= %5.2f m | every straight (%zu): ATE >= %5.2f m | "
        "causal: first straight to pose %zu (%.0f m, scale %.3f, prior %.2f) ATE >= %5.2f m, every "
        "straight %5.2f m\n",
        ps.scenario.name.c_str(), k, n, sg[n - 1] - sg[k], scale_before, scale_on, final_err,
        std::sqrt(sum_sq / double(n)), cuts.size() - 1, std::sqrt(every_sq / double(n)), first_end,
        sg[first_end], PathRatio(sg, se, 0, first_end), prior, std::sqrt(first_sq / double(n)),
        std::sqrt(causal_sq / double(n)));
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
    if (const char* d = std::getenv("STRAIGHT_DEG")) kStraightDeg = std::atof(d);
    if (const char* d = std::getenv("TURN_DEG")) kTurnDeg = std::atof(d);
    if (const char* d = std::getenv("CLIMB_M")) kClimbM = std::atof(d);
    if (const char* d = std::getenv("SCALE_PRIOR")) kScalePrior = std::atof(d);
    return driftcorr::bench::ForEachScenario(argc, argv, Evaluate);
}
