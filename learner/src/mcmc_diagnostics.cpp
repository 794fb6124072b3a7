#include "learner/mcmc_diagnostics.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hbirl {

namespace {

constexpr double kNotANumber = std::numeric_limits<double>::quiet_NaN();

// At least `min_chains` chains, every one the same length, at least `min_length`.
void check_chains(const Chains& chains, size_t min_chains, size_t min_length) {
  if (chains.size() < min_chains || chains.empty()) throw std::invalid_argument("MCMC diagnostics: too few chains");
  const size_t n = chains.front().size();
  if (n < min_length) throw std::invalid_argument("MCMC diagnostics: chains too short");
  for (const auto& chain : chains) {
    if (chain.size() != n) throw std::invalid_argument("MCMC diagnostics: chains of different lengths");
  }
}

bool all_identical(const Chains& chains) {
  for (const auto& chain : chains) {
    for (double x : chain) {
      if (x != chains.front().front()) return false;
    }
  }
  return true;
}

// The chain means, W (the mean of the chains' unbiased variances) and
// var+ = (N-1)/N W + B/N with B/N the (unbiased) variance of the chain means
// (Vehtari et al. 2021 §3.1; B/N = 0 for a single chain).
struct ChainMoments {
  std::vector<double> means;
  double within = 0.0;
  double var_plus = 0.0;
};

ChainMoments chain_moments(const Chains& chains) {
  const double m = static_cast<double>(chains.size());
  const double n = static_cast<double>(chains.front().size());
  ChainMoments out;
  double grand = 0.0;
  for (const auto& chain : chains) {
    // Shifted by the first draw: a constant chain has exactly its value as mean and 0 as
    // variance.
    double mean = 0.0;
    for (double x : chain) mean += x - chain.front();
    mean = chain.front() + mean / n;
    double squares = 0.0;
    for (double x : chain) squares += (x - mean) * (x - mean);
    out.within += squares / (n - 1.0);
    out.means.push_back(mean);
    grand += mean;
  }
  out.within /= m;
  grand /= m;
  double between = 0.0;  // B / N
  if (chains.size() > 1) {
    for (double mean : out.means) between += (mean - grand) * (mean - grand);
    between /= m - 1.0;
  }
  out.var_plus = (n - 1.0) / n * out.within + between;
  return out;
}

// Each chain minus its own mean.
Chains centred(const Chains& chains, const std::vector<double>& means) {
  Chains out = chains;
  for (size_t c = 0; c < out.size(); ++c) {
    for (double& x : out[c]) x -= means[c];
  }
  return out;
}

// The mean over chains of the lag-t autocovariance, normalised by N (not N - t): the
// s_m^2 rho_t,m of eq. 10.
double mean_autocovariance(const Chains& centred_chains, size_t lag) {
  const auto n = static_cast<Eigen::Index>(centred_chains.front().size());
  const Eigen::Index overlap = n - static_cast<Eigen::Index>(lag);
  double sum = 0.0;
  for (const auto& chain : centred_chains) {
    const Eigen::Map<const Eigen::VectorXd> x(chain.data(), n);
    sum += x.head(overlap).dot(x.tail(overlap));
  }
  return sum / static_cast<double>(n) / static_cast<double>(centred_chains.size());
}

double pooled_median(const Chains& chains) {
  std::vector<double> all;
  for (const auto& chain : chains) all.insert(all.end(), chain.begin(), chain.end());
  const size_t half = all.size() / 2;
  std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(half), all.end());
  const double upper = all[half];
  if (all.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(half)));
}

// Draws without an order (NaN) or without a rank (infinities) are refused.
void check_finite(double x) {
  if (!std::isfinite(x)) throw std::invalid_argument("MCMC diagnostics: a draw is not finite");
}

// The distinct draws in increasing order, by sorting them all.
std::vector<double> sorted_distinct_draws(const Chains& chains) {
  std::vector<double> values;
  for (const auto& chain : chains) {
    for (double x : chain) check_finite(x);
    values.insert(values.end(), chain.begin(), chain.end());
  }
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  return values;
}

