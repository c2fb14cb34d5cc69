// How well the per-pose covariance (optim/covariance.h) describes the true error of a correction.
//
// For each scenario with ground truth this runs the batch corrector as the pipeline does
// (PrepareScenario, then the incremental pass and the refinement with the scenario's corrector
// settings) and compares the true horizontal error e = corrected - ground truth (East, North) of
// every pose after the first with its covariance Sigma_xy:
//  - the share of poses inside their 95 % region, e^T Sigma^-1 e <= 5.991 (chi2, 2 dof), with the
//    raw Gauss-Newton curvature and with the a posteriori variance factor applied, and the mean
//    and largest e^T Sigma^-1 e (a covariance that is the error's has mean 2); where the CLI
//    would keep the input (KeepAgreeingInput), the same for the input and its covariance;
//  - the size, median and 90th percentile of sqrt(trace Sigma) [m];
//  - along-track / cross-track (against the corrected heading): RMS of the error, median sigma,
//    and the share inside the 1D 95 % interval (e^2 / sigma^2 <= 3.841);
//  - per term family: terms, chi2, redundancy and the family's variance factor chi2 / redundancy;
//  - the time the covariance took;
//  - the same comparison for other settings of CovarianceConfig on the same solution: the
//    solver's own model, each part of the default alone, and the default's neighbours;
//  - the map: the share of corrected poses within a centre line's interpolation band, and how far
//    the ground truth runs from the mapped centre lines (the map's true error).
// Nothing is fitted: the ground truth is only compared with.
//
// Run: build/tests/covariance_calibration [--reference-rms-m=R] [scenario dir ...]
// (default: the 7 KITTI scenarios)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "driftcorr/optim/corrector.h"
#include "driftcorr/optim/covariance.h"
#include "driftcorr/optim/incremental_corrector.h"
#include "driftcorr/pipeline/pipeline.h"
#include "scenario_correction.h"
#include "scenario_list.h"

namespace {

using namespace driftcorr;

constexpr double kChi2Two95 = 5.991;  // 95 % quantile of chi2 with 2 degrees of freedom
constexpr double kChi2One95 = 3.841;  // and with 1

double Quantile(std::vector<double> v, double q) {
    if (v.empty()) return std::nan("");
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[k];
}

struct Calibration {
    double inside = 0.0, inside_along = 0.0, inside_cross = 0.0;  // shares
    std::vector<double> size_m, sigma_along_m, sigma_cross_m;
    double rms_along_m = 0.0, rms_cross_m = 0.0;
    double mean_d2 = 0.0, max_d2 = 0.0;  // e^T Sigma^-1 e: mean 2 where Sigma is the error's
};

// The ground truth's own error in the world frame, per axis [m^2] (--reference-rms-m).
double reference_var_m2 = 0.0;

// Compares errors with the covariances times `factor` (plus the reference's own error).
Calibration Compare(const PlanarTrajectory& corrected, const PlanarTrajectory& truth,
                    const std::vector<PoseCovariance>& cov, double factor) {
    Calibration c;
    const std::size_t n = corrected.size();
    for (std::size_t i = 1; i < n; ++i) {
        const Eigen::Vector2d e = corrected.p_en[i] - truth.p_en[i];
        const Eigen::Matrix2d s =
            factor * cov[i].xy_m2 + reference_var_m2 * Eigen::Matrix2d::Identity();
        const double yaw = corrected.yaw_rad[i];
        const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw)), v(-u.y(), u.x());
        const double var_a = u.dot(s * u), var_c = v.dot(s * v);
        const double ea = u.dot(e), ec = v.dot(e);
        const double d2 = e.dot(s.ldlt().solve(e));
        c.inside += d2 <= kChi2Two95;
        c.mean_d2 += d2, c.max_d2 = std::max(c.max_d2, d2);
        c.inside_along += ea * ea <= kChi2One95 * var_a;
        c.inside_cross += ec * ec <= kChi2One95 * var_c;
        c.size_m.push_back(std::sqrt(s.trace()));
        c.sigma_along_m.push_back(std::sqrt(var_a));
        c.sigma_cross_m.push_back(std::sqrt(var_c));
        c.rms_along_m += ea * ea;
        c.rms_cross_m += ec * ec;
    }
    const double m = double(n - 1);
    c.inside /= m, c.inside_along /= m, c.inside_cross /= m, c.mean_d2 /= m;
    c.rms_along_m = std::sqrt(c.rms_along_m / m), c.rms_cross_m = std::sqrt(c.rms_cross_m / m);
    return c;
}

