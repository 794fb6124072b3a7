#pragma once
// Convergence diagnostics of MCMC draws: the rank-normalised split-R-hat and the bulk
// effective sample size of Vehtari, Gelman, Simpson, Carpenter & Buerkner (2021),
// "Rank-normalization, folding, and localization: an improved R-hat for assessing
// convergence of MCMC", Bayesian Analysis 16(2) -- what Stan and ArviZ print.
// docs/MODEL.md ("Is the MCMC E-step converged?") says where hbirl uses them.
//
// Draws come as M chains of N draws each (every chain the same length). With
//   split:  every chain cut into its first and second half (the middle draw of an odd
//           chain dropped), so a chain that drifts disagrees with itself (§3.1);
//   rank-normalise:  every draw replaced by z = Phi^-1((r - 3/8) / (S + 1/4)), r its rank
//           among all S draws pooled, tied draws sharing their average rank (§4);
//   fold:   every draw replaced by |x - median|, the median of all draws pooled (§4);
// the diagnostics are
//   R-hat    = max(split-R-hat of the rank-normalised split draws,
//                  split-R-hat of the rank-normalised split folded draws)          (§4)
//   bulk ESS = ESS of the rank-normalised split draws (§4), the ESS by the
//              multi-chain autocorrelation of eq. 10 with Geyer's initial positive and
//              initial monotone sequences (§3.2).
#include <limits>
#include <optional>
#include <vector>

namespace hbirl {

// M chains of N draws each. The functions throw std::invalid_argument when the chains
// differ in length or are too short, and the rank-based ones when a draw is not finite.
using Chains = std::vector<std::vector<double>>;

// Vehtari et al. 2021's recommendations: R-hat above this or a bulk ESS below the
// other means the draws should not be trusted yet.
constexpr double kRhatThreshold = 1.01;
constexpr double kBulkEssThreshold = 400.0;

// Phi^-1(p) for p in (0, 1): the standard normal quantile, to ~1e-15.
double normal_quantile(double p);

// Each chain as two chains, its first and its second half; an odd chain's middle draw
// is dropped.
Chains split_chains(const Chains& chains);
// z = Phi^-1((r - 3/8) / (S + 1/4)) with r the rank of the draw among all S draws pooled,
// ties given their average rank (Vehtari et al. 2021 §4). Same shape as the input.
Chains rank_normalise(const Chains& chains);
// |x - median(all draws)|.
Chains fold(const Chains& chains);

// The potential scale reduction of the chains as given (Gelman-Rubin; Vehtari et al.
// 2021 §3.1): sqrt(var+ / W), var+ = (N-1)/N W + B/N, W the mean within-chain
// variance, B/N the variance of the chain means. Infinite when every chain is constant
// but they differ; NaN when all draws are identical. Needs M >= 2 and N >= 2.
double potential_scale_reduction(const Chains& chains);
// potential_scale_reduction(split_chains(chains)): split-R-hat on the raw draws.
double split_rhat(const Chains& chains);
// The paper's R-hat: max of the split-R-hat of the rank-normalised draws and of the
// rank-normalised folded draws. The folded part is left out when it cannot differ: when
// the draws take two values (an indicator), as R-hat is invariant under affine maps and
// both parts are then affine images of the same indicator (or the folded draws are all
// identical).
double rank_normalised_split_rhat(const Chains& chains);

// The ESS of the chains as given (no splitting, no ranks; Vehtari et al. 2021 §3.2):
// S / tau, tau = -1 + 2 sum_k P_k, P_k = rho_2k + rho_2k+1 summed while positive and
// made non-increasing, rho_t = 1 - (W - mean_m acov_m(t)) / var+ (eq. 10), rho_0 = 1;
// at most S log10 S (antithetic chains). Needs M >= 1 and N >= 2.
double effective_sample_size(const Chains& chains);
// effective_sample_size(rank_normalise(split_chains(chains))).
double bulk_ess(const Chains& chains);

// Both diagnostics of one quantity, sharing the split and the ranks; nothing when the
// split draws are all identical (a quantity that never changes carries no information
// about mixing: R-hat is 0/0) or too short (fewer than 2 draws per half).
struct QuantityDiagnostics {
  double rhat = 0.0;
  double bulk_ess = 0.0;
};
std::optional<QuantityDiagnostics> diagnose(const Chains& chains);

// The worst diagnostics over many quantities (and many chain sets): max R-hat, min bulk
// ESS, how many quantities were checked. Merging takes max / min / sum, which are exact
// and order-free, so a sum over blocks has the same bits whatever the thread count or
// block order. The neutral value checks nothing.
struct McmcDiagnostics {
  double worst_rhat = -std::numeric_limits<double>::infinity();
  double worst_bulk_ess = std::numeric_limits<double>::infinity();
  long long quantities = 0;
  int chains = 0;  // chains per chain set (the largest seen)

  void add(const QuantityDiagnostics& q);
  McmcDiagnostics& operator+=(const McmcDiagnostics& other);
  bool converged() const {
    return quantities == 0 || (worst_rhat <= kRhatThreshold && worst_bulk_ess >= kBulkEssThreshold);
  }
};

}  // namespace hbirl
