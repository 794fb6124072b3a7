#include "learner/observations.hpp"

#include <algorithm>
#include <numeric>

namespace hbirl {

ObservedTrajectory merge_identical_observations(const ObservedTrajectory& trajectory) {
  ObservedTrajectory out;
  out.ends_in_terminal = trajectory.ends_in_terminal;
  const Eigen::Index sources = trajectory.eta.cols();
  std::vector<int> rows;
  std::vector<double> weights;
  auto less = [&](int x, int y) {
    if (trajectory.symbols[static_cast<size_t>(x)] != trajectory.symbols[static_cast<size_t>(y)]) {
      return trajectory.symbols[static_cast<size_t>(x)] < trajectory.symbols[static_cast<size_t>(y)];
    }
    for (Eigen::Index z = 0; z < sources; ++z) {
      if (trajectory.eta(x, z) != trajectory.eta(y, z)) return trajectory.eta(x, z) < trajectory.eta(y, z);
    }
    return false;
  };
  for (int t = 0; t < trajectory.length(); ++t) {
    std::vector<int> step(static_cast<size_t>(trajectory.observations_at(t)));
    std::iota(step.begin(), step.end(), trajectory.step_begin[static_cast<size_t>(t)]);
    std::sort(step.begin(), step.end(), less);
    for (size_t i = 0; i < step.size(); ++i) {
      if (i > 0 && !less(step[i - 1], step[i])) {
        weights.back() += trajectory.weight(step[i]);
      } else {
        rows.push_back(step[i]);
        weights.push_back(trajectory.weight(step[i]));
      }
    }
    out.step_begin.push_back(static_cast<int>(rows.size()));
  }
  out.eta.resize(static_cast<Eigen::Index>(rows.size()), sources);
  for (size_t i = 0; i < rows.size(); ++i) {
    out.symbols.push_back(trajectory.symbols[static_cast<size_t>(rows[i])]);
    out.eta.row(static_cast<Eigen::Index>(i)) = trajectory.eta.row(rows[i]);
  }
  out.weights = std::move(weights);
  return out;
}

}  // namespace hbirl