void Print(const char* label, const Calibration& c) {
    std::printf(
        "  %-12s inside 95%%: %5.1f %% (along %5.1f %%, cross %5.1f %%) | sqrt(tr) median "
        "%7.2f m, p90 %7.2f m | sigma along median %7.2f m, cross %6.2f m | e'S^-1e mean "
        "%.2f, max %.2f\n",
        label, 100.0 * c.inside, 100.0 * c.inside_along, 100.0 * c.inside_cross,
        Quantile(c.size_m, 0.5), Quantile(c.size_m, 0.9), Quantile(c.sigma_along_m, 0.5),
        Quantile(c.sigma_cross_m, 0.5), c.mean_d2, c.max_d2);
}

// Share of corrected poses within a centre line's interpolation band (|grad d| < 0.9), and the
// ground truth's signed distance from the nearest centre line (positive on the left of travel).
void PrintMapDiagnostics(const TrajectoryState& state, const PlanarTrajectory& corrected,
                         const PlanarTrajectory& truth, const TraversableField& field) {
    std::size_t band = 0;
    std::vector<double> offset_m, abs_offset_m;
    for (std::size_t i = 1; i < truth.size(); ++i) {
        const Eigen::Vector3d& p = state.poses[i].p;
        if (const auto q = field.Query(p); q && q->centre.gradient.norm() < 0.9) ++band;
        const auto qt = field.Query(Eigen::Vector3d(truth.p_en[i].x(), truth.p_en[i].y(), p.z()));
        if (!qt) continue;
        const double yaw = corrected.yaw_rad[i];
        const Eigen::Vector2d left(-std::sin(yaw), std::cos(yaw));
        const double side = qt->centre.gradient.head<2>().dot(left) >= 0.0 ? 1.0 : -1.0;
        offset_m.push_back(side * qt->centre.value);
        abs_offset_m.push_back(qt->centre.value);
    }
    double mean = 0.0, sq = 0.0;
    for (double o : offset_m) mean += o, sq += o * o;
    const double m = double(std::max<std::size_t>(offset_m.size(), 1));
    std::printf(
        "  band %.1f %% of poses | ground truth off the centre line: mean %.2f m, RMS "
        "%.2f m, |.| median %.2f m, p90 %.2f m\n",
        100.0 * double(band) / double(truth.size() - 1), mean / m, std::sqrt(sq / m),
        Quantile(abs_offset_m, 0.5), Quantile(abs_offset_m, 0.9));
}

void PrintFamilies(const CovarianceResult& cov) {
    for (int f = 0; f < kTermFamilies; ++f) {
        const FamilyStatistics& s = cov.families[f];
        if (s.terms == 0) continue;
        std::printf("    %-21s %6zu terms, chi2 %10.4g, redundancy %8.1f, factor %8.3g\n",
                    ToString(static_cast<TermFamily>(f)), s.terms, s.chi2, s.redundancy,
                    s.VarianceFactor());
    }
    std::printf("    variance components:");
    for (int f = 0; f < kTermFamilies; ++f) {
        if (cov.family_factors[f] != 1.0) {
            std::printf(" %s %.3g", ToString(static_cast<TermFamily>(f)), cov.family_factors[f]);
        }
    }
    std::printf("\n");
}

// The same solution under other settings of the covariance (no variance factor).
void PrintVariants(const TrajectoryState& state, const TraversableField& field,
                   const CorrectorConfig& cfg, const PlanarTrajectory& corrected,
                   const PlanarTrajectory& truth) {
    struct Variant {
        std::string label;
        double share, correlation_m;
        bool components;
        double step_sd, step_correlation_m;
        bool across = true;  // CovarianceConfig::map_across_travel
    };
    const CovarianceConfig& d = cfg.covariance;
    const double share = d.map_offset_share, corr_m = d.map_offset_correlation_m;
    const bool comp = d.family_variance_components;
    const double step_sd = d.step_error_sd, step_m = d.step_error_correlation_m;
    std::vector<Variant> variants{{"solver model", 0.0, corr_m, false, 0.0, step_m, false},
                                  {"map along grad d", share, corr_m, comp, step_sd, step_m, false},
                                  {"offset only", share, corr_m, false, 0.0, step_m},
                                  {"components", 0.0, corr_m, true, 0.0, step_m},
                                  {"share 0.25", 0.25, corr_m, comp, step_sd, step_m},
                                  {"share 0.75", 0.75, corr_m, comp, step_sd, step_m},
                                  {"corr 0.5x", share, 0.5 * corr_m, comp, step_sd, step_m},
                                  {"corr 2x", share, 2.0 * corr_m, comp, step_sd, step_m}};
    // The step length's slowly varying error (CovarianceConfig::step_error_sd): off, and a grid.
    variants.push_back({"no step error", share, corr_m, comp, 0.0, step_m});
    for (double sd : {0.05, 0.1, 0.15}) {
        for (double c_m : {5.0, 10.0, 20.0}) {
            char label[32];
            std::snprintf(label, sizeof label, "step %.2f/%.0fm", sd, c_m);
            variants.push_back({label, share, corr_m, comp, sd, c_m});
        }
    }
    for (const Variant& v : variants) {
        CovarianceConfig c = d;
        c.apply_variance_factor = false;
        c.map_offset_share = v.share;
        c.map_offset_correlation_m = v.correlation_m;
        c.family_variance_components = v.components;
        c.step_error_sd = v.step_sd;
        c.step_error_correlation_m = v.step_correlation_m;
        c.map_across_travel = v.across && d.map_across_travel;
        const CovarianceResult r = ComputeCovariance(state, &field, cfg.model, c);
        Print(v.label.c_str(), Compare(corrected, truth, r.poses, 1.0));
    }
}

