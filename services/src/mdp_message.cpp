// The MDP on the bus (mdp_message.hpp).
#include "services/mdp_message.hpp"

#include <cmath>

#include "learner/input_error.hpp"

namespace hbirl::services {

std::vector<hbirl::mdp_t> to_messages(const Mdp& mdp, const std::string& domain, int max_entries) {
  const SparseRowMatrix& T = mdp.transitions;
  const auto entries = static_cast<int>(T.nonZeros());
  const int chunks = std::max(1, (entries + max_entries - 1) / max_entries);
  std::vector<hbirl::mdp_t> out(static_cast<size_t>(chunks));
  const auto digest = static_cast<std::int64_t>(dynamics_digest(mdp));
  for (int c = 0; c < chunks; ++c) {
    hbirl::mdp_t& m = out[static_cast<size_t>(c)];
    m.utime = 0;  // the task, not a moment of it
    m.mdp_digest = digest;
    m.domain = domain;
    m.chunk = c;
    m.num_chunks = chunks;
    m.num_states = mdp.num_states;
    m.num_actions = mdp.num_actions;
    m.discount = mdp.discount;
    m.num_start = c == 0 ? mdp.num_states : 0;
    if (c == 0) {
      m.start.assign(mdp.start.data(), mdp.start.data() + mdp.start.size());
      m.terminal.assign(mdp.terminal.begin(), mdp.terminal.end());
    }
  }
  int k = 0;
  for (int r = 0; r < T.outerSize(); ++r) {
    for (SparseRowMatrix::InnerIterator it(T, r); it; ++it, ++k) {
      hbirl::mdp_t& m = out[static_cast<size_t>(k / max_entries)];
      m.pair.push_back(r);
      m.next_state.push_back(static_cast<std::int32_t>(it.col()));
      m.probability.push_back(it.value());
    }
  }
  for (auto& m : out) m.num_transitions = static_cast<std::int32_t>(m.pair.size());
  return out;
}

void MdpAssembler::forget() {
  // swap, not clear: a large half-received MDP must not keep its memory
  std::vector<char>().swap(have_);
  std::vector<TransitionEntry>().swap(transitions_);
  std::vector<int>().swap(terminal_);
  start_.resize(0);
  received_ = 0;
}

std::optional<Mdp> MdpAssembler::add(const hbirl::mdp_t& m) {
  if (m.num_states < 1 || m.num_states > kMaxStates)
    throw InputError("mdp.num_states", "must be in [1, " + std::to_string(kMaxStates) + "]");
  if (m.num_actions < 1 || m.num_actions > kMaxActions) {
    throw InputError("mdp.num_actions", "must be in [1, " + std::to_string(kMaxActions) + "]");
  }
  if (static_cast<long long>(m.num_states) * m.num_actions > kMaxPairs)
    throw InputError("mdp.num_actions", "too many state-action pairs");
  if (m.num_chunks < 1 || m.num_chunks > kMaxChunks || m.chunk < 0 || m.chunk >= m.num_chunks) {
    throw InputError("mdp.chunk", std::to_string(m.chunk) + " of " + std::to_string(m.num_chunks) + " is not a chunk");
  }
  if (!(m.discount >= 0.0 && m.discount < 1.0)) throw InputError("mdp.discount", "must be in [0, 1)");
  if (m.num_start != (m.chunk == 0 ? m.num_states : 0))
    throw InputError("mdp.num_start", "must be num_states in chunk 0, else 0");
  const long long pairs = static_cast<long long>(m.num_states) * m.num_actions;
  for (int i = 0; i < m.num_transitions; ++i) {
    const auto k = static_cast<size_t>(i);
    if (m.pair[k] < 0 || m.pair[k] >= pairs || m.next_state[k] < 0 || m.next_state[k] >= m.num_states ||
        !(m.probability[k] >= 0.0 && m.probability[k] <= 1.0)) {
      throw InputError("mdp.transition[" + std::to_string(i) + "]", "pair, next state or probability out of range");
    }
  }
  const auto digest = static_cast<std::uint64_t>(m.mdp_digest);
  if (digest != digest_ || m.num_chunks != num_chunks_ || m.num_states != num_states_ ||
      m.num_actions != num_actions_ || m.discount != discount_) {
    // Another MDP: start over (a half-received one is dropped).
    digest_ = digest;
    num_chunks_ = m.num_chunks;
    num_states_ = m.num_states;
    num_actions_ = m.num_actions;
    discount_ = m.discount;
    forget();
    have_.assign(static_cast<size_t>(m.num_chunks), 0);
  }
  if (have_[static_cast<size_t>(m.chunk)]) return std::nullopt;  // a repeat
  if (static_cast<long long>(transitions_.size()) + m.num_transitions > kMaxTransitions) {
    throw InputError("mdp.num_transitions", "more than " + std::to_string(kMaxTransitions) + " in all");
  }
  have_[static_cast<size_t>(m.chunk)] = 1;
  ++received_;
  if (m.chunk == 0) {
    start_ = Eigen::Map<const Eigen::VectorXd>(m.start.data(), m.num_states);
    for (int s = 0; s < m.num_states; ++s) {
      if (m.terminal[static_cast<size_t>(s)]) terminal_.push_back(s);
    }
  }
  for (int i = 0; i < m.num_transitions; ++i) {
    const auto k = static_cast<size_t>(i);
    transitions_.push_back({m.pair[k] / m.num_actions, m.pair[k] % m.num_actions, m.next_state[k], m.probability[k]});
  }
  if (received_ < num_chunks_) return std::nullopt;
  Mdp mdp = make_mdp(num_states_, num_actions_, 0, transitions_, {}, start_, terminal_, discount_);
  forget();
  digest_ = 0;
  num_chunks_ = 0;
  mdp.validate();  // InputError naming what is wrong
  if (dynamics_digest(mdp) != digest) throw InputError("mdp.mdp_digest", "does not match the MDP received");
  return mdp;
}

}  // namespace hbirl::services