// The distinct draws in increasing order: by one scan when there are few (indicators,
// small counts), else by sorting them all.
std::vector<double> distinct_draws(const Chains& chains) {
  constexpr size_t kFew = 16;
  std::vector<double> values;
  double last = std::numeric_limits<double>::quiet_NaN();
  for (const auto& chain : chains) {
    for (double x : chain) {
      if (x == last) continue;  // runs are common in chains
      check_finite(x);
      last = x;
      if (std::find(values.begin(), values.end(), x) != values.end()) continue;
      if (values.size() == kFew) return sorted_distinct_draws(chains);
      values.push_back(x);
    }
  }
  std::sort(values.begin(), values.end());
  return values;
}

// Split-R-hat of the rank-normalised draws of already split chains; NaN when the draws
// are all identical.
double rank_rhat(const Chains& split) {
  return all_identical(split) ? kNotANumber : potential_scale_reduction(rank_normalise(split));
}

// Split-R-hat of the rank-normalised split folded draws (§4); NaN when it adds nothing.
// Draws of two distinct values (the engine's indicators) fold to two values again -- an
// affine image of the same indicator -- or to a constant; rank normalisation of
// two-valued draws is affine too, and R-hat is invariant under affine maps, so the
// folded part then equals the other and is not computed again.
double folded_rank_rhat(const Chains& chains) {
  if (distinct_draws(chains).size() <= 2) return kNotANumber;
  return rank_rhat(split_chains(fold(chains)));
}

// The paper's R-hat from its two parts (§4); a NaN folded part (see folded_rank_rhat)
// adds nothing.
double worse_of(double bulk, double folded) { return std::isnan(folded) ? bulk : std::max(bulk, folded); }

}  // namespace

double normal_quantile(double p) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("normal_quantile: p must be in (0, 1)");
  // Acklam's rational approximation (relative error < 1.2e-9) ...
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                                 1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                                 6.680131188771972e+01, -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                                 -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                                 3.754408661907416e+00};
  const double tail = std::min(p, 1.0 - p);
  double x = 0.0;
  if (tail < 0.02425) {
    const double q = std::sqrt(-2.0 * std::log(tail));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    if (p > 0.5) x = -x;
  } else {
    const double q = p - 0.5;
    const double r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  // ... then one Halley step on Phi(x) = p, Phi(x) = erfc(-x / sqrt 2) / 2: full double precision.
  const double error = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
  const double u = error * 2.50662827463100050242 * std::exp(0.5 * x * x);  // error / phi(x)
  return x - u / (1.0 + 0.5 * x * u);
}

Chains split_chains(const Chains& chains) {
  check_chains(chains, 1, 2);
  const size_t n = chains.front().size();
  const auto half = static_cast<std::ptrdiff_t>(n / 2);
  Chains out;
  for (const auto& chain : chains) {
    out.emplace_back(chain.begin(), chain.begin() + half);
    out.emplace_back(chain.end() - half, chain.end());  // an odd chain's middle draw is dropped
  }
  return out;
}

Chains rank_normalise(const Chains& chains) {
  check_chains(chains, 1, 1);
  const std::vector<double> values = distinct_draws(chains);
  std::vector<size_t> group;  // of every draw, chain after chain: the index of its value
  std::vector<double> count(values.size(), 0.0);
  for (const auto& chain : chains) {
    for (double x : chain) {
      group.push_back(static_cast<size_t>(std::lower_bound(values.begin(), values.end(), x) - values.begin()));
      count[group.back()] += 1.0;
    }
  }
  // The draws equal to values[j] hold ranks below + 1 .. below + count[j] (1-based) and
  // each gets their average.
  const double total = static_cast<double>(chains.size() * chains.front().size());
  std::vector<double> z(values.size());
  double below = 0.0;
  for (size_t j = 0; j < values.size(); ++j) {
    const double rank = below + 0.5 * (count[j] + 1.0);
    z[j] = normal_quantile((rank - 0.375) / (total + 0.25));
    below += count[j];
  }
  Chains out = chains;
  auto next = group.begin();
  for (auto& chain : out) {
    for (double& x : chain) x = z[*next++];
  }
  return out;
}

