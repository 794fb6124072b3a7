#include "learner/hidden_data_em.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "learner/input_error.hpp"
#include "learner/maxcausalent.hpp"
#include "learner/parallel.hpp"

namespace hbirl {

namespace {

// Largest SQUAREM step length (it grows 4x while the longest step keeps being accepted).
constexpr double kMaxStep = 1024.0;

// The EM map of HiddenDataEM: from (theta, alpha), an E-step (which also refines alpha
// once or more) and an M-step warm-started at theta.
class EmMap {
 public:
  struct Point {
    Eigen::VectorXd theta;
    std::optional<ObservationPrior> alpha;
  };
  struct Step {
    Point next;
    double objective = 0.0;  // EM's objective at the input point (EStepResult::objective)
    EStepResult e;
    OptimizeResult m;
  };

  EmMap(const Mdp& mdp, const EStep& estep, const LearnOptions& options, std::uint64_t seed)
      : mdp_(mdp), estep_(estep), options_(options), solver_(mdp, options.soft_vi), state_(estep.initial_state(seed)) {}

  Point start(const Eigen::VectorXd& theta) const { return {theta, state_.alpha}; }

  // The E-step alone: log-likelihood and counts at x (alpha refined into `refined`).
  EStepResult expect(const Point& x, std::optional<ObservationPrior>& refined) {
    state_.alpha = x.alpha;
    EStepResult e = estep_.expect(solver_.solve(mdp_.reward(x.theta)), state_);
    refined = state_.alpha;
    return e;
  }

  Step operator()(const Point& x) {
    Step step;
    step.e = expect(x, step.next.alpha);
    step.objective = step.e.objective;
    ++evaluations_;
    if (!std::isfinite(step.objective) || !(step.e.counts.sum() > 0.0)) {
      // Nowhere to go from a point where the data are impossible (an extrapolation that
      // overshot): report it and stay put; callers reject it.
      step.objective = -std::numeric_limits<double>::infinity();
      step.next = x;
      step.m.x = x.theta;
      step.m.status = "E-step found the data impossible at this point";
      return step;
    }
    CausalLikelihood objective(mdp_, step.e.counts, options_.l2, options_.soft_vi);
    objective.warm_start(solver_.solution());  // the E-step solved at x.theta, where the M-step starts
    const Objective f = [&objective](const Eigen::VectorXd& t, Eigen::VectorXd& g) {
      return objective.evaluate(t, &g);
    };
    step.m = maximize(f, x.theta, options_.optimizer);
    step.next.theta = step.m.x;
    optimizer_iterations_ += step.m.iterations;
    return step;
  }

  // log Pr(data | theta, mean of alpha) at x, for the report.
  double data_log_likelihood(const Point& x) {
    state_.alpha = x.alpha;
    return estep_.data_log_likelihood(solver_.solve(mdp_.reward(x.theta)), state_);
  }

  std::optional<StrengthChoice> choose_strength(const Point& x) {
    state_.alpha = x.alpha;
    return estep_.choose_strength(solver_.solve(mdp_.reward(x.theta)), state_);
  }

  int evaluations() const { return evaluations_; }
  int optimizer_iterations() const { return optimizer_iterations_; }

