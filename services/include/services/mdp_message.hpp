#pragma once
// The MDP on the bus (MDP, lcmtypes/mdp_t.lcm): the optimiser sends the dynamics it
// learns on, in chunks; a sampler worker assembles them, validates the whole MDP before
// it computes with it, and checks the digest.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hbirl/mdp_t.hpp"
#include "learner/mdp.hpp"

namespace hbirl::services {

// The MDP's dynamics as messages of at most `max_entries` transition entries each.
std::vector<hbirl::mdp_t> to_messages(const Mdp& mdp, const std::string& domain, int max_entries = 65536);

// Collects the chunks of one MDP. Limits checked before anything is allocated.
class MdpAssembler {
 public:
  static constexpr int kMaxStates = 10'000'000;
  static constexpr int kMaxActions = 100'000;
  static constexpr long long kMaxPairs = 50'000'000;
  static constexpr int kMaxChunks = 100'000;
  static constexpr long long kMaxTransitions = 50'000'000;  // ~1.2 GB while assembling

  // Takes one chunk; returns the MDP once every chunk of its digest has come (then
  // forgets it). Throws InputError naming the field of a chunk that does not fit, or of
  // an assembled MDP that is not one (probabilities, start, digest).
  std::optional<Mdp> add(const hbirl::mdp_t& m);

 private:
  std::uint64_t digest_ = 0;
  int num_states_ = 0, num_actions_ = 0, num_chunks_ = 0;
  double discount_ = 0.0;
  std::vector<char> have_;  // per chunk
  int received_ = 0;
  Eigen::VectorXd start_;
  std::vector<int> terminal_;
  std::vector<TransitionEntry> transitions_;
  void forget();  // the MDP being assembled, memory and all
};

}  // namespace hbirl::services
