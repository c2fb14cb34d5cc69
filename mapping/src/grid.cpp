// The definitions of what driftcorr/mapping/grid.h declares.
#include "driftcorr/mapping/grid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <thread>

#ifdef __linux__
#include <sched.h>
#include <sys/mman.h>
#endif

#include "driftcorr/core/check.h"

namespace driftcorr {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// One 1-D pass on squared distances in cell units: f (input, kInf where no site) -> d.
// Scratch buffers v (site indices) and z (envelope boundaries) have n and n + 1 entries.
// `w` weighs the squared step along this axis (anisotropic grids: (dz / resolution)^2).
void Edt1d(const float* f, int n, float* d, int* v, float* z, float w = 1.0f) {
    int k = -1;
    for (int q = 0; q < n; ++q) {
        if (f[q] == kInf) continue;
        float s = 0.0f;
        while (k >= 0) {
            const int p = v[k];
            s = ((f[q] + w * float(q) * q) - (f[p] + w * float(p) * p)) / (2.0f * w * (q - p));
            if (s > z[k]) break;
            --k;
        }
        ++k;
        v[k] = q;
        z[k] = (k == 0) ? -kInf : s;
        z[k + 1] = kInf;
    }
    if (k < 0) {
        for (int q = 0; q < n; ++q) d[q] = kInf;
        return;
    }
    int j = 0;
    for (int q = 0; q < n; ++q) {
        while (z[j + 1] < q) ++j;
        const float dq = float(q - v[j]);
        d[q] = w * dq * dq + f[v[j]];
    }
}

// The first pass, along y, on the feature mask itself: in a column the distance (in cells) to the
// nearest feature is that to the last one before or the next one after, a sweep down the rows and
// one back up, each a whole row at a time (the lower envelope is only needed once distances
// differ from 0 and infinity). The sweep down over `rows` rows; `above`: its values in the row
// before the first (none: no row before it).
void SweepDown(const std::uint8_t* f, float* d, std::size_t nx, int rows, const float* above) {
    for (int j = 0; j < rows; ++j) {
        const std::uint8_t* fr = f + std::size_t(j) * nx;
        float* row = d + std::size_t(j) * nx;
        const float* before = j > 0 ? row - nx : above;
        if (before == nullptr) {
            for (std::size_t i = 0; i < nx; ++i) row[i] = fr[i] ? 0.0f : kInf;
        } else {
            for (std::size_t i = 0; i < nx; ++i) row[i] = fr[i] ? 0.0f : before[i] + 1.0f;
        }
    }
}

// The sweep back up over `rows` rows, from the last.
void SweepUp(float* d, std::size_t nx, int rows) {
    for (int j = rows - 2; j >= 0; --j) {
        const float* below = d + std::size_t(j + 1) * nx;
        float* row = d + std::size_t(j) * nx;
        for (std::size_t i = 0; i < nx; ++i) row[i] = std::min(row[i], below[i] + 1.0f);
    }
}

// Column distances to squared ones, those beyond cap2 infinity.
void SquareCapped(float* d, std::size_t n, float cap2) {
    for (std::size_t i = 0; i < n; ++i) {
        const float sq = d[i] * d[i];
        d[i] = sq > cap2 ? kInf : sq;
    }
}

// A squared distance in cells to metres.
float ToMetres(float squared_cells, float res) {
    return squared_cells == kInf ? kInf : std::sqrt(squared_cells) * res;
}

// The first pass, along y, of every slab: the two sweeps, then squared, beyond cap2 infinity.
void FeatureColumns(const std::vector<std::uint8_t>& feature, const GridSpec& s,
                    std::vector<float>& g, float cap2) {
    const std::size_t nx = std::size_t(s.nx), slab = nx * std::size_t(s.ny);
    for (std::size_t base = 0; base < g.size(); base += slab) {
        SweepDown(feature.data() + base, g.data() + base, nx, s.ny, nullptr);
        SweepUp(g.data() + base, nx, s.ny);
        SquareCapped(g.data() + base, slab, cap2);
    }
}

// Applies Edt1d along x, in place: the rows are contiguous.
void EdtRows(std::vector<float>& g, const GridSpec& s) {
    const int n = s.nx;
    std::vector<float> d(n), z(n + 1);
    std::vector<int> v(n);
    for (std::size_t base = 0; base < g.size(); base += std::size_t(n)) {
        float* row = g.data() + base;
        Edt1d(row, n, d.data(), v.data(), z.data());
        std::copy(d.begin(), d.end(), row);
    }
}

// Applies Edt1d along z, in place. The lines along z are strided in memory; kBlock neighbouring
// lines (neighbours along x) are gathered and scattered together, a row of kBlock contiguous
// samples at a time.
void EdtLayers(std::vector<float>& g, const GridSpec& s) {
    constexpr int kBlock = 16;
    const int n = s.nz;
    const std::size_t stride = std::size_t(s.nx) * s.ny;
    std::vector<float> f(std::size_t(n) * kBlock), d(n), z(n + 1);
    std::vector<int> v(n);
    const float ratio = float(s.dz() / s.resolution_m);
    const float w = ratio * ratio;
    for (int b = 0; b < s.ny; ++b) {
        for (int a0 = 0; a0 < s.nx; a0 += kBlock) {
            const int width = std::min(kBlock, s.nx - a0);
            const std::size_t base = s.Index(a0, b, 0);
            for (int q = 0; q < n; ++q) {
                const float* row = &g[base + q * stride];
                for (int a = 0; a < width; ++a) f[std::size_t(a) * n + q] = row[a];
            }
            for (int a = 0; a < width; ++a) {
                float* line = &f[std::size_t(a) * n];
                Edt1d(line, n, d.data(), v.data(), z.data(), w);
                std::copy(d.begin(), d.end(), line);
            }
            for (int q = 0; q < n; ++q) {
                float* row = &g[base + q * stride];
                for (int a = 0; a < width; ++a) row[a] = f[std::size_t(a) * n + q];
            }
        }
    }
}

}  // namespace

