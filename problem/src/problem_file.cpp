#include "problem/problem_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <limits>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <sys/stat.h>
#include <unistd.h>

#include "json_document.hpp"
#include "problem/json_format.hpp"
#include "problem/domain_file.hpp"
#include "problem/json_node.hpp"
#include "readers.hpp"

namespace hbirl {

namespace {
// All the digits of x: 0.9999999999999999 must not read as 1 in an error line.
std::string exact(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}
}  // namespace

namespace {

// Probabilities given in a file may be rounded (1/3 as 0.333333); sums within this of 1
// are accepted and renormalised exactly.
constexpr double kFileSumTolerance = 1e-6;
constexpr long long kMaxPairs = std::numeric_limits<int>::max() / 2;
constexpr long long kMaxFeatureCells = 1LL << 28;  // (S*A) x K doubles: 2 GiB

std::string fmt(double x) {
  std::ostringstream out;
  out.precision(10);
  out << x;
  return out.str();
}

std::string pair_name(int s, int a) { return "(s=" + std::to_string(s) + ", a=" + std::to_string(a) + ")"; }

// Fails on the first entry, in the file's order, that repeats an earlier one, naming both
// (as the parser does when it reads the list, json_document.hpp).
template <typename Key>
void reject_duplicates(std::vector<std::pair<Key, size_t>> keys, const JsonNode& list, const char* what) {
  std::sort(keys.begin(), keys.end());
  size_t repeat = std::numeric_limits<size_t>::max(), first = 0;
  for (size_t i = 1; i < keys.size(); ++i) {
    if (keys[i].first == keys[i - 1].first && keys[i].second < repeat) {
      repeat = keys[i].second;
      size_t j = i - 1;
      while (j > 0 && keys[j - 1].first == keys[i].first) --j;
      first = keys[j].second;
    }
  }
  if (repeat != std::numeric_limits<size_t>::max()) {
    list[repeat].fail(std::string("duplicate ") + what + " (also given at index " + std::to_string(first) + ")");
  }
}

struct Sizes {
  int states = 0;
  int actions = 0;
  int features = 0;
};

}  // namespace

namespace detail {

// The parts of a problem (and domain) file as the parser builds them: the keys each reader
// knows, so that its warnings and what the parser builds come from one list.
const JsonShape& mdp_shape() {
  static const JsonShape transitions = JsonShape::list(kTransitionTuple), start = JsonShape::list(kStartTuple),
                         features = JsonShape::list(kFeatureTuple), impossible = JsonShape::list(kImpossibleTuple);
  static const JsonShape shape = JsonShape::object({{"num_states", nullptr},
                                                    {"num_actions", nullptr},
                                                    {"num_features", nullptr},
                                                    {"transitions", &transitions},
                                                    {"start", &start},
                                                    {"features", &features},
                                                    {"discount", nullptr},
                                                    {"terminal", nullptr},
                                                    {"impossible_actions", &impossible},
                                                    {"state_names", nullptr},
                                                    {"action_names", nullptr},
                                                    {"feature_names", nullptr}});
  return shape;
}

const JsonShape& observation_model_shape() {
  static const JsonShape subject = JsonShape::list(kSubjectAlphaTuple),
                         confounder = JsonShape::list(kConfounderAlphaTuple),
                         unlisted = JsonShape::object({{"eta", nullptr}}), end_alpha = JsonShape::list(kEndAlphaTuple),
                         end_sensor = JsonShape::object(
                             {{"num_symbols", nullptr}, {"alpha", &end_alpha}, {"alpha_default", nullptr}});
  static const JsonShape shape = JsonShape::object({{"num_symbols", nullptr},
                                                    {"num_confounders", nullptr},
                                                    {"subject_alpha", &subject},
                                                    {"subject_alpha_default", nullptr},
                                                    {"confounder_alpha", &confounder},
                                                    {"confounder_alpha_default", nullptr},
                                                    {"learn", nullptr},
                                                    {"c", nullptr},
                                                    {"update", nullptr},
                                                    {"prior_strength", nullptr},
                                                    {"learn_eta", nullptr},
                                                    {"eta_prior_strength", nullptr},
                                                    {"tie_actions", nullptr},
                                                    {"unlisted_source", &unlisted},
                                                    {"end_sensor", &end_sensor}});
  return shape;
}

namespace {

const JsonShape& step_shape() {
  static const JsonShape shape = JsonShape::object({{"observations", nullptr}});
  return shape;
}

const JsonShape& trajectory_shape() {
  static const JsonShape steps = JsonShape::list(step_shape()), truth = JsonShape::list(kTruthTuple);
  static const JsonShape shape = JsonShape::object({{"steps", &steps},
                                                    {"truth", &truth},
                                                    {"ends_in_terminal", nullptr},
                                                    {"end_state", nullptr},
                                                    {"end_symbols", nullptr},
                                                    {"controlled", nullptr}});
  return shape;
}

const JsonShape& problem_shape() {
  static const JsonShape demonstration = JsonShape::list(trajectory_shape());
  static const JsonShape shape = JsonShape::object({{"name", nullptr},
                                                    {"mdp", &mdp_shape()},
                                                    {"observation_model", &observation_model_shape()},
                                                    {"demonstration", &demonstration},
                                                    {"context_names", nullptr},
                                                    {"true_weights", nullptr}});
  return shape;
}

}  // namespace

void expect_tuple(const JsonNode& node, const TupleList& tuple) { node.expect_tuple(tuple.size, tuple.shape); }

std::vector<std::string> read_context_names(const JsonNode& node) {
  const size_t n = node.size();
  if (n == 0 || n > 65536) node.fail("has " + std::to_string(n) + " names: give 1 to 65536 (one per context, from 0)");
  std::vector<std::string> names;
  for (size_t i = 0; i < n; ++i) {
    names.push_back(node[i].as_string());
    if (names.back().empty()) node[i].fail("is empty: name context " + std::to_string(i));
  }
  return names;
}

std::string read_domain_name(const JsonNode& node) {
  const std::string name = node.as_string();
  if (const std::string wrong = domain_name_problem(name); !wrong.empty()) node.fail(wrong);
  return name;
}

std::vector<std::string> read_names(const JsonNode& node, long long expected, const char* what) {
  const size_t n = node.size();
  if (static_cast<long long>(n) != expected) {
    node.fail("has " + std::to_string(n) + " names, expected " + std::to_string(expected) + " (one per " + what + ")");
  }
  std::vector<std::string> names;
  for (size_t i = 0; i < n; ++i) names.push_back(node[i].as_string());
  return names;
}

namespace {

// "num_states", "num_actions" and "num_features", checked against what the file holds
// before anything is allocated for them: every state is terminal or has transitions, and
// every action of a non-terminal state has transitions or is impossible -- so a few bytes
// cannot declare a billion states.
Sizes read_mdp_sizes(const JsonNode& node) {
  Sizes n;
  n.states = static_cast<int>(node.at("num_states").as_int(1, std::numeric_limits<int>::max()));
  n.actions = static_cast<int>(node.at("num_actions").as_int(1, std::numeric_limits<int>::max()));
  n.features = static_cast<int>(node.at("num_features").as_int(0, std::numeric_limits<int>::max()));
  const long long pairs = static_cast<long long>(n.states) * n.actions;
  if (pairs > kMaxPairs) node.at("num_actions").fail("num_states * num_actions is too large");
  if (pairs * std::max(n.features, 1) > kMaxFeatureCells) {
    node.at("num_features").fail("num_states * num_actions * num_features is too large");
  }
  const auto listed = [&node](const char* key) -> long long {
    const auto list = node.find(key);
    return list ? static_cast<long long>(list->size()) : 0;
  };
  const long long transitions_listed = listed("transitions"), terminal_listed = listed("terminal");
  const bool has_transitions = node.has("transitions");  // when missing, that is the error to report
  if (has_transitions && n.states > transitions_listed + terminal_listed) {
    node.at("num_states")
        .fail("is " + std::to_string(n.states) + ", but the file lists only " + std::to_string(transitions_listed) +
              " transitions and " + std::to_string(terminal_listed) +
              " terminal states (each state is terminal or has transitions)");
  }
  if (has_transitions && pairs > transitions_listed + listed("impossible_actions") + terminal_listed * n.actions) {
    node.at("num_actions")
        .fail("num_states * num_actions is " + std::to_string(pairs) +
              " pairs, more than the file's transitions, impossible actions and terminal states cover");
  }
  return n;
}

// "discount"; 0.95 when absent.
double read_discount(const JsonNode& node) {
  double discount = 0.95;
  if (auto d = node.find("discount")) {
    discount = d->as_number();
    if (!(discount >= 0.0 && discount <= kMaxDiscount)) {
      d->fail("expected a number in [0, " + fmt(kMaxDiscount) + "] (a horizon of at most a million steps), got " +
              exact(discount));
    }
  }
  return discount;
}

// "terminal": the terminal states, each flagged in is_terminal too.
std::vector<int> read_terminal_states(const JsonNode& node, const Sizes& n, std::vector<char>& is_terminal) {
  std::vector<int> terminal;
  if (auto t = node.find("terminal")) {
    for (size_t i = 0; i < t->size(); ++i) {
      const int s = static_cast<int>((*t)[i].as_int(0, n.states - 1));
      terminal.push_back(s);
      is_terminal[static_cast<size_t>(s)] = 1;
    }
  }
  return terminal;
}

// "impossible_actions": a flag per (s, a).
std::vector<char> read_impossible_actions(const JsonNode& node, const Sizes& n) {
  const long long pairs = static_cast<long long>(n.states) * n.actions;
  std::vector<char> impossible(static_cast<size_t>(pairs), 0);
  if (auto list = node.find("impossible_actions")) {
    for (size_t i = 0; i < list->size(); ++i) {
      const JsonNode e = (*list)[i];
      expect_tuple(e, kImpossibleTuple);
      const int s = static_cast<int>(e[0].as_int(0, n.states - 1));
      const int a = static_cast<int>(e[1].as_int(0, n.actions - 1));
      impossible[static_cast<size_t>(s) * n.actions + a] = 1;
    }
  }
  return impossible;
}

// "transitions" [s, a, s', p]: every action of a non-terminal state has them, summing to 1
// (within kFileSumTolerance), or is impossible; each row is renormalised exactly.
std::vector<TransitionEntry> read_transitions(const JsonNode& node, const Sizes& n,
                                              const std::vector<char>& is_terminal,
                                              const std::vector<char>& impossible) {
  const long long pairs = static_cast<long long>(n.states) * n.actions;
  const JsonNode list = node.at("transitions");
  std::vector<TransitionEntry> transitions;
  std::vector<double> row_sum(static_cast<size_t>(pairs), 0.0);
  std::vector<size_t> row_first(static_cast<size_t>(pairs), std::numeric_limits<size_t>::max());
  std::vector<std::pair<std::pair<long long, int>, size_t>> keys;
  const size_t count = list.size();
  transitions.reserve(count);
  keys.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const JsonNode e = list[i];
    expect_tuple(e, kTransitionTuple);
    const int s = static_cast<int>(e[0].as_int(0, n.states - 1));
    const int a = static_cast<int>(e[1].as_int(0, n.actions - 1));
    const int s2 = static_cast<int>(e[2].as_int(0, n.states - 1));
    const double p = e[3].as_number(0.0, 1.0);
    const long long r = static_cast<long long>(s) * n.actions + a;
    if (impossible[static_cast<size_t>(r)]) {
      e.fail("gives a transition for " + pair_name(s, a) + ", which mdp.impossible_actions lists as impossible");
    }
    transitions.push_back({s, a, s2, p});
    keys.push_back({{r, s2}, i});
    row_sum[static_cast<size_t>(r)] += p;
    row_first[static_cast<size_t>(r)] = std::min(row_first[static_cast<size_t>(r)], i);
  }
  reject_duplicates(std::move(keys), list, kTransitionTuple.what);
  for (long long r = 0; r < pairs; ++r) {
    const int s = static_cast<int>(r / n.actions);
    const int a = static_cast<int>(r % n.actions);
    const size_t first = row_first[static_cast<size_t>(r)];
    if (first == std::numeric_limits<size_t>::max()) {
      if (!is_terminal[static_cast<size_t>(s)] && !impossible[static_cast<size_t>(r)]) {
        list.fail("no entries for " + pair_name(s, a) +
                  "; every action of a non-terminal state needs transitions summing to 1 "
                  "(or a place in mdp.impossible_actions)");
      }
      continue;
    }
    const double sum = row_sum[static_cast<size_t>(r)];
    if (std::abs(sum - 1.0) > kFileSumTolerance) {
      list[first].fail("probabilities for " + pair_name(s, a) + " sum to " + fmt(sum) + ", expected 1");
    }
  }
  for (auto& t : transitions) t.probability /= row_sum[static_cast<size_t>(t.state) * n.actions + t.action];
  return transitions;
}

// "start" [s, p]; by default uniform over the non-terminal states.
Eigen::VectorXd read_start(const JsonNode& node, const Sizes& n, const std::vector<char>& is_terminal) {
  Eigen::VectorXd start = Eigen::VectorXd::Zero(n.states);
  if (auto st = node.find("start")) {
    std::vector<std::pair<int, size_t>> seen;
    double sum = 0.0;
    for (size_t i = 0; i < st->size(); ++i) {
      const JsonNode e = (*st)[i];
      expect_tuple(e, kStartTuple);
      const int s = static_cast<int>(e[0].as_int(0, n.states - 1));
      const double p = e[1].as_number(0.0, 1.0);
      if (p > 0.0 && is_terminal[static_cast<size_t>(s)]) e.fail("start state " + std::to_string(s) + " is terminal");
      start[s] = p;
      sum += p;
      seen.push_back({s, i});
    }
    reject_duplicates(std::move(seen), *st, kStartTuple.what);
    if (std::abs(sum - 1.0) > kFileSumTolerance) st->fail("probabilities sum to " + fmt(sum) + ", expected 1");
    // A sum off by rounding only is kept as given (as eta's, normalise_eta), so that a
    // file written from an MDP reads back bit for bit: 25 x 0.04 is not 1 in doubles, and
    // dividing by it moved every start probability by an ulp -- and a recorded run's
    // exported problem learned another theta in the 8th digit.
    if (std::abs(sum - 1.0) > 8.0 * static_cast<double>(n.states) * std::numeric_limits<double>::epsilon())
      start /= sum;
  } else {
    const auto live = std::count(is_terminal.begin(), is_terminal.end(), 0);
    if (live == 0) node.at("terminal").fail("every state is terminal");
    for (int s = 0; s < n.states; ++s) {
      if (!is_terminal[static_cast<size_t>(s)]) start[s] = 1.0 / static_cast<double>(live);
    }
  }
  return start;
}

// "features" [s, a, k, value]; absent entries are 0.
std::vector<FeatureEntry> read_features(const JsonNode& node, const Sizes& n) {
  std::vector<FeatureEntry> features;
  if (auto fl = node.find("features")) {
    std::vector<std::pair<std::pair<long long, int>, size_t>> seen;
    for (size_t i = 0; i < fl->size(); ++i) {
      const JsonNode e = (*fl)[i];
      expect_tuple(e, kFeatureTuple);
      const int s = static_cast<int>(e[0].as_int(0, n.states - 1));
      const int a = static_cast<int>(e[1].as_int(0, n.actions - 1));
      if (n.features == 0) e[2].fail("mdp.num_features is 0, so there is no feature to set");
      const int k = static_cast<int>(e[2].as_int(0, n.features - 1));
      const double v = e[3].as_number(-kMaxFeatureMagnitude, kMaxFeatureMagnitude);
      features.push_back({s, a, k, v});
      seen.push_back({{static_cast<long long>(s) * n.actions + a, k}, i});
    }
    reject_duplicates(std::move(seen), *fl, kFeatureTuple.what);
  }
  return features;
}

}  // namespace

Mdp read_mdp(const JsonNode& node, Problem& problem, std::vector<std::string>* warnings) {
  node.check_keys(mdp_shape().keys(), warnings);
  const Sizes n = read_mdp_sizes(node);
  const double discount = read_discount(node);
  std::vector<char> is_terminal(static_cast<size_t>(n.states), 0);
  const std::vector<int> terminal = read_terminal_states(node, n, is_terminal);
  const std::vector<char> impossible = read_impossible_actions(node, n);
  const std::vector<TransitionEntry> transitions = read_transitions(node, n, is_terminal, impossible);
  const Eigen::VectorXd start = read_start(node, n, is_terminal);
  const std::vector<FeatureEntry> features = read_features(node, n);
  if (auto names = node.find("state_names")) problem.state_names = read_names(*names, n.states, "state");
  if (auto names = node.find("action_names")) problem.action_names = read_names(*names, n.actions, "action");
  if (auto names = node.find("feature_names")) problem.feature_names = read_names(*names, n.features, "feature");

  Mdp mdp = make_mdp(n.states, n.actions, n.features, transitions, features, start, terminal, discount);
  mdp.validate();  // anything left (e.g. a non-terminal state whose actions are all impossible)
  return mdp;
}

namespace {

// The Dirichlet parameters: subject_alpha_default and confounder_alpha_default (1 when
// absent) and the entries subject_alpha and confounder_alpha list.
void read_alphas(const JsonNode& node, const Mdp& mdp, ObservationPrior& prior) {
  double subject_default = 1.0;
  if (auto d = node.find("subject_alpha_default")) subject_default = d->as_number(0.0, 1e300);
  double confounder_default = 1.0;
  if (auto d = node.find("confounder_alpha_default")) confounder_default = d->as_number(0.0, 1e300);
  prior.subject_alpha_base = subject_default;
  prior.subject_alpha = Eigen::MatrixXd::Constant(mdp.num_pairs(), prior.num_symbols, subject_default);
  prior.confounder_alpha = Eigen::MatrixXd::Constant(prior.num_confounders, prior.num_symbols, confounder_default);
  if (auto list = node.find("subject_alpha")) {
    for (size_t i = 0; i < list->size(); ++i) {
      const JsonNode e = (*list)[i];
      expect_tuple(e, kSubjectAlphaTuple);
      const int s = static_cast<int>(e[0].as_int(0, mdp.num_states - 1));
      const int a = static_cast<int>(e[1].as_int(0, mdp.num_actions - 1));
      const int w = static_cast<int>(e[2].as_int(0, prior.num_symbols - 1));
      prior.subject_alpha(mdp.pair(s, a), w) = e[3].as_number(0.0, 1e300);
    }
  }
  if (auto list = node.find("confounder_alpha")) {
    for (size_t i = 0; i < list->size(); ++i) {
      const JsonNode e = (*list)[i];
      expect_tuple(e, kConfounderAlphaTuple);
      if (prior.num_confounders == 0) e[0].fail("observation_model.num_confounders is 0");
      const int c = static_cast<int>(e[0].as_int(0, prior.num_confounders - 1));
      const int w = static_cast<int>(e[1].as_int(0, prior.num_symbols - 1));
      prior.confounder_alpha(c, w) = e[2].as_number(0.0, 1e300);
    }
  }
}

// The Dirichlet mean needs a positive total per distribution.
void check_alpha_totals(const JsonNode& node, const Mdp& mdp, const ObservationPrior& prior) {
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) {
      if (mdp.is_terminal(s) || !mdp.available(s, a)) continue;
      if (!(prior.subject_alpha.row(mdp.pair(s, a)).sum() > 0.0)) {
        node.at("subject_alpha")
            .fail("alpha of " + pair_name(s, a) + " sums to 0; set a positive entry or subject_alpha_default");
      }
    }
  }
  for (int c = 0; c < prior.num_confounders; ++c) {
    if (!(prior.confounder_alpha.row(c).sum() > 0.0)) {
      (node.has("confounder_alpha") ? node.at("confounder_alpha") : node)
          .fail("alpha of confounder " + std::to_string(c) +
                " sums to 0; set a positive entry or confounder_alpha_default");
    }
  }
}

