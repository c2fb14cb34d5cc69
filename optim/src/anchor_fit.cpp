// The definitions of what driftcorr/optim/anchor_fit.h declares.
#include "driftcorr/optim/anchor_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "driftcorr/core/angles.h"

namespace driftcorr {
namespace {

// The scored poses: one per sample_spacing_m of path, up to lead_path_m, relative to the pivot.
struct Lead {
    std::vector<Eigen::Vector2d> p_rel;  // position minus pivot
    std::vector<double> up_m;
    double path_m = 0.0;
};

Lead LeadSamples(const PlanarTrajectory& t, const Eigen::Vector2d& pivot,
                 const AnchorFitConfig& c) {
    Lead lead;
    double next_m = 0.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        if (i > 0) lead.path_m += (t.p_en[i] - t.p_en[i - 1]).norm();
        if (lead.path_m > c.lead_path_m) break;
        if (lead.path_m < next_m) continue;
        lead.p_rel.push_back(t.p_en[i] - pivot);
        lead.up_m.push_back(t.up_m[i]);
        next_m = lead.path_m + c.sample_spacing_m;
    }
    return lead;
}

Eigen::Matrix2d Rot(double a) {
    Eigen::Matrix2d r;
    r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    return r;
}

// Scores one placement (fills rms_m and off_share).
void Score(const Lead& lead, const Eigen::Vector2d& pivot, const TraversableField& field,
           double reach_m, AnchorPlacement& pl) {
    const Eigen::Matrix2d r = Rot(pl.dyaw_rad);
    const Eigen::Vector2d shift = pivot + pl.offset_en;
    const CentreFit fit = FitToCentres(field, lead.p_rel.size(), reach_m, [&](std::size_t k) {
        const Eigen::Vector2d p = r * lead.p_rel[k] + shift;
        return Eigen::Vector3d(p.x(), p.y(), lead.up_m[k]);
    });
    pl.rms_m = fit.rms_m;
    pl.off_share = fit.off_share;
}

// Golden-section search for the minimum of rms(f(x)) over [a, b], 12 steps: the better of the
// last two points and f there.
template <class F, class Rms>
auto GoldenSection(const F& f, const Rms& rms, double a, double b) {
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = b - g * (b - a), x2 = a + g * (b - a);
    auto f1 = f(x1), f2 = f(x2);
    for (int it = 0; it < 12; ++it) {
        if (rms(f1) <= rms(f2)) {
            b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = f(x1);
        } else {
            a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = f(x2);
        }
    }
    return rms(f1) <= rms(f2) ? std::make_pair(x1, f1) : std::make_pair(x2, f2);
}

bool Distinct(const AnchorPlacement& a, const AnchorPlacement& b, const AnchorFitConfig& c) {
    return std::abs(WrapAngle(a.dyaw_rad - b.dyaw_rad)) > DegToRad(c.distinct_yaw_deg) ||
           (a.offset_en - b.offset_en).norm() > c.distinct_position_m;
}

// Pattern search around `pl`: halves the heading and position steps until they are small.
void Refine(const Lead& lead, const Eigen::Vector2d& pivot, const TraversableField& field,
            const AnchorFitConfig& c, bool search_yaw, double radius_m, AnchorPlacement& pl) {
    double dyaw = search_yaw ? DegToRad(c.yaw_step_deg) : 0.0;
    double dpos = radius_m > 0.0 ? c.position_step_m : 0.0;
    while (dyaw > DegToRad(0.1) || dpos > 0.25) {
        bool moved = false;
        const AnchorPlacement centre = pl;
        for (int k = 0; k < 6; ++k) {
            AnchorPlacement cand = centre;
            if (k < 2) {
                if (dyaw == 0.0) continue;
                cand.dyaw_rad += k == 0 ? dyaw : -dyaw;
            } else {
                if (dpos == 0.0) continue;
                cand.offset_en[(k - 2) / 2] += (k % 2 == 0) ? dpos : -dpos;
                if (cand.offset_en.norm() > radius_m) continue;
            }
            Score(lead, pivot, field, c.reach_m, cand);
            if (cand.rms_m < pl.rms_m) pl = cand, moved = true;
        }
        if (!moved) dyaw *= 0.5, dpos *= 0.5;
    }
}

}  // namespace

std::optional<ParamProblem> AnchorFitConfig::FindProblem() const {
    return CheckRows(kAnchorFitParams, *this);
}

std::string AnchorFitConfig::Validate() const {
    return ToMessage(kAnchorFitParams.section, FindProblem());
}

