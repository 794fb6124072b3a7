#pragma once
// The products BiCGSTAB makes with (I - gamma P_pi) and its transpose (PolicyMatrix), as
// an Eigen matrix-free operator (Eigen's "Matrix-free solvers" interface).
//
// Why not Eigen's sparse product: at 40,000 states a row of the matrix holds ~5 entries,
// and a compressed-row product then costs about three loads per entry (value, column,
// x[column]): ~1 entry per cycle, a third of what the L3 cache could stream
// (docs/BENCHMARKS.md "Scale to the limit"). When the entries lie on few diagonals
// (a grid's moves: the offsets 0, +-1, +-width) they are stored by diagonal instead, one
// dense array per offset, and the product is a few contiguous multiply-adds per row that
// the compiler vectorises across rows: 2.5x faster on the 200x200 Gridworld.
//
// Either way each row's sum is formed as Eigen forms it (from 0, in the order of its
// columns, then added to a zeroed result), so for a finite x every product is bit for bit
// Eigen's, and so is every solve and everything learned (tests PolicyOperator.*, against
// Eigen's BiCGSTAB compiled as the library is): a diagonal's slots outside the pattern
// hold 0 and add exactly 0. A non-finite x can make such a slot NaN: PolicyMatrix's solves
// then fail as they did (every diagonal entry of I - gamma P_pi is non-zero, so a
// non-finite entry reaches a residual either way), though perhaps at another iteration.
#include <Eigen/Core>
#include <Eigen/IterativeLinearSolvers>
#include <type_traits>
#include <vector>

#include "learner/mdp.hpp"

namespace hbirl {
class PolicyOperator;
}

namespace Eigen::internal {
// Eigen's traits for a matrix-free operator: those of a sparse matrix.
template <>
struct traits<hbirl::PolicyOperator> : public traits<Eigen::SparseMatrix<double>> {};
}  // namespace Eigen::internal

namespace hbirl {

class PolicyOperator : public Eigen::EigenBase<PolicyOperator> {
 public:
  using Scalar = double;
  using RealScalar = double;
  using StorageIndex = int;
  enum { ColsAtCompileTime = Eigen::Dynamic, MaxColsAtCompileTime = Eigen::Dynamic, IsRowMajor = false };

  // Stored by diagonal when its distinct offsets times its rows are at most this many
  // times its non-zeros (the work a product wastes on slots outside the pattern).
  static constexpr int kMaxDiagonalFill = 2;

  // How the products read the matrix: by diagonal where that pays (kChosen), or always
  // row by row (kRows: what the tests compare the diagonal products with).
  enum class Storage { kChosen, kRows };

  PolicyOperator() = default;
  // matrix: square, compressed, its pattern fixed from now on (its values follow through
  // update_values). transposed: the operator is matrix^T.
  PolicyOperator(const SparseRowMatrix& matrix, bool transposed, Storage storage = Storage::kChosen);

  // Take the matrix's current values (its values changed, not its pattern); the operator
  // reads the matrix itself from then on, so it must outlive the products.
  void update_values(const SparseRowMatrix& matrix);

  Eigen::Index rows() const { return n_; }
  Eigen::Index cols() const { return n_; }
  bool by_diagonal() const { return !offsets_.empty(); }
  // The bytes one product reads and writes (its storage, x once, y): what
  // docs/BENCHMARKS.md divides by the measured bandwidth.
  long long bytes_per_product() const;

  // y = A x (A: the matrix, or its transpose), each row summed as Eigen sums it.
  void multiply(const double* x, double* y) const;
  // 1 / A(j, j) where that is non-zero, else 1: Eigen's DiagonalPreconditioner's.
  void inverse_diagonal(Eigen::VectorXd& out) const;

  template <typename Rhs>
  Eigen::Product<PolicyOperator, Rhs, Eigen::AliasFreeProduct> operator*(const Eigen::MatrixBase<Rhs>& x) const {
    return Eigen::Product<PolicyOperator, Rhs, Eigen::AliasFreeProduct>(*this, x.derived());
  }

 private:
  void multiply_rows(const double* x, double* y) const;
  void multiply_diagonals(const double* x, double* y) const;
  void multiply_diagonals_transposed(const double* x, double* y) const;

  const SparseRowMatrix* matrix_ = nullptr;
  bool transposed_ = false;
  int n_ = 0;
  // Rows (transposed_ false) or columns (true) of the matrix as compressed rows of A:
  // for the transpose without diagonals, a copy with its own pattern.
  SparseRowMatrix rows_;
  std::vector<int> rows_slot_;  // rows_ entry -> index into the matrix's values
  // By diagonal: diagonals_[k * n + r] = matrix(r, r + offsets_[k]), 0 outside the pattern.
  std::vector<int> offsets_;  // ascending
  std::vector<double> diagonals_;
  std::vector<int> diagonal_slot_;  // matrix values entry -> index into diagonals_
};

// Eigen's DiagonalPreconditioner, its inverse diagonal read from a PolicyOperator.
class InverseDiagonalPreconditioner : public Eigen::DiagonalPreconditioner<double> {
 public:
  template <typename MatType>
  InverseDiagonalPreconditioner& analyzePattern(const MatType&) {
    return *this;
  }
  InverseDiagonalPreconditioner& factorize(const PolicyOperator& op) {
    op.inverse_diagonal(m_invdiag);
    m_isInitialized = true;
    return *this;
  }
  InverseDiagonalPreconditioner& compute(const PolicyOperator& op) { return factorize(op); }
};

}  // namespace hbirl

namespace Eigen::internal {
// dst = A x, dst += A x, dst -= A x and dst += alpha A x, each as Eigen's sparse product
// (res += alpha * row sum) forms them.
template <typename Rhs>
struct generic_product_impl<hbirl::PolicyOperator, Rhs, SparseShape, DenseShape, GemvProduct>
    : generic_product_impl_base<
          hbirl::PolicyOperator, Rhs,
          generic_product_impl<hbirl::PolicyOperator, Rhs, SparseShape, DenseShape, GemvProduct>> {
  template <typename Dest>
  static void evalTo(Dest& dst, const hbirl::PolicyOperator& lhs, const Rhs& rhs) {
    const Eigen::Ref<const Eigen::VectorXd> x(rhs);  // no copy for a plain vector
    if constexpr (std::is_same_v<Dest, Eigen::VectorXd>) {
      if (dst.data() != x.data()) {
        dst.resize(lhs.rows());
        lhs.multiply(x.data(), dst.data());
        return;
      }
    }
    Eigen::VectorXd product(lhs.rows());
    lhs.multiply(x.data(), product.data());
    dst = product;
  }
  template <typename Dest>
  static void scaleAndAddTo(Dest& dst, const hbirl::PolicyOperator& lhs, const Rhs& rhs, const double& alpha) {
    const Eigen::Ref<const Eigen::VectorXd> x(rhs);
    Eigen::VectorXd sum(lhs.rows());
    lhs.multiply(x.data(), sum.data());
    for (Index i = 0; i < sum.size(); ++i) dst.coeffRef(i) += alpha * sum[i];
  }
  template <typename Dest>
  static void addTo(Dest& dst, const hbirl::PolicyOperator& lhs, const Rhs& rhs) {
    scaleAndAddTo(dst, lhs, rhs, 1.0);
  }
  template <typename Dest>
  static void subTo(Dest& dst, const hbirl::PolicyOperator& lhs, const Rhs& rhs) {
    scaleAndAddTo(dst, lhs, rhs, -1.0);
  }
};
}  // namespace Eigen::internal