// The end sensor (docs/MODEL.md "Sensors that see the end"): its alphabet and the
// Dirichlet prior of O_end(s) for each terminal state s (alpha_default, 1 when absent, then
// the entries listed); the other states' rows stay 0 (never used).
void read_end_sensor(const JsonNode& node, const Mdp& mdp, ObservationPrior& prior) {
  if (std::find(mdp.terminal.begin(), mdp.terminal.end(), 1) == mdp.terminal.end())
    node.fail("is given, but the MDP has no terminal states for it to see");
  const JsonNode count = node.at("num_symbols");
  const int K = static_cast<int>(count.as_int(1, kMaxEndSymbols));
  if (static_cast<long long>(mdp.num_states) * K > kMaxFeatureCells)
    count.fail("num_states * num_symbols is more than the " + std::to_string(kMaxFeatureCells) + " cells allowed");
  double fallback = 1.0;
  if (auto d = node.find("alpha_default")) fallback = d->as_number(0.0, 1e300);
  prior.end_alpha_base = fallback;
  prior.end_alpha = Eigen::MatrixXd::Zero(mdp.num_states, K);
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) prior.end_alpha.row(s).setConstant(fallback);
  }
  if (auto list = node.find("alpha")) {
    for (size_t i = 0; i < list->size(); ++i) {
      const JsonNode e = (*list)[i];
      expect_tuple(e, kEndAlphaTuple);
      const int s = static_cast<int>(e[0].as_int(0, mdp.num_states - 1));
      if (!mdp.is_terminal(s))
        e[0].fail("state " + std::to_string(s) + " is not terminal; the end sensor sees only those");
      const int w = static_cast<int>(e[1].as_int(0, K - 1));
      prior.end_alpha(s, w) = e[2].as_number(0.0, 1e300);
    }
  }
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s) && !(prior.end_alpha.row(s).sum() > 0.0))
      (node.has("alpha") ? node.at("alpha") : node)
          .fail("alpha of terminal state " + std::to_string(s) + " sums to 0; set a positive entry or alpha_default");
  }
}