AnchorFitResult FitAnchor(const PlanarTrajectory& estimate, const Eigen::Vector2d& pivot_en,
                          const TraversableField& field, bool search_yaw, double radius_m,
                          const AnchorFitConfig& c) {
    const Lead lead = LeadSamples(estimate, pivot_en, c);
    AnchorFitResult res;
    res.samples = lead.p_rel.size();
    res.lead_path_m = std::min(lead.path_m, c.lead_path_m);
    Score(lead, pivot_en, field, c.reach_m, res.given);

    // Coarse grid over headings and positions.
    std::vector<AnchorPlacement> grid;
    const int n_yaw = search_yaw ? int(std::lround(360.0 / c.yaw_step_deg)) : 1;
    const int n_pos = radius_m > 0.0 ? int(std::floor(radius_m / c.position_step_m)) : 0;
    for (int iy = 0; iy < n_yaw; ++iy) {
        for (int ix = -n_pos; ix <= n_pos; ++ix) {
            for (int jy = -n_pos; jy <= n_pos; ++jy) {
                AnchorPlacement pl;
                pl.dyaw_rad = WrapAngle(DegToRad(iy * c.yaw_step_deg));
                pl.offset_en = c.position_step_m * Eigen::Vector2d(ix, jy);
                if (pl.offset_en.norm() > radius_m + 1e-9) continue;
                Score(lead, pivot_en, field, c.reach_m, pl);
                grid.push_back(pl);
            }
        }
    }
    std::sort(grid.begin(), grid.end(),
              [](const AnchorPlacement& a, const AnchorPlacement& b) { return a.rms_m < b.rms_m; });
    // Refine the best few distinct coarse placements; the best refined one wins.
    std::vector<AnchorPlacement> refined;
    for (const AnchorPlacement& pl : grid) {
        if (refined.size() >= 6) break;
        const bool seen =
            std::any_of(refined.begin(), refined.end(),
                        [&](const AnchorPlacement& r) { return !Distinct(r, pl, c); });
        if (seen) continue;
        refined.push_back(pl);
        Refine(lead, pivot_en, field, c, search_yaw, radius_m, refined.back());
    }
    std::sort(refined.begin(), refined.end(),
              [](const AnchorPlacement& a, const AnchorPlacement& b) { return a.rms_m < b.rms_m; });
    res.best = refined.empty() ? res.given : refined.front();
    if (res.given.rms_m <= res.best.rms_m) res.best = res.given;
    // The runner-up: the best refined placement that is still distinct from the best one (a
    // coarse placement next to the best may refine into its basin).
    std::vector<AnchorPlacement> tried;
    for (const AnchorPlacement& coarse : grid) {
        if (tried.size() >= 8) break;
        const auto near = [&](const AnchorPlacement& t) { return !Distinct(t, coarse, c); };
        if (!Distinct(coarse, res.best, c) || std::any_of(tried.begin(), tried.end(), near)) {
            continue;
        }
        tried.push_back(coarse);
        AnchorPlacement pl = coarse;
        Refine(lead, pivot_en, field, c, search_yaw, radius_m, pl);
        if (Distinct(pl, res.best, c) && (!res.runner_up || pl.rms_m < res.runner_up->rms_m)) {
            res.runner_up = pl;
        }
    }
    return res;
}

PlanarTrajectory ScaleAbout(const PlanarTrajectory& t, const Eigen::Vector2d& pivot_en,
                            double pivot_up_m, double scale) {
    PlanarTrajectory out = t;
    for (auto& p : out.p_en) p = pivot_en + scale * (p - pivot_en);
    for (double& u : out.up_m) u = pivot_up_m + scale * (u - pivot_up_m);
    return out;
}

