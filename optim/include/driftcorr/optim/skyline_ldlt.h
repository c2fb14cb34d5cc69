#pragma once
// LDL^T of a symmetric matrix held by its envelope ("skyline"): column j keeps its rows from the
// first one that is not zero down to the diagonal, and the factor fills in only within that
// envelope. A window's Hessian in the Newton solver's order is such a matrix: a band of a few
// poses, and each scale or bias variable's column reaching back to the first pose it touches.
// Stored densely per column, the factorisation needs no symbolic analysis and no index lookups
// (cost: the sum over columns of their height squared, halved).
#include <cstddef>
#include <vector>

namespace driftcorr {

class SkylineLdlt {
public:
    /// The envelope: first_row[j] <= j is the first row of column j that may be non-zero.
    explicit SkylineLdlt(std::vector<int> first_row);

    int size() const { return static_cast<int>(first_.size()); }
    /// Entries of the envelope, column after column.
    std::size_t entries() const { return start_.back(); }
    /// Index of entry (row, column), first_row[column] <= row <= column, into values().
    std::size_t Index(int row, int column) const {
        return start_[column] + static_cast<std::size_t>(row - first_[column]);
    }
    /// The matrix's upper triangle within the envelope; set it, then Factorize.
    std::vector<double>& values() { return values_; }
    const std::vector<double>& values() const { return values_; }
    int first_row(int column) const { return first_[column]; }

    /// Factorises values() (left as they are). True when every pivot D is positive (the matrix
    /// is positive definite); false otherwise, NaN included.
    bool Factorize();
    /// Solves A x = b in place with the last factorisation. Precondition: Factorize() was true.
    void Solve(std::vector<double>& b) const;

private:
    std::vector<int> first_;
    std::vector<std::size_t> start_;
    std::vector<double> values_, factor_;  // factor_: U above the diagonal (A = U^T D U), D on it
    std::vector<double> h_;                // Factorize's column before scaling
};

}  // namespace driftcorr