// How the prior is learned: learn, update, c, learn_eta, eta_prior_strength, tie_actions,
// unlisted_source and prior_strength.
void read_learning_options(const JsonNode& node, ObservationPrior& prior, std::vector<std::string>* warnings) {
  if (auto l = node.find("learn")) prior.learn = l->as_bool();
  if (auto u = node.find("update")) {
    AlphaUpdate update = AlphaUpdate::kPosterior;
    if (!parse_alpha_update(u->as_string(), update))
      u->fail("expected \"posterior\" or \"paper\", got \"" + u->as_string() + "\"");
    use_alpha_update(prior, update);
  }
  if (auto c = node.find("c")) {
    prior.c = c->as_number();
    if (!(prior.c > 0.0 && prior.c <= 1.0)) c->fail("expected a number in (0, 1], got " + fmt(prior.c));
  }
  if (auto l = node.find("learn_eta")) prior.learn_eta = l->as_bool();
  if (auto k = node.find("eta_prior_strength")) {
    prior.eta_strength = k->as_number();
    if (!(prior.eta_strength > 0.0 && prior.eta_strength <= 1e12))
      k->fail("expected a number in (0, 1e12], got " + fmt(prior.eta_strength));
  }
  if (auto t = node.find("tie_actions")) prior.tie_actions = t->as_bool();
  if (auto u = node.find("unlisted_source")) {
    u->check_keys({"eta"}, warnings);  // as observation_model_shape()
    const JsonNode eta = u->at("eta");
    prior.unlisted_eta = eta.as_number();
    if (!(prior.unlisted_eta > 0.0 && prior.unlisted_eta < 1.0))
      eta.fail("expected a number in (0, 1), got " + fmt(prior.unlisted_eta));
  }
  if (auto strength = node.find("prior_strength")) {
    if (strength->is_string()) {
      if (strength->as_string() != "auto")
        strength->fail("expected \"auto\" or a positive number, got \"" + strength->as_string() + "\"");
    } else {
      const double s = strength->as_number(ObservationPrior::kMinStrength, ObservationPrior::kMaxStrength);
      prior.automatic_strength = false;
      prior.strength = s;
    }
  }
}

}  // namespace