bool SecondThreadAllowed(int threads) {
    if (threads != 0) return threads >= 2;
#ifdef __linux__
    cpu_set_t allowed;
    if (sched_getaffinity(0, sizeof(allowed), &allowed) == 0) return CPU_COUNT(&allowed) >= 2;
#endif
    return std::thread::hardware_concurrency() >= 2;
}

std::launch SecondThreadLaunch(int threads) {
    return SecondThreadAllowed(threads) ? std::launch::async : std::launch::deferred;
}

template <typename T>
void AssignLarge(std::vector<T>& v, std::size_t n, T value) {
#ifdef __linux__
    constexpr std::size_t kHuge = std::size_t(2) << 20;
    if (n * sizeof(T) >= 4 * kHuge && v.capacity() < n) {
        std::vector<T>().swap(v);
        v.reserve(n);  // fresh pages, not yet touched
        const auto begin = reinterpret_cast<std::uintptr_t>(v.data());
        const std::uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1);
        const std::uintptr_t last = (begin + n * sizeof(T)) & ~(kHuge - 1);
        if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
    }
#endif
    v.assign(n, value);
}

template void AssignLarge<float>(std::vector<float>&, std::size_t, float);
template void AssignLarge<std::uint8_t>(std::vector<std::uint8_t>&, std::size_t, std::uint8_t);

std::vector<float> EuclideanDistanceTransform(const GridSpec& spec,
                                              const std::vector<std::uint8_t>& feature,
                                              double cap_m) {
    DRIFTCORR_CHECK(feature.size() == spec.size(), "feature mask does not match the grid");
    std::vector<float> g;
    AssignLarge(g, spec.size(), 0.0f);
    // A site farther than the cap along y cannot make a distance within it (squared cells; a
    // cell's margin against rounding).
    const double cap_cells = cap_m / spec.resolution_m + 1.0;
    FeatureColumns(feature, spec, g, std::isfinite(cap_m) ? float(cap_cells * cap_cells) : kInf);
    EdtRows(g, spec);
    if (spec.nz > 1) EdtLayers(g, spec);
    const float res = static_cast<float>(spec.resolution_m);
    for (float& x : g) x = ToMetres(x, res);
    return g;
}

void MergeCappedDistanceTransform(const GridSpec& spec, const std::vector<std::uint8_t>& feature,
                                  double cap_m, float offset_m, float ceiling_m,
                                  std::vector<float>& exact) {
    DRIFTCORR_CHECK(spec.nz == 1 && std::isfinite(cap_m), "a 2-D grid and a finite cap");
    DRIFTCORR_CHECK(feature.size() == spec.size() && exact.size() == spec.size(),
                    "feature mask and exact distances must match the grid");
    constexpr int kStrip = 256;  // rows a strip
    const std::size_t nx = std::size_t(spec.nx);
    const int ny = spec.ny;
    // As EuclideanDistanceTransform: squared column distances beyond cap2 are infinity. A column
    // distance the strip's pass gets wrong (a feature more than `ahead` rows below the strip
    // left out) is more than ahead >= cap_cells + 1 cells, so it is infinity either way.
    const double cap_cells = cap_m / spec.resolution_m + 1.0;
    const float cap2 = float(cap_cells * cap_cells);
    const int ahead = int(std::ceil(cap_cells)) + 1;
    const float res = static_cast<float>(spec.resolution_m);
    std::vector<float> col(std::size_t(std::min(ny, kStrip + ahead)) * nx), carried(nx, kInf);
    std::vector<float> d(nx), z(nx + 1);
    std::vector<int> v(nx);
    for (int j0 = 0; j0 < ny; j0 += kStrip) {
        const int j1 = std::min(ny, j0 + kStrip), end = std::min(ny, j1 + ahead);
        // Down the rows from the row above the strip (carried), then back up from its end.
        SweepDown(feature.data() + std::size_t(j0) * nx, col.data(), nx, end - j0,
                  j0 > 0 ? carried.data() : nullptr);
        std::copy_n(col.data() + std::size_t(j1 - 1 - j0) * nx, nx, carried.data());
        SweepUp(col.data(), nx, end - j0);
        // Along each row, then the merge (a row of `exact` is read only for itself).
        for (int j = j0; j < j1; ++j) {
            float* row = col.data() + std::size_t(j - j0) * nx;
            SquareCapped(row, nx, cap2);
            Edt1d(row, int(nx), d.data(), v.data(), z.data());
            float* out = exact.data() + std::size_t(j) * nx;
            for (std::size_t i = 0; i < nx; ++i) {
                out[i] =
                    std::min(ceiling_m, out[i] < kInf ? out[i] : ToMetres(d[i], res) + offset_m);
            }
        }
    }
}

