#pragma once
// The only source of randomness in hbirl. Every random draw goes through an Rng that
// was passed in explicitly; independent work items (restarts, runs, trajectories) get
// their own stream derived from (seed, stream index), so results do not depend on
// which thread ran what or in which order.
#include <Eigen/Core>
#include <cstdint>
#include <random>

namespace hbirl {

class Rng {
 public:
  explicit Rng(std::uint64_t seed, std::uint64_t stream = 0);

  // A child generator for work item `stream`; independent of how many draws this
  // generator has made.
  Rng split(std::uint64_t stream) const { return Rng(seed_, mix(stream_, stream)); }

  std::uint64_t next_u64() { return engine_(); }
  // Uniform in [0, 1), 53 random bits (the same on every platform, unlike
  // std::uniform_real_distribution).
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n), n > 0, unbiased.
  int uniform_int(int n);
  // Index drawn from non-negative weights (need not be normalised; must not all be 0).
  int categorical(const Eigen::Ref<const Eigen::VectorXd>& weights);

 private:
  static std::uint64_t mix(std::uint64_t a, std::uint64_t b);
  std::uint64_t seed_;
  std::uint64_t stream_;
  std::mt19937_64 engine_;
};

}  // namespace hbirl
