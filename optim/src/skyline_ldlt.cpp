// The definitions of what driftcorr/optim/skyline_ldlt.h declares.
#include "driftcorr/optim/skyline_ldlt.h"

#include <algorithm>

#include "driftcorr/core/check.h"

namespace driftcorr {

SkylineLdlt::SkylineLdlt(std::vector<int> first_row) : first_(std::move(first_row)) {
    start_.assign(first_.size() + 1, 0);
    std::size_t tallest = 1;  // the highest column
    for (std::size_t j = 0; j < first_.size(); ++j) {
        DRIFTCORR_CHECK(first_[j] >= 0 && first_[j] <= int(j), "an envelope row below its column");
        const std::size_t height = j - std::size_t(first_[j]) + 1;
        start_[j + 1] = start_[j] + height;
        tallest = std::max(tallest, height);
    }
    values_.assign(start_.back(), 0.0);
    factor_.assign(start_.back(), 0.0);
    h_.assign(tallest, 0.0);
}

// Column by column (A = U^T D U, U unit upper): for rows i of column j in turn,
// h_i = a_ij - sum_k u_ki h_k over the rows k both columns hold, then u_ij = h_i / d_i and
// d_j = a_jj - sum_i u_ij h_i. Each row is scaled as soon as its h_i is known (h_ keeps the
// unscaled ones for the rows below), so the divisions overlap the next rows' sums; every sum
// runs in the same order as when the rows are scaled after the column's sums.
bool SkylineLdlt::Factorize() {
    std::copy(values_.begin(), values_.end(), factor_.begin());
    const int n = size();
    for (int j = 0; j < n; ++j) {
        const int fj = first_[j];
        double* col = factor_.data() + start_[j];  // col[i - fj]: row i of column j
        double* h = h_.data();                     // h[i - fj]: row i of column j before scaling
        double d = col[j - fj];
        for (int i = fj; i < j; ++i) {
            const int k0 = std::max(first_[i], fj);
            const double* ui = factor_.data() + start_[i] + (k0 - first_[i]);
            const double* hk = h + (k0 - fj);
            double dot = 0.0;
            for (int k = 0; k < i - k0; ++k) dot += ui[k] * hk[k];
            const double hi = col[i - fj] - dot;
            h[i - fj] = hi;
            const double u = hi / factor_[start_[i] + std::size_t(i - first_[i])];
            col[i - fj] = u;
            d -= u * hi;
        }
        col[j - fj] = d;
        if (!(d > 0.0)) return false;  // the rest would divide by it
    }
    return true;
}

void SkylineLdlt::Solve(std::vector<double>& b) const {
    const int n = size();
    DRIFTCORR_CHECK(int(b.size()) == n, "right-hand side of the wrong size");
    for (int j = 0; j < n; ++j) {  // U^T y = b
        const double* col = factor_.data() + start_[j];
        double s = b[j];
        for (int i = first_[j]; i < j; ++i) s -= col[i - first_[j]] * b[i];
        b[j] = s;
    }
    for (int j = 0; j < n; ++j) b[j] /= factor_[start_[j] + std::size_t(j - first_[j])];
    for (int j = n - 1; j >= 0; --j) {  // U x = z
        const double* col = factor_.data() + start_[j];
        const double x = b[j];
        for (int i = first_[j]; i < j; ++i) b[i] -= col[i - first_[j]] * x;
    }
}

}  // namespace driftcorr