std::vector<float> SignedDistanceTransform(const GridSpec& spec,
                                           const std::vector<std::uint8_t>& inside) {
    std::vector<std::uint8_t> outside(inside.size());
    for (std::size_t i = 0; i < inside.size(); ++i) outside[i] = inside[i] ? 0 : 1;
    std::vector<float> to_inside = EuclideanDistanceTransform(spec, inside);
    const std::vector<float> to_outside = EuclideanDistanceTransform(spec, outside);
    const float half = 0.5f * static_cast<float>(spec.resolution_m);
    for (std::size_t i = 0; i < to_inside.size(); ++i) {
        to_inside[i] = inside[i] ? -(to_outside[i] - half) : (to_inside[i] - half);
    }
    return to_inside;
}

double PointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                            const Eigen::Vector2d& b) {
    const Eigen::Vector2d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + t * ab - p).norm();
}

namespace {

// Widens [lo, hi] by the chord of the disc of radius r around c on the line at height y.
void AddDiscChord(const Eigen::Vector2d& c, double r, double y, double& lo, double& hi) {
    const double dy = y - c.y(), h2 = r * r - dy * dy;
    if (h2 < 0.0) return;
    const double h = std::sqrt(h2);
    lo = std::min(lo, c.x() - h);
    hi = std::max(hi, c.x() + h);
}

// Intersects [lo, hi] with {x : lo_v <= k * x + m <= hi_v}.
void ClipLinear(double k, double m, double lo_v, double hi_v, double& lo, double& hi) {
    if (k == 0.0) {
        if (m < lo_v || m > hi_v) {
            lo = 1.0;
            hi = 0.0;
        }
        return;
    }
    double x0 = (lo_v - m) / k, x1 = (hi_v - m) / k;
    if (x0 > x1) std::swap(x0, x1);
    lo = std::max(lo, x0);
    hi = std::min(hi, x1);
}

}  // namespace

bool SegmentRowSpan(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double reach, double y,
                    double& lo, double& hi) {
    // The capsule is the union of the discs at both ends and the band between them; its chord
    // is the hull of theirs (the capsule is convex and each piece's chord lies in it).
    lo = std::numeric_limits<double>::infinity();
    hi = -lo;
    AddDiscChord(a, reach, y, lo, hi);
    AddDiscChord(b, reach, y, lo, hi);
    const Eigen::Vector2d ab = b - a;
    const double len = ab.norm();
    if (len > 0.0) {
        const Eigen::Vector2d u = ab / len;
        // Band: 0 <= u . (p - a) <= len and |n . (p - a)| <= reach, n = (-u.y, u.x), p = (x, y).
        double blo = -std::numeric_limits<double>::infinity(), bhi = -blo;
        const double dy = y - a.y();
        ClipLinear(u.x(), u.y() * dy - u.x() * a.x(), 0.0, len, blo, bhi);
        ClipLinear(-u.y(), u.x() * dy + u.y() * a.x(), -reach, reach, blo, bhi);
        if (blo <= bhi) {
            lo = std::min(lo, blo);
            hi = std::max(hi, bhi);
        }
    }
    return lo <= hi;
}

bool SegmentRowCells(const GridSpec& whole, int di, int dj, int j, const Eigen::Vector2d& a,
                     const Eigen::Vector2d& b, double reach, const CellBox& box, int& i0, int& i1) {
    double lo = 0.0, hi = 0.0;
    if (!SegmentRowSpan(a, b, reach, whole.Position(0, j + dj).y(), lo, hi)) return false;
    const double ox = whole.origin_m.x(), res = whole.resolution_m;
    i0 = std::max(box.i0, int(std::floor((lo - ox) / res)) - di - 1);
    i1 = std::min(box.i1, int(std::ceil((hi - ox) / res)) - di + 1);
    return i0 <= i1;
}

CellBox SegmentCells(const GridSpec& s, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                     double reach) {
    const double res = s.resolution_m;
    const Eigen::Vector2d lo = a.cwiseMin(b).array() - reach, hi = a.cwiseMax(b).array() + reach;
    return {std::max(0, int(std::floor((lo.x() - s.origin_m.x()) / res))),
            std::max(0, int(std::floor((lo.y() - s.origin_m.y()) / res))),
            std::min(s.nx - 1, int(std::ceil((hi.x() - s.origin_m.x()) / res))),
            std::min(s.ny - 1, int(std::ceil((hi.y() - s.origin_m.y()) / res)))};
}

}  // namespace driftcorr