ObservationPrior read_observation_model(const JsonNode& node, const Mdp& mdp, std::vector<std::string>* warnings) {
  node.check_keys(observation_model_shape().keys(), warnings);
  ObservationPrior prior;
  prior.num_symbols = static_cast<int>(node.at("num_symbols").as_int(1, 1 << 20));
  prior.num_confounders = static_cast<int>(node.at("num_confounders").as_int(0, 1 << 16));
  // O is (|S||A| + |E|) x |W| doubles, and the E-step holds a few of its size: bounded
  // before it is allocated.
  if ((static_cast<long long>(mdp.num_pairs()) + prior.num_confounders) * prior.num_symbols > kMaxFeatureCells) {
    node.at("num_symbols")
        .fail("(num_states * num_actions + num_confounders) * num_symbols is " +
              std::to_string((static_cast<long long>(mdp.num_pairs()) + prior.num_confounders) * prior.num_symbols) +
              " cells, more than the " + std::to_string(kMaxFeatureCells) + " (2 GiB) an observation model may take");
  }
  read_alphas(node, mdp, prior);
  check_alpha_totals(node, mdp, prior);
  if (auto end = node.find("end_sensor")) read_end_sensor(*end, mdp, prior);
  read_learning_options(node, prior, warnings);
  return prior;
}