ScaleFitResult FitScale(const PlanarTrajectory& estimate, const Eigen::Vector2d& pivot_en,
                        double pivot_up_m, const TraversableField& field, bool search_yaw,
                        double min_scale, double max_scale, double step_ratio,
                        std::size_t max_candidates, const AnchorFitConfig& c) {
    ScaleFitResult res;
    const auto fit = [&](double scale) {
        const PlanarTrajectory scaled = ScaleAbout(estimate, pivot_en, pivot_up_m, scale);
        return FitAnchor(scaled, pivot_en, field, search_yaw, 0.0, c).best;
    };
    const double log_step = std::log(step_ratio);
    const int n = 1 + int(std::ceil(std::log(max_scale / min_scale) / log_step - 1e-9));
    std::vector<AnchorPlacement> best(n);
    for (int k = 0; k < n; ++k) {
        res.scales.push_back(min_scale * std::exp(k * log_step));
        best[k] = fit(res.scales.back());
        res.rms_m.push_back(best[k].rms_m);
    }
    // Local minima (a plateau counts once, at its first grid point), lowest first.
    std::vector<int> minima;
    for (int k = 0; k < n; ++k) {
        const bool left = k == 0 || res.rms_m[k] < res.rms_m[k - 1];
        const bool right = k + 1 == n || res.rms_m[k] <= res.rms_m[k + 1];
        if (left && right) minima.push_back(k);
    }
    std::sort(minima.begin(), minima.end(),
              [&](int a, int b) { return res.rms_m[a] < res.rms_m[b]; });
    for (int k : minima) {
        if (res.candidates.size() >= max_candidates) break;
        const bool near = std::any_of(
            res.candidates.begin(), res.candidates.end(), [&](const ScaleCandidate& cand) {
                return std::abs(std::log(cand.scale / res.scales[k])) < 2.5 * log_step;
            });
        if (near) continue;
        // Refined in log(scale) between the neighbours.
        const auto [x, refined] =
            GoldenSection([&](double log_scale) { return fit(std::exp(log_scale)); },
                          [](const AnchorPlacement& pl) { return pl.rms_m; },
                          std::log(res.scales[k]) - log_step, std::log(res.scales[k]) + log_step);
        ScaleCandidate cand{res.scales[k], best[k]};
        if (refined.rms_m < cand.placement.rms_m) cand = {std::exp(x), refined};
        res.candidates.push_back(cand);
    }
    return res;
}

SizeFit FitSizes(const PlanarTrajectory& t, const TraversableField& field, double range,
                 const AnchorFitConfig& c) {
    AnchorFitConfig whole = c;
    whole.lead_path_m = std::numeric_limits<double>::infinity();
    const Eigen::Vector2d pivot = t.p_en.front();
    const Lead lead = LeadSamples(t, pivot, whole);
    SizeFit res;
    for (const Eigen::Vector2d& p : lead.p_rel) res.farthest_m = std::max(res.farthest_m, p.norm());
    const auto fit = [&](double g) {
        return FitToCentres(field, lead.p_rel.size(), c.reach_m,
                            [&](std::size_t k) {
                                const Eigen::Vector2d p = pivot + g * lead.p_rel[k];
                                return Eigen::Vector3d(p.x(), p.y(), lead.up_m[k]);
                            })
            .rms_m;
    };
    res.rms_m = fit(1.0);
    if (!(res.farthest_m > 2.0 * c.reach_m)) return res;  // no size the map could tell apart
    const double log_step = std::log1p(c.reach_m / res.farthest_m);
    const double log_range = std::log1p(range);
    const int half = int(std::ceil(log_range / log_step));
    std::vector<double> log_g, rms;
    for (int k = -half; k <= half; ++k) {
        log_g.push_back(k * log_step);
        rms.push_back(k == 0 ? res.rms_m : fit(std::exp(k * log_step)));
    }
    const double distinct = std::log1p(2.0 * c.reach_m / res.farthest_m);
    const int n = int(rms.size());
    for (int k = 0; k < n; ++k) {
        const bool minimum =
            (k == 0 || rms[k] < rms[k - 1]) && (k + 1 == n || rms[k] <= rms[k + 1]);
        if (!minimum || std::abs(log_g[k]) <= distinct) continue;
        if (res.other && res.other->placement.rms_m <= rms[k]) continue;
        // Refined in log(g) between the neighbours, staying distinct from g = 1.
        const auto [x, refined] =
            GoldenSection([&](double log_size) { return fit(std::exp(log_size)); },
                          [](double r) { return r; }, log_g[k] - log_step, log_g[k] + log_step);
        ScaleCandidate cand;
        cand.scale = std::exp(log_g[k]);
        cand.placement.rms_m = rms[k];
        if (refined < rms[k] && std::abs(x) > distinct) {
            cand.scale = std::exp(x), cand.placement.rms_m = refined;
        }
        res.other = cand;
    }
    return res;
}

PlanarTrajectory ApplyPlacement(const PlanarTrajectory& t, const Eigen::Vector2d& pivot_en,
                                const AnchorPlacement& pl) {
    PlanarTrajectory out = t;
    const Eigen::Matrix2d r = Rot(pl.dyaw_rad);
    for (auto& p : out.p_en) p = r * (p - pivot_en) + pivot_en + pl.offset_en;
    for (double& y : out.yaw_rad) y += pl.dyaw_rad;
    return out;
}

}  // namespace driftcorr
