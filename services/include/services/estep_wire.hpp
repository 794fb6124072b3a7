#pragma once
// The E-step's messages on the bus (the protocol: estep_service.hpp): trajectories,
// requests and results encoded and decoded, and what a result must be to be believed.
// Both sides use them: the optimiser (BusBlockExecutor) and the workers (sampler_worker.hpp).
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "hbirl/estep_request_t.hpp"
#include "hbirl/estep_result_t.hpp"
#include "hbirl/trajectory_t.hpp"
#include "learner/estep_observations.hpp"

namespace hbirl::services {

// Trajectories on the bus: trajectory `index` of a data set of `count`, in the block
// whose trajectories have `block_digest`, sent to `worker`. from_message throws
// InputError naming the bad field.
hbirl::trajectory_t to_message(const ObservedTrajectory& t, int index, int count, std::uint64_t block_digest,
                               const std::string& worker);
ObservedTrajectory from_message(const hbirl::trajectory_t& m);
// The trajectories of block `b` of `trajectories` (ObservationEStep::kBlockSize each), in place.
std::span<const ObservedTrajectory> block_of(const std::vector<ObservedTrajectory>& trajectories, int b);

// A fingerprint of this build's floating-point results: the bits of a fixed small E-step
// pass (a four-state task written here, exact engine). Workers built or run differently (another compiler,
// flags, CPU features, Eigen version) compute sums that differ in the last bits; their
// fingerprints then differ, and theta is no longer bit-identical to a one-process run.
std::uint64_t numerics_fingerprint();

// What is asked of the workers in one pass, apart from the attempt and who computes which
// block: the data set (by digests), the policy, the observation model and learned eta.
struct PassData {
  std::int64_t request_id = 0;
  std::uint64_t data_digest = 0, mdp_digest = 0;
  const std::vector<std::uint64_t>* block_digests = nullptr;
  std::uint64_t seed = 0;
};
hbirl::estep_request_t request_message(const PassData& pass, const ObservationEStep& estep, const SoftSolution& policy,
                                       const ObservationModel& model, const RowMatrix* eta);

// The shape every answer to a pass's request has.
struct ResultShape {
  int blocks = 0, pairs = 0, symbols = 0, confounders = 0, contexts = 0;
  int watch = -1, watch_steps = 0;    // the watched trajectory and its length (-1: none)
  int end_rows = 0, end_symbols = 0;  // the end sensor's O_end (0: none)
  std::vector<char> end_reported;     // per block: its trajectories have end reports (its answer, end counts)
};
// InputError unless the answer's statistics have the request's shape and a log-likelihood
// that is a number or -inf.
void check_shape(const hbirl::estep_result_t& m, const ResultShape& shape);
// The statistics an answer carries; InputError naming the field when they are not
// statistics (negative or infinite counts, marginals that are not distributions, contexts
// not of the request).
EStepStatistics statistics_of(const hbirl::estep_result_t& m, const ResultShape& shape);

// Two blocks' statistics equal, or within a relative `tolerance` (0: bit for bit).
bool same_statistics(const EStepStatistics& a, const EStepStatistics& b, double tolerance);

}  // namespace hbirl::services
