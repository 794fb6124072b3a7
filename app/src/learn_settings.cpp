// The learning settings' schema (learn_settings.hpp): one entry per setting, in the order
// `hbirl learn --help` lists them.
#include "app/learn_settings.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

#include "learner/input_error.hpp"

namespace hbirl::app {

namespace {

using json = nlohmann::json;
using Type = Setting::Type;
constexpr long double kUnbounded = std::numeric_limits<long double>::infinity();

// A setting of `type` stored in the `T` that `field` reaches. The const_cast only reads:
// one accessor serves get and put.
template <typename T>
Setting stored_in(Type type, std::string name, std::string flag, std::string help,
                  std::function<T&(LearnSettings&)> field) {
  Setting s;
  s.name = std::move(name);
  s.flag = std::move(flag);
  s.help = std::move(help);
  s.type = type;
  s.get = [field](const LearnSettings& l) { return json(field(const_cast<LearnSettings&>(l))); };
  s.put = [field](LearnSettings& l, const json& v) { field(l) = v.get<T>(); };
  return s;
}

// A whole number in [min, max], stored in `T` (int or std::uint64_t).
template <typename T>
Setting integer(std::string name, std::string flag, std::string help, long double min, long double max,
                std::function<T&(LearnSettings&)> field) {
  Setting s = stored_in<T>(Type::kInteger, std::move(name), std::move(flag), std::move(help), std::move(field));
  s.min = min;
  s.max = max;
  return s;
}

// A finite number from min (`above_min`: excluded) up.
Setting number(std::string name, std::string flag, std::string help, long double min, bool above_min,
               std::function<double&(LearnSettings&)> field) {
  Setting s = stored_in<double>(Type::kNumber, std::move(name), std::move(flag), std::move(help), std::move(field));
  s.min = min;
  s.above_min = above_min;
  s.max = kUnbounded;
  return s;
}

Setting choice(std::string name, std::string flag, std::string help, std::vector<std::string> choices) {
  Setting s;
  s.name = std::move(name);
  s.flag = std::move(flag);
  s.help = std::move(help);
  s.type = Type::kChoice;
  s.choices = std::move(choices);
  return s;
}

// An optional setting: unset means "as the prior says" (`unset_help`). Only when learning
// from observations.
Setting unset_means(Setting s, std::string unset_help) {
  s.optional = true;
  s.group = Setting::Group::kPrior;
  s.unset_help = std::move(unset_help);
  s.hidden_data = true;
  return s;
}

Setting observations_only(Setting s) {
  s.hidden_data = true;
  return s;
}

// The posterior engine's: only from observations, and not on the optimiser (the sampler
// workers compute exact blocks).
Setting engine_setting(Setting s) {
  s.hidden_data = true;
  s.optimiser = false;
  s.group = Setting::Group::kEngine;
  return s;
}

// The posterior engine (engine_setting).
void add_engine_settings(std::vector<Setting>& schema) {
  const auto add = [&schema](Setting s) { schema.push_back(std::move(s)); };
  Setting engine = choice("engine", "--engine",
                          "Posterior engine: 'exact' (forward-backward, the source of each observation summed out) or "
                          "'mcmc' (the paper's Metropolis-within-Gibbs sampler)",
                          {"exact", "mcmc"});
  engine.get = [](const LearnSettings& l) { return json(l.engine); };
  engine.put = [](LearnSettings& l, const json& v) { l.engine = v.get<std::string>(); };
  add(engine_setting(std::move(engine)));
  // The sampler keeps every kept sweep of every chain (4 bytes a step): a million is
  // ~40 MB per chain of 10 steps.
  add(engine_setting(integer<int>("mcmc_samples", "--mcmc-samples", "MCMC: sweeps kept per chain", 1, 1e6,
                                  [](LearnSettings& l) -> int& { return l.mcmc.samples; })));
  add(engine_setting(integer<int>("mcmc_burn_in", "--mcmc-burn-in", "MCMC: sweeps discarded per chain", 0, 1e6,
                                  [](LearnSettings& l) -> int& { return l.mcmc.burn_in; })));
  add(engine_setting(integer<int>("mcmc_chains", "--mcmc-chains", "MCMC: independent chains (R-hat compares them)", 1,
                                  1000, [](LearnSettings& l) -> int& { return l.mcmc.chains; })));
}

// The M-step's optimiser, its restarts, seed and threads.
void add_optimiser_settings(std::vector<Setting>& schema) {
  const auto add = [&schema](Setting s) { schema.push_back(std::move(s)); };
  Setting optimizer = choice("optimizer", "--optimizer",
                             "M-step optimiser: 'lbfgs' (L-BFGS) or 'eg' (the paper's adaptive exponentiated gradient)",
                             {"lbfgs", "eg"});
  optimizer.get = [](const LearnSettings& l) { return json(to_string(l.em.optimizer.kind)); };
  optimizer.put = [](LearnSettings& l, const json& v) {
    l.em.optimizer.kind = v.get<std::string>() == "eg" ? OptimizerKind::kExponentiatedGradient : OptimizerKind::kLbfgs;
  };
  add(std::move(optimizer));
  add(number("l2", "--l2", "L2 penalty weight on theta, per demonstrated step", 0, false,
             [](LearnSettings& l) -> double& { return l.em.l2; }));
  // More restarts changed nothing on average on the random tasks (docs/results/random_tasks).
  Setting restarts = integer<int>(
      "restarts", "--restarts",
      "Restarts: the first from theta = 0, the others from U[-1,1]^K; the one with the highest (penalised) "
      "log-likelihood wins (the held-out log-likelihood when the prior strength is chosen from the data)",
      1, 100000, [](LearnSettings& l) -> int& { return l.em.restarts; });
  restarts.optimiser = false;  // a service's --restarts is how often its supervisor restarted it
  add(std::move(restarts));
  add(integer<std::uint64_t>("seed", "--seed", "Seed of every random choice", 0,
                             static_cast<long double>(std::numeric_limits<std::uint64_t>::max()),
                             [](LearnSettings& l) -> std::uint64_t& { return l.em.seed; }));
  Setting threads = integer<int>("threads", "--threads", "Threads (0 = one per core); the result does not depend on it",
                                 0, 4096, [](LearnSettings& l) -> int& { return l.em.threads; });
  threads.optimiser = false;  // one E-step at a time on the bus
  add(std::move(threads));
  add(integer<int>("max_iterations", "--max-iterations", "Optimiser iteration limit per M-step", 1, 1e8,
                   [](LearnSettings& l) -> int& { return l.em.optimizer.max_iterations; }));
  add(number("tolerance", "--tolerance", "The M-step has converged when ||gradient|| <= tolerance * max(1, ||theta||)",
             0, true, [](LearnSettings& l) -> double& { return l.em.optimizer.gradient_tolerance; }));
  add(number("eg_radius", "--eg-radius", "EG only: search the L1 ball ||theta||_1 <= radius", 0, true,
             [](LearnSettings& l) -> double& { return l.em.optimizer.eg_radius; }));
  add(number("eg_rate", "--eg-rate", "EG only: learning rate eta (<= 0.25 for its regret bound)", 0, true,
             [](LearnSettings& l) -> double& { return l.em.optimizer.eg_learning_rate; }));
}

// When HiddenDataEM and the observation model's refinement stop (observations only).
void add_em_settings(std::vector<Setting>& schema) {
  const auto add = [&schema](Setting s) { schema.push_back(std::move(s)); };
  add(observations_only(
      integer<int>("max_em_iterations", "--max-em-iterations",
                   "HiddenDataEM's budget of E-step + M-step evaluations (SQUAREM's rejected extrapolations count; "
                   "\"em_evaluations\" in the output)",
                   1, 1e6, [](LearnSettings& l) -> int& { return l.em.max_em_iterations; })));
  add(observations_only(
      number("em_theta_tolerance", "--em-theta-tolerance",
             "EM has converged when max|theta change| <= this * max(1, max|theta|), the log-likelihood "
             "has settled (--em-likelihood-tolerance) and O has converged",
             0, true, [](LearnSettings& l) -> double& { return l.em.theta_tolerance; })));
  add(observations_only(number("em_likelihood_tolerance", "--em-likelihood-tolerance",
                               "EM's log-likelihood has settled when it changes by <= this * max(1, |log-likelihood|)",
                               0, true, [](LearnSettings& l) -> double& { return l.em.likelihood_tolerance; })));
  add(observations_only(number("alpha_tolerance", "--alpha-tolerance",
                               "The observation model has converged when O moves less than this (docs/MODEL.md)", 0,
                               true, [](LearnSettings& l) -> double& { return l.alpha_tolerance; })));
  add(observations_only(integer<int>("max_alpha_iterations", "--max-alpha-iterations",
                                     "Observation-model refinements per E-step (EM continues until O has converged)", 1,
                                     1e6, [](LearnSettings& l) -> int& { return l.max_alpha_iterations; })));
}

// The posterior over theta (learner/reward_posterior.hpp), drawn after EM when asked; on the
// optimiser, for its live estimates' confidence (--anytime).
void add_posterior_settings(std::vector<Setting>& schema) {
  Setting samples = integer<int>(
      "posterior_samples", "--posterior-samples",
      "Draw this many samples of theta from its posterior (importance sampling around the Laplace approximation, "
      "the observation model held at what EM learned, and when learned the confidence averaged with O at the "
      "prior; 0: none) and report the confidence in the learned policy, "
      "credible intervals and the expected ILE (docs/MODEL.md \"The posterior over theta\"); the exact engine only",
      0, 1e6, [](LearnSettings& l) -> int& { return l.posterior.samples; });
  schema.push_back(std::move(samples));  // hbirl-optimiser: the confidence of its live estimates (--anytime)
  Setting scale = number("prior_scale", "--prior-scale",
                         "The posterior's Gaussian prior on each weight of theta: its standard deviation, for features "
                         "of order 1 (scale it with yours; 0: chosen from the data by the Laplace evidence over "
                         "0.25 .. 128, measured worse calibrated; docs/MODEL.md \"The posterior over theta\")",
                         0, false, [](LearnSettings& l) -> double& { return l.posterior.prior_scale; });
  schema.push_back(std::move(scale));
}

// How the observation model and eta are learned; unset, as the prior says (unset_means).
void add_prior_settings(std::vector<Setting>& schema) {
  const auto add = [&schema](Setting s) { schema.push_back(std::move(s)); };
  Setting learn_o;
  learn_o.name = "learn_observation_model";
  learn_o.flag = "--learn-observation-model";
  learn_o.help = "Refine the observation model O inside the E-step (true) or keep the prior's mean (false)";
  learn_o.type = Type::kSwitch;
  learn_o.get = [](const LearnSettings& l) {
    return l.learn_observation_model ? json(*l.learn_observation_model) : json();
  };
  learn_o.put = [](LearnSettings& l, const json& v) {
    l.learn_observation_model = v.is_null() ? std::nullopt : std::optional<bool>(v.get<bool>());
  };
  add(unset_means(std::move(learn_o), "as the prior says (true unless it was made with learn false)"));

  Setting update = choice("alpha_update", "--alpha-update",
                          "How the observation model is learned: 'posterior' (the Dirichlet posterior of the prior and "
                          "the data, the prior's weight chosen from the data; docs/MODEL.md) or 'paper' (alpha = c "
                          "alpha_dot + (1 - c) alpha, which forgets the prior at its fixed point)",
                          {"posterior", "paper"});
  update.get = [](const LearnSettings& l) {
    return l.alpha_update ? json(alpha_update_name(*l.alpha_update)) : json();
  };
  update.put = [](LearnSettings& l, const json& v) {
    AlphaUpdate u = AlphaUpdate::kPosterior;
    if (v.is_null()) {
      l.alpha_update.reset();
    } else if (parse_alpha_update(v.get<std::string>(), u)) {
      l.alpha_update = u;
    }
  };
  add(unset_means(std::move(update), "the prior's (a problem file's observation_model.update), else posterior"));

  Setting c;
  c.name = "c";
  c.flag = "--c";
  c.help = "The paper's step size c (--alpha-update paper)";
  c.type = Type::kNumber;
  c.above_min = true;
  c.max = 1;
  c.get = [](const LearnSettings& l) { return l.c ? json(*l.c) : json(); };
  c.put = [](LearnSettings& l, const json& v) {
    l.c = v.is_null() ? std::nullopt : std::optional<double>(v.get<double>());
  };
  add(unset_means(std::move(c), "the prior's, else 0.1"));

  Setting eta = choice("eta", "--eta",
                       "'stated': take every observation's eta as given; 'learned': learn it per context (the "
                       "labeller's rule, else each distinct eta; docs/MODEL.md)",
                       {"stated", "learned"});
  eta.get = [](const LearnSettings& l) { return l.learn_eta ? json(*l.learn_eta ? "learned" : "stated") : json(); };
  eta.put = [](LearnSettings& l, const json& v) {
    l.learn_eta = v.is_null() ? std::nullopt : std::optional<bool>(v.get<std::string>() == "learned");
  };
  add(unset_means(std::move(eta),
                  "the prior's (a problem file's or domain file's observation_model.learn_eta), "
                  "else learned with the posterior update"));
}

// One entry per setting, by group, in the order `hbirl learn --help` lists them.
std::vector<Setting> make_schema() {
  std::vector<Setting> schema;
  add_engine_settings(schema);
  add_optimiser_settings(schema);
  add_em_settings(schema);
  add_prior_settings(schema);
  add_posterior_settings(schema);
  return schema;
}

std::string number_text(long double x) {
  std::ostringstream out;
  out.precision(17);
  out << static_cast<double>(x);
  return out.str();
}

}  // namespace

void apply_to_prior(const LearnSettings& settings, ObservationPrior& prior) {
  if (settings.learn_observation_model) prior.learn = *settings.learn_observation_model;
  if (settings.alpha_update) use_alpha_update(prior, *settings.alpha_update);
  if (settings.c) prior.c = *settings.c;
  if (settings.learn_eta) prior.learn_eta = *settings.learn_eta;
}

const std::vector<Setting>& learn_settings_schema() {
  static const std::vector<Setting> schema = make_schema();
  return schema;
}

const Setting& learn_setting(const std::string& name) {
  for (const Setting& s : learn_settings_schema()) {
    if (s.name == name) return s;
  }
  throw InputError(name, "is not a learning setting");
}

std::string describe_range(const Setting& s) {
  switch (s.type) {
    case Type::kChoice: {
      std::string out;
      for (size_t i = 0; i < s.choices.size(); ++i)
        out += (i == 0 ? "" : i + 1 == s.choices.size() ? " or " : ", ") + s.choices[i];
      return out;
    }
    case Type::kSwitch:
      return "true or false";
    case Type::kInteger:
    case Type::kNumber:
      break;
  }
  const auto text = [&s](long double x) {
    if (s.type != Type::kInteger) return number_text(x);
    return x < 0 ? std::to_string(static_cast<std::int64_t>(x)) : std::to_string(static_cast<std::uint64_t>(x));
  };
  const std::string low = (s.above_min ? "(" : "[") + text(s.min);
  const std::string high = std::isinf(s.max) ? "inf)" : text(s.max) + "]";
  return "in " + low + ", " + high;
}

void check(const Setting& s, const json& value) {
  if (value.is_null()) {
    if (s.optional) return;
    throw InputError(s.name, "must be given (it has no 'as the prior says')");
  }
  const auto refuse = [&s](const std::string& what) { throw InputError(s.name, "must be " + what); };
  switch (s.type) {
    case Type::kChoice:
      if (!value.is_string()) refuse(describe_range(s));
      for (const std::string& c : s.choices) {
        if (value.get<std::string>() == c) return;
      }
      throw InputError(s.name, "'" + value.get<std::string>() + "' is not " + describe_range(s));
    case Type::kSwitch:
      if (!value.is_boolean()) refuse("true or false");
      return;
    case Type::kInteger: {
      if (!value.is_number_integer()) refuse("a whole number " + describe_range(s));
      const long double x = value.is_number_unsigned() ? static_cast<long double>(value.get<std::uint64_t>())
                                                       : static_cast<long double>(value.get<std::int64_t>());
      if (x < s.min || x > s.max) refuse(describe_range(s) + ", got " + value.dump());
      return;
    }
    case Type::kNumber: {
      if (!value.is_number()) refuse("a number " + describe_range(s));
      const long double x = value.get<double>();
      if (!std::isfinite(x) || x < s.min || (s.above_min && x == s.min) || x > s.max) {
        refuse("a finite number " + describe_range(s) + ", got " + value.dump());
      }
      return;
    }
  }
}

void set(LearnSettings& settings, const Setting& setting, const json& value) {
  check(setting, value);
  setting.put(settings, value);
}

void set_all(LearnSettings& settings, const json& object) {
  if (!object.is_object()) throw InputError("settings", "must be an object of setting: value");
  for (const auto& [name, value] : object.items()) set(settings, learn_setting(name), value);
}

json value_of_text(const Setting& s, const std::string& text) {
  const auto refuse = [&](const std::string& what) -> json {
    throw InputError(s.flag, "'" + text + "' is not " + what);
  };
  switch (s.type) {
    case Type::kChoice:
      return json(text);
    case Type::kSwitch:
      if (text == "true") return json(true);
      if (text == "false") return json(false);
      return refuse("true or false");
    case Type::kInteger: {
      const char* end = text.data() + text.size();
      if (!text.empty() && text[0] == '-') {
        std::int64_t v = 0;
        const auto r = std::from_chars(text.data(), end, v);
        if (r.ec != std::errc() || r.ptr != end) return refuse("a whole number");
        return json(v);
      }
      std::uint64_t v = 0;
      const auto r = std::from_chars(text.data(), end, v);
      if (r.ec != std::errc() || r.ptr != end) return refuse("a whole number");
      return json(v);
    }
    case Type::kNumber: {
      // strtod: the command line's numbers as C reads them (1e-9, 0.25, inf is refused by check).
      char* stop = nullptr;
      const double v = std::strtod(text.c_str(), &stop);
      if (text.empty() || stop != text.c_str() + text.size()) return refuse("a number");
      return json(v);
    }
  }
  return json();
}

nlohmann::ordered_json to_json(const LearnSettings& settings) {
  nlohmann::ordered_json out;
  for (const Setting& s : learn_settings_schema()) out[s.name] = s.get(settings);
  return out;
}

}  // namespace hbirl::app
