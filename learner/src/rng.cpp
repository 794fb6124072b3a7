#include "learner/rng.hpp"

#include <stdexcept>

namespace hbirl {

namespace {
// SplitMix64 finaliser: turns structured (seed, stream) pairs into well-spread seeds.
std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
}  // namespace

std::uint64_t Rng::mix(std::uint64_t a, std::uint64_t b) { return splitmix(splitmix(a) ^ b); }

Rng::Rng(std::uint64_t seed, std::uint64_t stream)
    : seed_(seed), stream_(stream), engine_(splitmix(seed) ^ splitmix(stream + 0x5851F42D4C957F2Dull)) {}

int Rng::uniform_int(int n) {
  if (n <= 0) throw std::invalid_argument("Rng::uniform_int: n must be positive");
  const auto range = static_cast<std::uint64_t>(n);
  // Reject the low values that would make the modulo biased.
  const std::uint64_t threshold = (0 - range) % range;
  std::uint64_t x = engine_();
  while (x < threshold) x = engine_();
  return static_cast<int>(x % range);
}

int Rng::categorical(const Eigen::Ref<const Eigen::VectorXd>& weights) {
  const double total = weights.sum();
  if (!(total > 0.0)) throw std::invalid_argument("Rng::categorical: weights sum to zero");
  double u = uniform() * total;
  const auto n = static_cast<int>(weights.size());
  int last_positive = -1;
  for (int i = 0; i < n; ++i) {
    if (weights[i] <= 0.0) continue;
    last_positive = i;
    if (u < weights[i]) return i;
    u -= weights[i];
  }
  return last_positive;  // rounding left a sliver past the end
}

}  // namespace hbirl
