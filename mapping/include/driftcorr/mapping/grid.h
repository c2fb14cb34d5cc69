#pragma once
// Regular sample grids and the exact Euclidean distance transform.
#include <Eigen/Core>
#include <cstdint>
#include <future>
#include <limits>
#include <vector>

namespace driftcorr {

/// A regular grid of samples: sample (i, j, k) sits at origin_m + (resolution_m * i,
/// resolution_m * j, dz() * k). A planar grid has nz == 1 (the road case); its samples ignore the
/// height coordinate. The vertical spacing may differ from the horizontal one (indoor fields:
/// fine in plan, coarse in height); resolution_z_m == 0 means isotropic.
struct GridSpec {
    Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
    double resolution_m = 0.5;
    int nx = 0, ny = 0, nz = 1;
    double resolution_z_m = 0.0;  ///< vertical spacing [m]; 0: the same as resolution_m

    /// The vertical spacing [m].
    double dz() const { return resolution_z_m > 0.0 ? resolution_z_m : resolution_m; }

    std::size_t size() const {
        return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) *
               static_cast<std::size_t>(nz);
    }
    std::size_t Index(int i, int j, int k = 0) const {
        return (static_cast<std::size_t>(k) * ny + j) * static_cast<std::size_t>(nx) + i;
    }
    Eigen::Vector3d Position(int i, int j, int k = 0) const {
        return origin_m + Eigen::Vector3d(resolution_m * i, resolution_m * j, dz() * k);
    }
    bool planar() const { return nz == 1; }
};

/// Distance from p to the segment ab [m].
double PointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                            const Eigen::Vector2d& b);

/// The horizontal cells [i0, i1] x [j0, j1] of `s` (clamped to the grid; empty when i0 > i1 or
/// j0 > j1) whose samples can lie within `reach` of the segment ab.
struct CellBox {
    int i0, j0, i1, j1;
};
CellBox SegmentCells(const GridSpec& s, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                     double reach);

/// The x interval [lo, hi] of the points of the line at height y that lie within `reach` of the
/// segment ab (the capsule's chord), or false when the line misses the capsule. Exact up to
/// rounding: widen it by a cell before testing samples against the distance.
bool SegmentRowSpan(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double reach, double y,
                    double& lo, double& hi);

/// The cells [i0, i1] of row j, within `box`, whose samples can lie within `reach` of ab: the
/// row's SegmentRowSpan widened by a cell. The samples sit at whole.Position(i + di, j + dj) (a
/// sub-grid of `whole` from sample (di, dj) on; di = dj = 0 for the grid itself). False when the
/// row has none.
bool SegmentRowCells(const GridSpec& whole, int di, int dj, int j, const Eigen::Vector2d& a,
                     const Eigen::Vector2d& b, double reach, const CellBox& box, int& i0, int& i1);

/// Whether a `threads` setting of the map stage (0: one per core the process may run on, by its
/// CPU affinity: taskset, a container's CPU set) allows a second thread.
bool SecondThreadAllowed(int threads);
/// The std::async policy of work that may run on that second thread: async when allowed,
/// deferred (run by the thread that waits for it) otherwise.
std::launch SecondThreadLaunch(int threads);

/// Fills `v` with n copies of `value` in memory the kernel may back with huge pages (Linux
/// transparent huge pages in "madvise" mode; elsewhere an ordinary assign): a grid of millions of
/// samples then costs hundreds of page faults instead of tens of thousands.
template <typename T>
void AssignLarge(std::vector<T>& v, std::size_t n, T value);

/// Exact Euclidean distance transform (Felzenszwalb & Huttenlocher 2012, separable lower
/// envelope of parabolas, linear in the number of samples). Returns, for every sample, the
/// distance in metres to the nearest sample whose `feature` is non-zero, or +infinity when the
/// grid has no feature. With `cap_m`, a distance beyond cap_m may come out larger, up to
/// +infinity (the features farther than cap_m along y are left out of the second pass: a field
/// truncated at cap_m needs no more); the distances up to cap_m are the same numbers.
/// Precondition: feature.size() == spec.size().
std::vector<float> EuclideanDistanceTransform(
    const GridSpec& spec, const std::vector<std::uint8_t>& feature,
    double cap_m = std::numeric_limits<double>::infinity());

/// EuclideanDistanceTransform(spec, feature, cap_m) of a 2-D grid (spec.nz == 1) laid under
/// exact distances known near the features, without a grid of its own: every sample of `exact`
/// becomes min(ceiling_m, exact) where it is finite, min(ceiling_m, transform + offset_m) where it
/// is +infinity; the same floats as the transform followed by that merge. The transform runs a
/// strip of rows at a time (its columns' pass looks beyond the strip as far as the cap), so it
/// needs memory for a strip, not for the grid. Preconditions: spec.nz == 1, cap_m finite,
/// feature.size() == exact.size() == spec.size().
void MergeCappedDistanceTransform(const GridSpec& spec, const std::vector<std::uint8_t>& feature,
                                  double cap_m, float offset_m, float ceiling_m,
                                  std::vector<float>& exact);

/// Signed distance to a set: negative inside (distance to the nearest outside sample, minus
/// half a cell), positive outside (distance to the nearest inside sample, minus half a cell), so
/// that the zero level lies between the last inside and the first outside sample.
std::vector<float> SignedDistanceTransform(const GridSpec& spec,
                                           const std::vector<std::uint8_t>& inside);

}  // namespace driftcorr
