// The step-length scale walk's level (ModelConfig::scale_rw_sigma) read from each drive: what two
// estimators choose, and how the correction fares at each level, against the ground truth.
//
// For each scenario with ground truth: the batch correction as the pipeline runs it
// (PrepareScenario, CorrectFromStarts with the scenario's corrector settings); then its final
// solve repeated from that solution at each walk level of a grid (the windows stay those of the
// default level), and for each:
//  - the NLL at the solution, half the log-determinant of the solver model's Gauss-Newton
//    curvature there (no map offset process, no variance components), k ln sigma (the k walk
//    terms' normalisation) and their sum: the negative log of the Laplace approximation of the
//    marginal likelihood of the level, up to a constant; the lowest sum is the level the data
//    choose;
//  - the ATE of that solution;
// and the level that iterated variance-component estimation reaches (Forstner, the walk family's
// chi2 over its redundancy at each solution, as the covariance's model reads it; at most five
// rounds, until the factor is below 1.1), with its ATE.
// Nothing is fitted: the ground truth is only compared with.
//
// Run: build/tests/walk_level [scenario dir ...] (default: the 7 KITTI scenarios)
#include <Eigen/SparseCholesky>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "driftcorr/core/metrics.h"
#include "driftcorr/optim/corrector.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/incremental_corrector.h"
#include "driftcorr/pipeline/pipeline.h"
#include "scenario_correction.h"
#include "scenario_list.h"

namespace {

using namespace driftcorr;

constexpr double kLevels[] = {0.005, 0.01, 0.014, 0.02, 0.028, 0.04, 0.057, 0.08};
constexpr int kVceRounds = 5;
constexpr double kVceStop = 1.1;

struct Solved {
    bool usable = false;
    double nll = 0.0;
    double ate_m = 0.0;
    TrajectoryState state;
};

// The final solve repeated from `from` with the walk at `sigma`.
Solved Refine(const TrajectoryState& from, const TraversableField& field, CorrectorConfig cfg,
              double sigma, const PlanarTrajectory& estimate, const PlanarTrajectory& truth) {
    cfg.model.scale_rw_sigma = sigma;
    cfg.compute_covariance = false;
    IncrementalCorrector inc(from, &field, cfg, IncrementalCorrector::Corrected{});
    const CorrectionResult r = inc.Finish(estimate.t_s);
    Solved s;
    s.usable = Usable(r.status);
    if (!s.usable) return s;
    s.nll = r.nll;
    s.ate_m = ComputeMetrics(r.corrected, truth).ate_m;
    s.state = inc.state();
    return s;
}

// Half the log-determinant of the solver model's curvature at `state`; NaN when it is not
// positive definite.
double HalfLogDet(const TrajectoryState& state, const TraversableField& field,
                  const ModelConfig& model) {
    CovarianceConfig plain;
    plain.map_offset_share = 0.0;
    plain.family_variance_components = false;
    plain.step_error_sd = 0.0;
    plain.apply_variance_factor = false;
    plain.block_poses = state.poses.size() + 1;
    CovarianceSystem system;
    const CovarianceResult c = ComputeCovariance(state, &field, model, plain, &system);
    if (c.status != CovarianceStatus::kOk) return std::nan("");
    const Eigen::SparseMatrix<double> h = system.information;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(h);
    if (ldlt.info() != Eigen::Success) return std::nan("");
    return 0.5 * ldlt.vectorD().array().log().sum();
}

// The walk family's variance component at `state` under `model` (1: as modelled or fewer than
// one redundant observation).
double WalkFactor(const TrajectoryState& state, const TraversableField& field,
                  const ModelConfig& model) {
    const CovarianceResult c = ComputeCovariance(state, &field, model, CovarianceConfig{});
    if (c.status != CovarianceStatus::kOk) return 1.0;
    return c.family_factors[static_cast<int>(TermFamily::kScaleWalk)];
}

void Evaluate(const std::string& dir) {
    const std::unique_ptr<bench::ScenarioCorrection> c = bench::CorrectWithGroundTruth(dir);
    if (!c) return;
    const pipeline::PreparedScenario& ps = c->scenario;
    const CorrectorConfig& cfg = c->config;
    const CorrectionResult& result = c->result;
    const IncrementalCorrector& inc = *c->corrector;
    if (!Usable(result.status) || inc.state().scales.size() < 2) {
        std::printf("%s: correction %s, %zu scale segment(s): skipped\n", ps.scenario.name.c_str(),
                    ToString(result.status).c_str(), inc.state().scales.size());
        return;
    }
    const PlanarTrajectory& truth = *ps.ground_truth;
    const double k = double(inc.state().scales.size() - 1);
    std::printf("%s: default walk %.3f, ATE %.2f m, %0.f walk terms\n", ps.scenario.name.c_str(),
                cfg.model.scale_rw_sigma, ComputeMetrics(result.corrected, truth).ate_m, k);
    std::printf("  %8s %10s %12s %9s %12s %8s\n", "walk", "NLL", "ln det / 2", "k ln s",
                "-ln evidence", "ATE [m]");
    double best = std::nan(""), best_level = 0.0, best_ate = 0.0;
    for (const double level : kLevels) {
        const Solved s = Refine(inc.state(), ps.field, cfg, level, ps.estimate, truth);
        if (!s.usable) {
            std::printf("  %8.3f   not usable\n", level);
            continue;
        }
        ModelConfig model = cfg.model;
        model.scale_rw_sigma = level;
        const double half_log_det = HalfLogDet(s.state, ps.field, model);
        const double evidence = s.nll + half_log_det + k * std::log(level);
        std::printf("  %8.3f %10.2f %12.2f %9.2f %12.2f %8.2f\n", level, s.nll, half_log_det,
                    k * std::log(level), evidence, s.ate_m);
        if (std::isfinite(evidence) && !(evidence >= best)) {
            best = evidence, best_level = level, best_ate = s.ate_m;
        }
    }
    std::printf("  the evidence chooses %.3f (ATE %.2f m)\n", best_level, best_ate);
    double level = cfg.model.scale_rw_sigma;
    TrajectoryState state = inc.state();
    double ate = ComputeMetrics(result.corrected, truth).ate_m;
    for (int round = 0; round < kVceRounds; ++round) {
        ModelConfig model = cfg.model;
        model.scale_rw_sigma = level;
        const double factor = WalkFactor(state, ps.field, model);
        if (factor < kVceStop) break;
        level *= std::sqrt(factor);
        const Solved s = Refine(state, ps.field, cfg, level, ps.estimate, truth);
        if (!s.usable) break;
        state = s.state, ate = s.ate_m;
    }
    std::printf("  variance components iterate to %.3f (ATE %.2f m)\n", level, ate);
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) { return driftcorr::bench::ForEachScenario(argc, argv, Evaluate); }
