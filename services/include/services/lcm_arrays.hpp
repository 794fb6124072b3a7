#pragma once
// Between Eigen and the arrays of lcm-gen's C++ messages: `double x[n]` is a
// std::vector<double>, `double x[rows][cols]` a std::vector<std::vector<double>> whose rows
// the decoder has sized to the message's own length fields. The one place such arrays
// are converted; callers check the length fields against what they expect.
#include <Eigen/Core>
#include <vector>

namespace hbirl::services {

template <class Derived>
std::vector<double> lcm_vector(const Eigen::DenseBase<Derived>& v) {
  std::vector<double> out(static_cast<size_t>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) out[static_cast<size_t>(i)] = v.derived().coeff(i);
  return out;
}

template <class Derived>
std::vector<std::vector<double>> lcm_rows(const Eigen::DenseBase<Derived>& m) {
  std::vector<std::vector<double>> out(static_cast<size_t>(m.rows()),
                                       std::vector<double>(static_cast<size_t>(m.cols())));
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      out[static_cast<size_t>(r)][static_cast<size_t>(c)] = m.derived().coeff(r, c);
  }
  return out;
}

inline Eigen::VectorXd eigen_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

// `cols`: the message's length field of the rows (every row has it, by the decoder).
template <class Matrix = Eigen::MatrixXd>
Matrix eigen_rows(const std::vector<std::vector<double>>& rows, Eigen::Index cols) {
  Matrix out(static_cast<Eigen::Index>(rows.size()), cols);
  for (Eigen::Index r = 0; r < out.rows(); ++r) {
    for (Eigen::Index c = 0; c < cols; ++c) out(r, c) = rows[static_cast<size_t>(r)][static_cast<size_t>(c)];
  }
  return out;
}

}  // namespace hbirl::services