Chains fold(const Chains& chains) {
  check_chains(chains, 1, 1);
  const double median = pooled_median(chains);
  Chains out = chains;
  for (auto& chain : out) {
    for (double& x : chain) x = std::abs(x - median);
  }
  return out;
}

double potential_scale_reduction(const Chains& chains) {
  check_chains(chains, 2, 2);
  const ChainMoments moments = chain_moments(chains);
  if (moments.within == 0.0) {
    // Every chain constant: identical draws say nothing, different constants never mix.
    return moments.var_plus == 0.0 ? kNotANumber : std::numeric_limits<double>::infinity();
  }
  return std::sqrt(moments.var_plus / moments.within);
}

double split_rhat(const Chains& chains) { return potential_scale_reduction(split_chains(chains)); }

double rank_normalised_split_rhat(const Chains& chains) {
  return worse_of(rank_rhat(split_chains(chains)), folded_rank_rhat(chains));
}

double effective_sample_size(const Chains& chains) {
  check_chains(chains, 1, 2);
  const ChainMoments moments = chain_moments(chains);
  if (moments.var_plus == 0.0) return kNotANumber;  // all draws identical
  const size_t n = chains.front().size();
  const Chains x = centred(chains, moments.means);
  // eq. 10: rho_t = 1 - (W - mean_m s_m^2 rho_t,m) / var+, with rho_0 = 1.
  const auto rho = [&](size_t lag) {
    return lag == 0 ? 1.0 : 1.0 - (moments.within - mean_autocovariance(x, lag)) / moments.var_plus;
  };
  // §3.2: Geyer's initial positive sequence (sum the pairs P_k = rho_2k + rho_2k+1 while
  // they are positive) made an initial monotone sequence (each P_k at most the previous).
  double pairs = 0.0;
  double previous = std::numeric_limits<double>::infinity();
  for (size_t k = 0; 2 * k + 1 < n; ++k) {
    const double p = rho(2 * k) + rho(2 * k + 1);
    if (!(p > 0.0)) break;
    previous = std::min(previous, p);
    pairs += previous;
  }
  const double draws = static_cast<double>(n * chains.size());
  // tau = -1 + 2 sum_k P_k; antithetic chains can make it small: ESS at most S log10 S (§3.2).
  const double tau = std::max(-1.0 + 2.0 * pairs, 1.0 / std::log10(draws));
  return draws / tau;
}

double bulk_ess(const Chains& chains) { return effective_sample_size(rank_normalise(split_chains(chains))); }

std::optional<QuantityDiagnostics> diagnose(const Chains& chains) {
  check_chains(chains, 1, 0);
  if (chains.front().size() < 4) return std::nullopt;  // fewer than 2 draws per half
  const Chains split = split_chains(chains);
  if (all_identical(split)) return std::nullopt;
  const Chains z = rank_normalise(split);
  const double folded = folded_rank_rhat(chains);
  return QuantityDiagnostics{worse_of(potential_scale_reduction(z), folded), effective_sample_size(z)};
}

void McmcDiagnostics::add(const QuantityDiagnostics& q) {
  worst_rhat = std::max(worst_rhat, std::isnan(q.rhat) ? std::numeric_limits<double>::infinity() : q.rhat);
  worst_bulk_ess = std::min(worst_bulk_ess, std::isnan(q.bulk_ess) ? 0.0 : q.bulk_ess);
  ++quantities;
}

McmcDiagnostics& McmcDiagnostics::operator+=(const McmcDiagnostics& other) {
  worst_rhat = std::max(worst_rhat, other.worst_rhat);
  worst_bulk_ess = std::min(worst_bulk_ess, other.worst_bulk_ess);
  quantities += other.quantities;
  chains = std::max(chains, other.chains);
  return *this;
}

}  // namespace hbirl