Eigen::VectorXd read_true_weights(const JsonNode& node, const Mdp& mdp) {
  const size_t k = node.size();
  if (static_cast<int>(k) != mdp.num_features()) {
    node.fail("has " + std::to_string(k) + " entries, expected " + std::to_string(mdp.num_features()) +
              " (mdp.num_features)");
  }
  Eigen::VectorXd w(static_cast<Eigen::Index>(k));
  for (size_t i = 0; i < k; ++i)
    w[static_cast<Eigen::Index>(i)] = node[i].as_number(-kMaxFeatureMagnitude, kMaxFeatureMagnitude);
  return w;
}

namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string too_large() {
  return "more than " + std::to_string(kMaxFileBytes >> 20) + " MB: not a problem file (or too large for one)";
}

struct Descriptor {
  int fd;
  ~Descriptor() { ::close(fd); }
};

}  // namespace

std::string read_text_file(const std::string& path) {
  // Only a regular file is read: opened without waiting (a FIFO's open would block until
  // a writer came) and checked before a byte is read (a device such as /dev/zero never ends).
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    struct stat st {};
    if (error == ENXIO && ::stat(path.c_str(), &st) == 0)
      throw FileError(std::string("is ") + kind_of(st.st_mode) + ", not a regular file");
    throw FileError("cannot open: " + std::string(std::strerror(error)));
  }
  const Descriptor closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw FileError("cannot read: " + std::string(std::strerror(errno)));
  if (!S_ISREG(st.st_mode)) throw FileError(std::string("is ") + kind_of(st.st_mode) + ", not a regular file");
  if (static_cast<std::uintmax_t>(st.st_size) > kMaxFileBytes) throw FileError(too_large());
  // The bound holds while reading too (the file may grow); its size is reserved, so the
  // text is copied once.
  std::string text;
  text.reserve(static_cast<size_t>(st.st_size));
  std::vector<char> block(1 << 16);
  for (;;) {
    const ssize_t n = ::read(fd, block.data(), block.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw FileError("cannot read: " + std::string(std::strerror(errno)));
    if (n == 0) break;
    text.append(block.data(), static_cast<size_t>(n));
    if (text.size() > kMaxFileBytes) throw FileError(too_large());
  }
  return text;
}

}  // namespace detail