 private:
  const Mdp& mdp_;
  const EStep& estep_;
  const LearnOptions& options_;
  SoftBellmanSolver solver_;
  EStepState state_;
  int evaluations_ = 0;
  int optimizer_iterations_ = 0;
};

// (theta, log alpha) as one vector, for extrapolation; alpha stays positive.
Eigen::VectorXd pack(const EmMap::Point& x) {
  const Eigen::Index k = x.theta.size();
  if (!x.alpha) return x.theta;
  const Eigen::Index a = x.alpha->subject_alpha.size();
  const Eigen::Index b = x.alpha->confounder_alpha.size();
  Eigen::VectorXd v(k + a + b);
  v.head(k) = x.theta;
  v.segment(k, a) = x.alpha->subject_alpha.reshaped().array().max(1e-300).log();
  v.tail(b) = x.alpha->confounder_alpha.reshaped().array().max(1e-300).log();
  return v;
}

EmMap::Point unpack(const Eigen::VectorXd& v, const EmMap::Point& like) {
  EmMap::Point x{v.head(like.theta.size()), like.alpha};
  if (x.alpha) {
    const Eigen::Index k = like.theta.size();
    const Eigen::Index a = x.alpha->subject_alpha.size();
    x.alpha->subject_alpha.reshaped() = v.segment(k, a).array().exp();
    x.alpha->confounder_alpha.reshaped() = v.tail(x.alpha->confounder_alpha.size()).array().exp();
  }
  return x;
}

bool converged(const LearnOptions& o, const EmMap::Step& step, const EmMap::Point& from, double previous) {
  const double theta_change = (step.next.theta - from.theta).lpNorm<Eigen::Infinity>();
  return step.e.alpha_converged &&
         theta_change <= o.theta_tolerance * std::max(1.0, step.next.theta.lpNorm<Eigen::Infinity>()) &&
         std::abs(step.objective - previous) <= o.likelihood_tolerance * std::max(1.0, std::abs(step.objective));
}

// Called with each accepted EM iterate (its objective is at that point); SQUAREM's rejected
// extrapolations are evaluations, not iterates, and are not reported: EM's record is then
// non-decreasing (docs/MODEL.md "EM's record").
using Report = std::function<void(const EmMap::Step&)>;

// Plain EM from x until it converges (true) or the evaluation budget runs out (false).
bool plain_em(EmMap& map, EmMap::Point& x, const LearnOptions& options, const Report& report) {
  double previous = -std::numeric_limits<double>::infinity();
  while (map.evaluations() < options.max_em_iterations) {
    const EmMap::Step step = map(x);
    report(step);
    const bool done = converged(options, step, x, previous);
    previous = step.objective;
    x = step.next;
    if (done) return true;
  }
  return false;
}

// SQUAREM (Varadhan & Roland 2008, scheme S3) with its monotone safeguard: two EM steps
// x1 = F(x0), x2 = F(x1) give r = x1 - x0 and v = x2 - 2 x1 + x0; the point
// x0 - 2a r + a^2 v with a = -|r|/|v| (clamped to [-step_max, -1]) is stabilised by one
// more EM step and kept only if its objective is no worse than x2's.
bool squarem(EmMap& map, EmMap::Point& x, const LearnOptions& options, const Report& report) {
  double step_max = 4.0;
  double previous = -std::numeric_limits<double>::infinity();
  while (map.evaluations() < options.max_em_iterations) {
    const EmMap::Step s1 = map(x);
    report(s1);
    if (converged(options, s1, x, previous)) {
      x = s1.next;
      return true;
    }
    const EmMap::Step s2 = map(s1.next);
    report(s2);
    if (converged(options, s2, s1.next, s1.objective)) {
      x = s2.next;
      return true;
    }
    const Eigen::VectorXd p0 = pack(x);
    const Eigen::VectorXd r = pack(s1.next) - p0;
    const Eigen::VectorXd v = pack(s2.next) - 2.0 * pack(s1.next) + p0;
    previous = s2.objective;
    if (v.norm() == 0.0 || !r.allFinite() || !v.allFinite() || map.evaluations() + 1 >= options.max_em_iterations) {
      x = s2.next;
      continue;
    }
    const double a = std::clamp(-r.norm() / v.norm(), -step_max, -1.0);
    const EmMap::Point jump = unpack(p0 - 2.0 * a * r + a * a * v, x);
    const EmMap::Step s3 = map(jump);
    if (std::isfinite(s3.objective) && s3.objective >= s2.objective - 1e-9 * std::max(1.0, std::abs(s2.objective))) {
      report(s3);
      x = s3.next;
      previous = s3.objective;
      if (a == -step_max) step_max = std::min(4.0 * step_max, kMaxStep);
    } else {
      x = s2.next;  // the extrapolation overshot: keep the plain EM step
      step_max = std::max(1.0, step_max / 4.0);
    }
  }
  return false;
}

// How many times EM is resumed with a newly chosen prior strength at most.
constexpr int kMaxStrengthChoices = 4;

RestartResult run_restart(const Mdp& mdp, const EStep& estep, const LearnOptions& options,
                          const IterationReport& on_iteration, Eigen::VectorXd theta, std::uint64_t seed, int index) {
  RestartResult result;
  result.initial_theta = theta;
  EmMap map(mdp, estep, options, seed);
  EmMap::Point x = map.start(theta);
  const Report report = [&](const EmMap::Step& step) {
    ++result.em_iterations;
    if (on_iteration) {
      on_iteration(index, result.em_iterations, step.objective, step.next.theta, step.e,
                   step.next.alpha ? &*step.next.alpha : nullptr);
    }
    result.optimizer_status = step.m.status;
  };
  std::optional<StrengthChoice> choice;
  if (!estep.depends_on_policy()) {
    // Known trajectories: one M-step is all of MaxCausalEnt.
    const EmMap::Step step = map(x);
    report(step);
    x = step.next;
    result.converged = step.m.converged;
  } else {
    // EM to convergence; then, when the E-step has a prior strength to choose, choose it
    // from the data there and resume EM with it until the choice stands.
    for (int round = 0;; ++round) {
      result.converged = options.accelerate ? squarem(map, x, options, report) : plain_em(map, x, options, report);
      if (!result.converged) break;
      choice = map.choose_strength(x);
      if (!choice || choice->best_strength == x.alpha->strength || round == kMaxStrengthChoices) break;
      x.alpha->strength = choice->best_strength;
      result.converged = false;
      choice.reset();
    }
  }
  // The objective and the likelihood at the returned point (alpha stays as learned).
  std::optional<ObservationPrior> refined;
  const EStepResult final_e = map.expect(x, refined);
  result.theta = x.theta;
  result.alpha = x.alpha;
  result.objective = final_e.objective;
  result.log_likelihood = map.data_log_likelihood(x);
  const double penalty = 0.5 * options.l2 * final_e.counts.sum() * x.theta.squaredNorm();
  // Restarts are compared by the held-out likelihood when a strength was chosen from it
  // (objectives at different strengths are not comparable), else by the objective.
  if (choice) result.held_out_log_likelihood = choice->current_score;
  result.score = (choice ? choice->current_score : final_e.objective) - penalty;
  result.em_evaluations = map.evaluations();
  result.optimizer_iterations = map.optimizer_iterations();
  return result;
}

}  // namespace

LearnResult learn_reward(const Mdp& mdp, const EStep& estep, const LearnOptions& options,
                         const IterationReport& on_iteration) {
  if (options.restarts < 1) throw InputError("restarts", "must be at least 1");
  const int k = mdp.num_features();
  // Draw every start point up front, each restart from its own stream.
  std::vector<Eigen::VectorXd> starts;
  const Rng root(options.seed);
  for (int r = 0; r < options.restarts; ++r) {
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(k);
    if (r > 0) {
      Rng rng = root.split(static_cast<std::uint64_t>(r));
      for (int i = 0; i < k; ++i) theta[i] = rng.uniform(-1.0, 1.0);
    }
    starts.push_back(std::move(theta));
  }
  if (options.warm_start) {
    if (options.warm_start->size() != k || !options.warm_start->allFinite()) {
      throw InputError("warm_start", "must be " + std::to_string(k) + " finite weights, one per feature");
    }
    starts.push_back(*options.warm_start);
  }
  const int runs = static_cast<int>(starts.size());
  LearnResult result;
  result.restarts.resize(starts.size());
  parallel_for(runs, options.threads, [&](int r) {
    result.restarts[static_cast<size_t>(r)] =
        run_restart(mdp, estep, options, on_iteration, starts[static_cast<size_t>(r)],
                    root.split(0x5EED0000ull + static_cast<std::uint64_t>(r)).next_u64(), r);
  });
  for (int r = 1; r < runs; ++r) {
    if (result.restarts[static_cast<size_t>(r)].score >
        result.restarts[static_cast<size_t>(result.selected_restart)].score) {
      result.selected_restart = r;
    }
  }
  const RestartResult& best = result.restarts[static_cast<size_t>(result.selected_restart)];
  result.theta = best.theta;
  result.log_likelihood = best.log_likelihood;
  result.objective = best.objective;
  return result;
}

}  // namespace hbirl
