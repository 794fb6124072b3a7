#include "learner/policy_operator.hpp"

#include <algorithm>
#include <stdexcept>

namespace hbirl {

namespace {
// Rows handled at once by the diagonal products: their sums (4 kB) stay in L1 while each
// diagonal passes over them.
constexpr int kRowBlock = 512;

void sort_unique(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

// The matrix's diagonals (column - row of its non-zeros), ascending; empty if there are
// more than max_count of them.
std::vector<int> diagonal_offsets(const SparseRowMatrix& m, long long max_count) {
  std::vector<int> offsets;
  const auto limit = static_cast<size_t>(std::min<long long>(max_count, m.nonZeros()));
  for (int r = 0; r < m.rows(); ++r) {
    for (int j = m.outerIndexPtr()[r]; j < m.outerIndexPtr()[r + 1]; ++j) offsets.push_back(m.innerIndexPtr()[j] - r);
    // A grid adds the same few offsets on every row: keep the list short as it grows.
    if (offsets.size() > 4 * limit + 64) {
      sort_unique(offsets);
      if (offsets.size() > limit) return {};
    }
  }
  sort_unique(offsets);
  if (offsets.size() > limit) return {};
  return offsets;
}
}  // namespace

PolicyOperator::PolicyOperator(const SparseRowMatrix& matrix, bool transposed, Storage storage)
    : transposed_(transposed), n_(static_cast<int>(matrix.rows())) {
  if (matrix.rows() != matrix.cols() || !matrix.isCompressed()) {
    throw std::logic_error("PolicyOperator: the matrix must be square and compressed");
  }
  // At most kMaxDiagonalFill times the non-zeros in slots: that many diagonals of n_.
  const long long max_diagonals = n_ > 0 ? static_cast<long long>(kMaxDiagonalFill) * matrix.nonZeros() / n_ : 0;
  std::vector<int> offsets = storage == Storage::kChosen ? diagonal_offsets(matrix, max_diagonals) : std::vector<int>{};
  const auto slots = static_cast<long long>(offsets.size()) * n_;
  if (!offsets.empty()) {
    offsets_ = std::move(offsets);
    diagonals_.assign(static_cast<size_t>(slots), 0.0);
    diagonal_slot_.resize(static_cast<size_t>(matrix.nonZeros()));
    for (int r = 0; r < n_; ++r) {
      for (int j = matrix.outerIndexPtr()[r]; j < matrix.outerIndexPtr()[r + 1]; ++j) {
        const auto k =
            std::lower_bound(offsets_.begin(), offsets_.end(), matrix.innerIndexPtr()[j] - r) - offsets_.begin();
        diagonal_slot_[static_cast<size_t>(j)] = static_cast<int>(k) * n_ + r;
      }
    }
  } else if (transposed_) {
    // The transpose's pattern once; update_values then copies values through rows_slot_
    // (what Eigen's transpose would give, without its allocation and count).
    rows_ = matrix.transpose();
    rows_slot_.resize(static_cast<size_t>(rows_.nonZeros()));
    for (int col = 0; col < n_; ++col) {
      for (int j = rows_.outerIndexPtr()[col]; j < rows_.outerIndexPtr()[col + 1]; ++j) {
        const int row = rows_.innerIndexPtr()[j];
        const int* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[row];
        const int* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[row + 1];
        rows_slot_[static_cast<size_t>(j)] =
            static_cast<int>(std::lower_bound(begin, end, col) - matrix.innerIndexPtr());
      }
    }
  }
}

void PolicyOperator::update_values(const SparseRowMatrix& matrix) {
  matrix_ = &matrix;
  const double* value = matrix.valuePtr();
  if (by_diagonal()) {
    for (size_t j = 0; j < diagonal_slot_.size(); ++j) diagonals_[static_cast<size_t>(diagonal_slot_[j])] = value[j];
  } else if (transposed_) {
    double* out = rows_.valuePtr();
    for (size_t j = 0; j < rows_slot_.size(); ++j) out[j] = value[rows_slot_[j]];
  }
}

void PolicyOperator::multiply(const double* x, double* y) const {
  if (!by_diagonal()) {
    multiply_rows(x, y);
  } else if (transposed_) {
    multiply_diagonals_transposed(x, y);
  } else {
    multiply_diagonals(x, y);
  }
}

// Eigen's row-major sparse product: tmp = 0, tmp += value * x[column] in column order,
// then res = 0 + tmp.
void PolicyOperator::multiply_rows(const double* x, double* y) const {
  const SparseRowMatrix& m = transposed_ ? rows_ : *matrix_;
  const int* start = m.outerIndexPtr();
  const int* column = m.innerIndexPtr();
  const double* value = m.valuePtr();
  for (int r = 0; r < n_; ++r) {
    double sum = 0.0;
    for (int j = start[r]; j < start[r + 1]; ++j) sum += value[j] * x[column[j]];
    y[r] = 0.0 + sum;  // Eigen adds the sum to a zeroed result: -0 becomes +0
  }
}

// Row r's sum over the diagonals in ascending offset (= column) order; a block of rows at
// a time so that each diagonal is a contiguous, vectorised multiply-add.
void PolicyOperator::multiply_diagonals(const double* __restrict x, double* __restrict y) const {
  for (int r0 = 0; r0 < n_; r0 += kRowBlock) {
    const int r1 = std::min(n_, r0 + kRowBlock);
    std::fill(y + r0, y + r1, 0.0);
    for (size_t k = 0; k < offsets_.size(); ++k) {
      const int o = offsets_[k];
      const double* __restrict d = diagonals_.data() + k * static_cast<size_t>(n_);
      const int lo = std::max(r0, -o);
      const int hi = std::min(r1, n_ - o);
      for (int r = lo; r < hi; ++r) y[r] += d[r] * x[r + o];
    }
    for (int r = r0; r < r1; ++r) y[r] = 0.0 + y[r];  // as multiply_rows
  }
}

// (A^T x)_i = sum_k A(i - o_k, i) x_{i - o_k}: A^T's row i in ascending column order is
// A's diagonals in descending offset order.
void PolicyOperator::multiply_diagonals_transposed(const double* __restrict x, double* __restrict y) const {
  for (int r0 = 0; r0 < n_; r0 += kRowBlock) {
    const int r1 = std::min(n_, r0 + kRowBlock);
    std::fill(y + r0, y + r1, 0.0);
    for (size_t k = offsets_.size(); k-- > 0;) {
      const int o = offsets_[k];
      const double* __restrict d = diagonals_.data() + k * static_cast<size_t>(n_);
      const int lo = std::max(r0, o);
      const int hi = std::min(r1, n_ + o);
      for (int i = lo; i < hi; ++i) y[i] += d[i - o] * x[i - o];
    }
    for (int i = r0; i < r1; ++i) y[i] = 0.0 + y[i];  // as multiply_rows
  }
}

long long PolicyOperator::bytes_per_product() const {
  const auto d = static_cast<long long>(sizeof(double));
  const auto i = static_cast<long long>(sizeof(int));
  const long long vectors = 2 * d * n_;
  if (by_diagonal()) return static_cast<long long>(diagonals_.size()) * d + vectors;
  const long long entries = transposed_ ? rows_.nonZeros() : matrix_->nonZeros();
  return entries * (d + i) + (n_ + 1) * i + vectors;
}

void PolicyOperator::inverse_diagonal(Eigen::VectorXd& out) const {
  const SparseRowMatrix& m = *matrix_;
  out.resize(n_);
  for (int r = 0; r < n_; ++r) {
    const int* begin = m.innerIndexPtr() + m.outerIndexPtr()[r];
    const int* end = m.innerIndexPtr() + m.outerIndexPtr()[r + 1];
    const int* it = std::lower_bound(begin, end, r);
    const double d = it != end && *it == r ? m.valuePtr()[it - m.innerIndexPtr()] : 0.0;
    out[r] = d != 0.0 ? 1.0 / d : 1.0;
  }
}

}  // namespace hbirl