namespace {

using detail::read_mdp;
using detail::read_observation_model;

// `learn_eta: true`, said explicitly, needs an eta to learn: observations, and a source
// besides the subject (a listed confounder or the unlisted catch-all).
void check_eta_can_be_learned(const JsonNode& root, const Problem& problem) {
  const std::optional<JsonNode> om = root.find("observation_model");
  const std::optional<JsonNode> flag = om ? om->find("learn_eta") : std::nullopt;
  if (!flag || !problem.observation_model->learn_eta) return;
  const ObservationPrior& prior = *problem.observation_model;
  if (prior.num_confounders == 0 && prior.unlisted_eta == 0.0) {
    flag->fail("is true, but there is one source (num_confounders 0, no unlisted_source): no eta to learn");
  }
  const bool observed = std::any_of(
      problem.demonstration.begin(), problem.demonstration.end(),
      [](const DemonstratedTrajectory& t) { return !t.controlled && t.steps && t.steps->num_observations() > 0; });
  if (!observed) flag->fail("is true, but no demonstrated step has observations: no eta to learn");
}

ObservedTrajectory read_steps(const JsonNode& steps, const std::optional<ObservationPrior>& prior,
                              std::vector<std::string>* warnings) {
  ObservedTrajectory out;
  const size_t length = steps.size();
  if (length == 0) steps.fail("is empty; a trajectory needs at least one step");
  // First pass: count, so the flat arrays are allocated once.
  size_t total = 0;
  for (size_t t = 0; t < length; ++t) {
    const JsonNode step = steps[t];
    step.check_keys(detail::step_shape().keys(), warnings);
    total += step.at("observations").size();
  }
  if (total > 0 && !prior) {
    steps.fail("has observations but the file has no observation_model");
  }
  const int sources = prior ? 1 + prior->num_confounders : 1;
  out.symbols.reserve(total);
  out.eta.resize(static_cast<Eigen::Index>(total), sources);
  out.step_begin.reserve(length + 1);
  Eigen::Index row = 0;
  for (size_t t = 0; t < length; ++t) {
    const JsonNode list = steps[t].at("observations");
    for (size_t n = 0; n < list.size(); ++n) {
      const JsonNode obs = list[n];
      // [symbol, eta] or [symbol, eta, context]; a trajectory gives contexts to all its observations or none.
      const bool with_context = obs.raw().is_array() && obs.raw().size() == 3;
      obs.expect_tuple(with_context ? 3 : 2, "[symbol, [eta...]] or [symbol, [eta...], context]");
      if (with_context != (row == 0 ? with_context : !out.contexts.empty())) {
        obs.fail(with_context ? "has a context, the trajectory's earlier observations none"
                              : "has no context, the trajectory's earlier observations one each");
      }
      if (with_context) out.contexts.push_back(static_cast<int>(obs[2].as_int(0, kMaxContexts - 1)));
      const int symbol = static_cast<int>(obs[0].as_int(0, prior->num_symbols - 1));
      const JsonNode eta = obs[1];
      const size_t m = eta.size();
      if (static_cast<int>(m) != sources) {
        obs.fail("eta has " + std::to_string(m) + " entries, expected " + std::to_string(sources) +
                 " (the subject and " + std::to_string(prior->num_confounders) + " confounders)");
      }
      for (size_t j = 0; j < m; ++j) out.eta(row, static_cast<Eigen::Index>(j)) = eta[j].as_number(0.0, 1.0);
      const std::string wrong = normalise_eta(out.eta.row(row).data(), static_cast<int>(m), kFileSumTolerance);
      if (!wrong.empty()) obs.fail("eta " + wrong);
      out.symbols.push_back(symbol);
      ++row;
    }
    out.step_begin.push_back(static_cast<int>(row));
  }
  return out;
}

Trajectory read_truth(const JsonNode& node, const Mdp& mdp) {
  Trajectory truth;
  const size_t length = node.size();
  if (length == 0) node.fail("is empty; a trajectory needs at least one step");
  for (size_t t = 0; t < length; ++t) {
    const JsonNode e = node[t];
    detail::expect_tuple(e, detail::kTruthTuple);
    const int s = static_cast<int>(e[0].as_int(0, mdp.num_states - 1));
    const int a = static_cast<int>(e[1].as_int(0, mdp.num_actions - 1));
    if (mdp.is_terminal(s)) {
      e.fail("state " + std::to_string(s) + " is terminal; a trajectory ends when it enters a terminal state");
    }
    if (!mdp.available(s, a)) e.fail("action " + std::to_string(a) + " is impossible in state " + std::to_string(s));
    if (t > 0) {
      const StateAction prev = truth.back();
      if (mdp.transitions.coeff(mdp.pair(prev.state, prev.action), s) <= 0.0) {
        e.fail("state " + std::to_string(s) + " cannot follow " + pair_name(prev.state, prev.action));
      }
    }
    truth.push_back({s, a});
  }
  return truth;
}

// What was seen of how a trajectory ended: "end_state" (the terminal state entered, known
// for certain) and "end_symbols" (an end sensor's reports of it). Both need "steps" (they
// are observations) and a trajectory that ended in a terminal state.
void read_end(const JsonNode& item, const Problem& problem, DemonstratedTrajectory& trajectory) {
  const std::optional<JsonNode> state = item.find("end_state"), symbols = item.find("end_symbols");
  for (const auto& node : {state, symbols}) {
    if (!node) continue;
    if (!trajectory.steps) node->fail("needs \"steps\": it is what was observed of the end");
    if (!trajectory.ends_in_terminal) node->fail("is given, but the trajectory does not end in a terminal state");
    if (trajectory.controlled) node->fail("a controlled run's end is not used (give it in a demonstration)");
  }
  if (state) {
    const int s = static_cast<int>(state->as_int(0, problem.mdp.num_states - 1));
    if (!problem.mdp.is_terminal(s)) state->fail("state " + std::to_string(s) + " is not terminal");
    if (trajectory.truth) {
      const StateAction last = trajectory.truth->back();
      if (!(problem.mdp.transitions.coeff(problem.mdp.pair(last.state, last.action), s) > 0.0))
        state->fail("state " + std::to_string(s) + " cannot follow the truth's last step " +
                    pair_name(last.state, last.action));
    }
    trajectory.steps->end_state = s;
  }
  if (symbols) {
    const int K = problem.observation_model ? problem.observation_model->num_end_symbols() : 0;
    if (K == 0) symbols->fail("is given, but observation_model has no \"end_sensor\"");
    if (symbols->size() > static_cast<size_t>(kMaxEndReports))
      symbols->fail("has " + std::to_string(symbols->size()) + " reports, more than the " +
                    std::to_string(kMaxEndReports) + " one ending may have");
    for (size_t k = 0; k < symbols->size(); ++k)
      trajectory.steps->end_symbols.push_back(static_cast<int>((*symbols)[k].as_int(0, K - 1)));
  }
}

Problem parse_document(const nlohmann::json& doc, std::vector<std::string>* warnings) {
  const JsonNode root(doc, "");
  if (!doc.is_object()) root.fail("the problem file must be a JSON object");
  root.check_keys(detail::problem_shape().keys(), warnings);
  Problem problem;
  if (auto n = root.find("name")) problem.name = detail::read_domain_name(*n);
  problem.mdp = read_mdp(root.at("mdp"), problem, warnings);
  if (auto om = root.find("observation_model")) {
    problem.observation_model = read_observation_model(*om, problem.mdp, warnings);
  }
  if (auto names = root.find("context_names")) problem.context_names = detail::read_context_names(*names);
  const bool has_terminal =
      std::find(problem.mdp.terminal.begin(), problem.mdp.terminal.end(), 1) != problem.mdp.terminal.end();
  const JsonNode demo = root.at("demonstration");
  const size_t count = demo.size();
  if (count == 0) demo.fail("is empty; give at least one trajectory");
  for (size_t i = 0; i < count; ++i) {
    const JsonNode item = demo[i];
    item.check_keys(detail::trajectory_shape().keys(), warnings);
    DemonstratedTrajectory trajectory;
    trajectory.ends_in_terminal = has_terminal;
    if (auto e = item.find("ends_in_terminal")) {
      trajectory.ends_in_terminal = e->as_bool();
      if (trajectory.ends_in_terminal && !has_terminal) e->fail("is true but the MDP has no terminal states");
    }
    if (auto steps = item.find("steps")) {
      trajectory.steps = read_steps(*steps, problem.observation_model, warnings);
      trajectory.steps->ends_in_terminal = trajectory.ends_in_terminal;
    }
    if (auto truth = item.find("truth")) {
      trajectory.truth = read_truth(*truth, problem.mdp);
      if (trajectory.ends_in_terminal) {
        const StateAction last = trajectory.truth->back();
        double exit = 0.0;
        for (SparseRowMatrix::InnerIterator it(problem.mdp.transitions, problem.mdp.pair(last.state, last.action)); it;
             ++it) {
          if (problem.mdp.is_terminal(static_cast<int>(it.col()))) exit += it.value();
        }
        if (exit <= 0.0) {
          item.at("truth").fail("ends with (s=" + std::to_string(last.state) + ", a=" + std::to_string(last.action) +
                                "), which cannot enter a terminal state; set \"ends_in_terminal\": false for a "
                                "trajectory that was cut off");
        }
      }
    }
    if (!trajectory.steps && !trajectory.truth) item.fail("has neither \"steps\" nor \"truth\"");
    if (auto c = item.find("controlled")) {
      trajectory.controlled = c->as_bool();
      if (trajectory.controlled && (!trajectory.steps || !trajectory.truth)) {
        c->fail(
            "a controlled-run trajectory needs both \"steps\" and \"truth\" (its prior counts symbols per true step)");
      }
    }
    read_end(item, problem, trajectory);  // (after "controlled": a controlled run's end is not read)
    if (trajectory.steps && trajectory.truth &&
        static_cast<size_t>(trajectory.steps->length()) != trajectory.truth->size()) {
      item.at("truth").fail("has " + std::to_string(trajectory.truth->size()) + " steps but \"steps\" has " +
                            std::to_string(trajectory.steps->length()));
    }
    problem.demonstration.push_back(std::move(trajectory));
  }
  check_eta_can_be_learned(root, problem);
  if (auto tw = root.find("true_weights")) problem.true_weights = detail::read_true_weights(*tw, problem.mdp);
  return problem;
}

}  // namespace