void Evaluate(const std::string& dir) {
    const std::unique_ptr<bench::ScenarioCorrection> c = bench::CorrectWithGroundTruth(dir);
    if (!c) return;
    const pipeline::PreparedScenario& ps = c->scenario;
    const CorrectorConfig& cfg = c->config;
    const CorrectionResult& result = c->result;
    const IncrementalCorrector& inc = *c->corrector;
    const CovarianceResult& cov = result.covariance;
    if (!Usable(result.status) || cov.status != CovarianceStatus::kOk) {
        std::printf("%s: correction %s, covariance %s: %s\n", ps.scenario.name.c_str(),
                    ToString(result.status).c_str(), ToString(cov.status), cov.message.c_str());
        return;
    }
    const PlanarTrajectory& truth = *ps.ground_truth;
    const PlanarTrajectory& corrected = result.corrected;
    const std::size_t n = truth.size();
    double sum_sq = 0.0;
    Eigen::Vector2d mean_error = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        sum_sq += (corrected.p_en[i] - truth.p_en[i]).squaredNorm();
        mean_error += (corrected.p_en[i] - truth.p_en[i]) / double(n);
    }
    std::printf(
        "%s: %zu poses, ATE %.2f m, correction %.2f s, covariance %.1f ms (%zu unknowns, "
        "nnz(L) %zu), variance factor %.3g (%s)\n",
        ps.scenario.name.c_str(), n, std::sqrt(sum_sq / double(n)),
        result.incremental_s + result.refine_s, 1e3 * result.covariance_s, cov.unknowns,
        cov.factor_nonzeros, cov.variance_factor,
        cov.variance_factor_applied ? "applied" : "not applied");
    PrintMapDiagnostics(inc.state(), corrected, truth, ps.field);
    // The covariance without and with the variance factor, whatever the configuration applied.
    const double applied = cov.variance_factor_applied ? cov.variance_factor : 1.0;
    const Calibration raw = Compare(corrected, truth, cov.poses, 1.0 / applied);
    std::printf("  error RMS along %.2f m, cross %.2f m; mean error East %.2f m, North %.2f m\n",
                raw.rms_along_m, raw.rms_cross_m, mean_error.x(), mean_error.y());
    Print("default", raw);
    Print("with factor", Compare(corrected, truth, cov.poses, cov.variance_factor / applied));
    // Where the input agrees with the map the CLI writes the input, with its covariance.
    CorrectionResult written = result;
    KeepAgreeingInput(ps.estimate, &ps.field, cfg, written);
    if (written.input_kept && written.covariance.status == CovarianceStatus::kOk) {
        Print("input kept", Compare(written.corrected, truth, written.covariance.poses, 1.0));
    }
    PrintFamilies(cov);
    PrintVariants(inc.state(), ps.field, cfg, corrected, truth);
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
    // --reference-rms-m=R: the ground truth's own horizontal error (RMS, 2D) is added to every
    // covariance as (R^2 / 2) I, e.g. the rigid fit of KITTI's ground truth to the RTK track.
    const std::string flag = "--reference-rms-m=";
    if (argc > 1 && std::string(argv[1]).rfind(flag, 0) == 0) {
        const double rms_m = std::atof(argv[1] + flag.size());
        reference_var_m2 = 0.5 * rms_m * rms_m;
        std::printf("reference error %.2f m RMS added to the covariances\n", rms_m);
        argv[1] = argv[0];
        return driftcorr::bench::ForEachScenario(argc - 1, argv + 1, Evaluate);
    }
    return driftcorr::bench::ForEachScenario(argc, argv, Evaluate);
}