std::vector<Trajectory> Problem::truth_trajectories() const {
  std::vector<Trajectory> out;
  for (size_t i = 0; i < demonstration.size(); ++i) {
    if (demonstration[i].controlled) continue;
    if (!demonstration[i].truth) {
      throw InputError("demonstration[" + std::to_string(i) + "].truth",
                       "missing (learning from the truth needs it for every trajectory)");
    }
    out.push_back(*demonstration[i].truth);
  }
  return out;
}

Problem parse_problem(const std::string& text, std::vector<std::string>* warnings) {
  return parse_document(detail::parse_json_text(text, detail::problem_shape()), warnings);
}

Problem read_problem_file(const std::string& path, std::vector<std::string>* warnings) {
  // The text is let go once its document is built.
  const nlohmann::json doc = detail::parse_json_text(detail::read_text_file(path), detail::problem_shape());
  return parse_document(doc, warnings);
}

namespace {

using OrderedJson = nlohmann::ordered_json;

// "mdp" as the reader takes it (read_mdp).
OrderedJson mdp_to_json(const Problem& problem) {
  using J = OrderedJson;
  const Mdp& mdp = problem.mdp;
  J m;
  m["num_states"] = mdp.num_states;
  m["num_actions"] = mdp.num_actions;
  m["num_features"] = mdp.num_features();
  m["discount"] = mdp.discount;
  if (!problem.state_names.empty()) m["state_names"] = problem.state_names;
  if (!problem.action_names.empty()) m["action_names"] = problem.action_names;
  if (!problem.feature_names.empty()) m["feature_names"] = problem.feature_names;
  J terminal = J::array();
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) terminal.push_back(s);
  }
  if (!terminal.empty()) m["terminal"] = terminal;
  J impossible = J::array();
  J transitions = J::array();
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) {
      const int r = mdp.pair(s, a);
      if (!mdp.is_terminal(s) && !mdp.available(s, a)) impossible.push_back({s, a});
      for (SparseRowMatrix::InnerIterator it(mdp.transitions, r); it; ++it) {
        transitions.push_back({s, a, it.col(), it.value()});
      }
    }
  }
  if (!impossible.empty()) m["impossible_actions"] = impossible;
  m["transitions"] = transitions;
  J start = J::array();
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.start[s] > 0.0) start.push_back({s, mdp.start[s]});
  }
  m["start"] = start;
  J features = J::array();
  for (int r = 0; r < mdp.num_pairs(); ++r) {
    for (int k = 0; k < mdp.num_features(); ++k) {
      if (mdp.features(r, k) != 0.0) {
        features.push_back({r / mdp.num_actions, r % mdp.num_actions, k, mdp.features(r, k)});
      }
    }
  }
  m["features"] = features;
  return m;
}

// "observation_model" as the reader takes it (read_observation_model).
OrderedJson observation_model_to_json(const ObservationPrior& p, const Mdp& mdp) {
  using J = OrderedJson;
  J om;
  om["num_symbols"] = p.num_symbols;
  om["num_confounders"] = p.num_confounders;
  J sa = J::array();
  for (int r = 0; r < p.subject_alpha.rows(); ++r) {
    for (int w = 0; w < p.num_symbols; ++w) {
      sa.push_back({r / mdp.num_actions, r % mdp.num_actions, w, p.subject_alpha(r, w)});
    }
  }
  om["subject_alpha"] = sa;
  J ca = J::array();
  for (int c = 0; c < p.num_confounders; ++c) {
    for (int w = 0; w < p.num_symbols; ++w) ca.push_back({c, w, p.confounder_alpha(c, w)});
  }
  om["confounder_alpha"] = ca;
  om["subject_alpha_default"] = p.subject_alpha_base;
  om["learn"] = p.learn;
  om["update"] = alpha_update_name(p.update);
  // Only when it differs from the update's default: said explicitly, it must have an eta to learn.
  if (p.learn_eta != (p.update == AlphaUpdate::kPosterior)) om["learn_eta"] = p.learn_eta;
  om["eta_prior_strength"] = p.eta_strength;
  if (p.tie_actions) om["tie_actions"] = true;  // only when on: files without it stay as they were
  if (p.unlisted_eta > 0.0) om["unlisted_source"] = J{{"eta", p.unlisted_eta}};
  om["c"] = p.c;
  if (p.automatic_strength) {
    om["prior_strength"] = "auto";
  } else {
    om["prior_strength"] = p.strength;
  }
  if (p.num_end_symbols() > 0) {
    J alpha = J::array();
    for (int s = 0; s < mdp.num_states; ++s) {
      if (!mdp.is_terminal(s)) continue;
      for (int w = 0; w < p.num_end_symbols(); ++w) alpha.push_back({s, w, p.end_alpha(s, w)});
    }
    om["end_sensor"] = J{{"num_symbols", p.num_end_symbols()}, {"alpha", alpha}, {"alpha_default", p.end_alpha_base}};
  }
  return om;
}

// One trajectory of "demonstration"; ends_in_terminal is written only when it is not the
// default (has_terminal: the MDP has terminal states).
OrderedJson trajectory_to_json(const DemonstratedTrajectory& trajectory, bool has_terminal) {
  using J = OrderedJson;
  J item = J::object();  // an object even when there is nothing to say (write_problem's layout)
  if (has_terminal && !trajectory.ends_in_terminal) item["ends_in_terminal"] = false;
  if (trajectory.controlled) item["controlled"] = true;
  if (trajectory.steps) {
    const ObservedTrajectory& o = *trajectory.steps;
    if (o.end_state >= 0) item["end_state"] = o.end_state;
    if (!o.end_symbols.empty()) item["end_symbols"] = o.end_symbols;
    J steps = J::array();
    for (int t = 0; t < o.length(); ++t) {
      J observations = J::array();
      for (int i = o.step_begin[static_cast<size_t>(t)]; i < o.step_begin[static_cast<size_t>(t) + 1]; ++i) {
        std::vector<double> eta(o.eta.row(i).data(), o.eta.row(i).data() + o.eta.cols());
        J observation = J::array({o.symbols[static_cast<size_t>(i)], eta});
        if (!o.contexts.empty()) observation.push_back(o.contexts[static_cast<size_t>(i)]);
        observations.push_back(std::move(observation));
      }
      steps.push_back(J{{"observations", observations}});
    }
    item["steps"] = steps;
  }
  if (trajectory.truth) {
    J truth = J::array();
    for (const auto& step : *trajectory.truth) truth.push_back({step.state, step.action});
    item["truth"] = truth;
  }
  return item;
}

// The fields before "demonstration" and after it, in the file's order.
OrderedJson problem_head_json(const Problem& problem) {
  OrderedJson doc = OrderedJson::object();
  if (!problem.name.empty()) doc["name"] = problem.name;
  doc["mdp"] = mdp_to_json(problem);
  if (problem.observation_model)
    doc["observation_model"] = observation_model_to_json(*problem.observation_model, problem.mdp);
  return doc;
}

OrderedJson problem_tail_json(const Problem& problem) {
  OrderedJson doc = OrderedJson::object();
  if (!problem.context_names.empty()) doc["context_names"] = problem.context_names;
  if (problem.true_weights) {
    doc["true_weights"] =
        std::vector<double>(problem.true_weights->data(), problem.true_weights->data() + problem.true_weights->size());
  }
  return doc;
}

bool has_terminal_states(const Mdp& mdp) {
  return std::find(mdp.terminal.begin(), mdp.terminal.end(), 1) != mdp.terminal.end();
}

}  // namespace

nlohmann::ordered_json problem_to_json(const Problem& problem) {
  OrderedJson doc = problem_head_json(problem);
  OrderedJson demo = OrderedJson::array();
  const bool has_terminal = has_terminal_states(problem.mdp);
  for (const auto& trajectory : problem.demonstration) demo.push_back(trajectory_to_json(trajectory, has_terminal));
  doc["demonstration"] = std::move(demo);
  doc.update(problem_tail_json(problem));
  return doc;
}

void write_problem(std::ostream& out, const Problem& problem, const nlohmann::ordered_json& before,
                   const nlohmann::ordered_json& after) {
  // format_json's text of the whole document (tested byte for byte), with "demonstration"
  // written a trajectory at a time: only one trajectory's JSON is ever built.
  constexpr size_t kFlushBytes = 1 << 20;
  std::string text = "{\n";
  bool first = true;
  const auto flush = [&] {
    if (out) out.write(text.data(), static_cast<std::streamsize>(text.size()));
    text.clear();
  };
  const auto key = [&](const std::string& name) {
    if (!first) text += ",\n";
    first = false;
    text += "  " + OrderedJson(name).dump() + ": ";
  };
  const auto fields = [&](const OrderedJson& object) {
    for (const auto& item : object.items()) {
      key(item.key());
      format_json_into(item.value(), 2, text);
      if (text.size() >= kFlushBytes) flush();
    }
  };
  const OrderedJson body = problem_head_json(problem);
  const OrderedJson tail = problem_tail_json(problem);
  // One key twice would be a file parse_problem refuses: a caller's mistake, said at once.
  std::set<std::string> keys = {"demonstration"};
  for (const OrderedJson* part : {&before, &body, &tail, &after}) {
    if (!part->is_object()) continue;
    for (const auto& item : part->items()) {
      if (!keys.insert(item.key()).second)
        throw std::logic_error("write_problem: the key \"" + item.key() + "\" would appear twice");
    }
  }
  if (before.is_object()) fields(before);
  fields(body);
  key("demonstration");
  if (problem.demonstration.empty()) {
    text += "[]";
  } else {
    // A trajectory is an object, never packed: one after the other, each on its own lines.
    const bool has_terminal = has_terminal_states(problem.mdp);
    text += "[\n    ";
    for (size_t i = 0; i < problem.demonstration.size(); ++i) {
      if (i > 0) text += ",\n    ";
      format_json_into(trajectory_to_json(problem.demonstration[i], has_terminal), 4, text);
      if (text.size() >= kFlushBytes) {
        flush();
        if (!out) return;  // the disk is full or the reader gone: the caller says so
      }
    }
    text += "\n  ]";
  }
  fields(tail);
  if (after.is_object()) fields(after);
  text += "\n}\n";
  flush();
}

}  // namespace hbirl
