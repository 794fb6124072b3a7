// hbirl generate: write problem files for the built-in domains.
#include <sstream>

#include "commands.hpp"
#include "generate_args.hpp"
#include "learner/input_error.hpp"
#include "problem/json_format.hpp"
#include "sim_driver/gridworld/problem_file.hpp"
#include "sim_driver/file/random_task.hpp"

namespace hbirl::cli {

namespace {

struct GridworldArgs {
  GridworldProblemOptions problem;
  std::string out;
};

int run_gridworld(const GridworldArgs& args) {
  const GridworldProblemOptions& o = args.problem;
  const Problem problem = gridworld_problem(o);
  nlohmann::ordered_json doc;
  if (o.confounders >= 0) {
    std::ostringstream comment;
    comment << "hbirl generate gridworld: " << o.confounders << " confounding element(s), " << o.per_step
            << " observations per step; the labeller gives its pick " << o.labeller.mass
            << " of eta but picks the true source with probability " << o.labeller.accuracy
            << " (its pick is each observation's context); the first " << o.controlled
            << " trajectories are the controlled run (the subject alone) that gives the subject prior.";
    doc["comment"] = comment.str();
  }
  emit_streamed([&](std::ostream& out) { write_problem(out, problem, doc); }, args.out);
  return 0;
}

struct RandomTaskArgs {
  std::uint64_t seed = 1;
  int draw = 0;
  RandomTaskOverrides overrides;
  bool end_sensor = false;
  std::string out;
};

// The task as a problem file: the demonstration's observations and true steps, the
// subject prior from the controlled run, the true weights, and a comment that says what
// was drawn.
int run_random_task(const RandomTaskArgs& args) {
  const RandomTask task = make_random_task(args.seed, args.draw, args.overrides);
  Problem problem;
  problem.mdp = task.mdp;
  problem.state_names = task.state_names;
  problem.action_names = task.action_names;
  problem.feature_names = task.feature_names;
  problem.observation_model = task.prior;
  if (args.end_sensor) problem.observation_model->end_alpha = task.end_alpha;
  for (size_t i = 0; i < task.demonstrations.size(); ++i) {
    DemonstratedTrajectory item;
    item.steps = task.observed.trajectories[i];
    if (args.end_sensor && item.steps->ends_in_terminal) item.steps->end_symbols = task.end_reports[i];
    item.truth = task.demonstrations[i];
    item.ends_in_terminal = task.observed.trajectories[i].ends_in_terminal;
    problem.demonstration.push_back(std::move(item));
  }
  problem.true_weights = task.true_weights;
  nlohmann::ordered_json doc;
  std::ostringstream comment;
  comment << "hbirl generate random-task --seed " << args.seed << " --draw " << args.draw << ": a " << task.layout
          << " of " << task.mdp.num_states << " states and " << task.mdp.num_actions << " actions, " << task.goals
          << " goal(s), " << task.traps << " trap(s), discount " << task.mdp.discount << ", expert decisiveness "
          << task.decisiveness << "; " << task.num_symbols << " symbols, " << task.num_confounders
          << " confounding elements, subject informativeness " << task.informativeness << ", subject share "
          << task.subject_share << ", " << eta_kind_name(task.eta) << " eta, " << task.per_step
          << " observations per step, " << task.occlusion << " of steps occluded; " << task.demonstrations.size()
          << " demonstrations of at most " << task.length << " steps; subject prior from a controlled run of "
          << task.controlled.size() << " trajectories (symbol counts per (s, a) plus 1)";
  if (args.end_sensor)
    comment << "; an end sensor of accuracy " << task.end_accuracy << ", its prior from " << task.end_calibration
            << " calibration reports per terminal state plus 1";
  comment << ".";
  doc["comment"] = comment.str();
  emit_streamed([&](std::ostream& out) { write_problem(out, problem, doc); }, args.out);
  return 0;
}

// generate gridworld: the paper's Gridworld.
CLI::App* add_gridworld_generator(CLI::App* cmd, GridworldArgs& args) {
  CLI::App* grid = cmd->add_subcommand(
      "gridworld",
      "The paper's Gridworld (paper §Experiments A): n x n cells, 4 moves that succeed with probability\n"
      "--intended and otherwise slip to one of the other three moves' cells, features =\n"
      "being in each corner, a goal corner with weight 1, and --trajectories demonstrations\n"
      "of --length steps by the soft expert (true state-action pairs only).");
  grid->add_option("--size", args.problem.size, "Cells per side")->check(CLI::Range(2, 1000))->capture_default_str();
  grid->add_option("--trajectories", args.problem.trajectories, "Number of trajectories")
      ->check(CLI::Range(1, 10000000))
      ->capture_default_str();
  grid->add_option("--length", args.problem.length, "Steps per trajectory")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  grid->add_option("--goal", args.problem.goal,
                   "Goal corner: 0 top-left, 1 top-right, 2 bottom-left, 3 bottom-right (default: drawn from the seed)")
      ->check(CLI::Range(0, 3));
  grid->add_option("--goal-weight", args.problem.goal_weight,
                   "Reward weight of the goal corner; larger = a more decisive soft expert")
      ->check(CLI::Range(-1000.0, 1000.0))
      ->capture_default_str();
  grid->add_option("--intended", args.problem.intended, "Probability that a move goes where intended")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  grid->add_option("--discount", args.problem.discount, "Discount gamma in [0, 1)")
      ->check(CLI::Range(0.0, 0.999999))
      ->capture_default_str();
  grid->add_option("--seed", args.problem.seed, "Seed of the goal and the demonstrations")->capture_default_str();
  grid->add_option(
          "--confounders", args.problem.confounders,
          "Watch the demonstrations through the paper's sensor with this many confounding elements (default: true "
          "steps only): observations, a labeller's eta with its pick as context, and a controlled run for the prior")
      ->check(CLI::Range(0, 64));
  grid->add_option("--per-step", args.problem.per_step, "With --confounders: observations per step")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  grid->add_option("--labeller-mass", args.problem.labeller.mass,
                   "With --confounders: the share of eta the labeller gives its pick (what it claims)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  grid->add_option("--labeller-accuracy", args.problem.labeller.accuracy,
                   "With --confounders: the probability that its pick is the true source (what it knows)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  grid->add_option("--controlled", args.problem.controlled, "With --confounders: trajectories of the controlled run")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  grid->add_option("--out,-o", args.out, "Write the problem file here instead of stdout");
  return grid;
}

// generate random-task: a task of the random-tasks experiment.
CLI::App* add_random_task_generator(CLI::App* cmd, RandomTaskArgs& args) {
  CLI::App* task = cmd->add_subcommand(
      "random-task",
      "A random task from its seed, as `hbirl experiment random-tasks` draws it: a grid or sparse graph MDP\n"
      "(9-100 states, 2-6 actions, goals and traps), a step cost and other features, a true reward whose optimal\n"
      "policy is not trivial, a random sensor (4-24 symbols, 0-7 confounding elements, occlusion), demonstrations\n"
      "watched through it, and the subject prior from a controlled run (sim_driver/file/random_task.hpp). Learn it "
      "with\n"
      "`hbirl learn --problem FILE` (or --from truth); set observation_model.learn to false for O fixed at the prior.");
  task->add_option("--seed", args.seed, "The task")->capture_default_str();
  task->add_option("--draw", args.draw, "Which of the task's data sets (the same task watched again)")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  task->add_option("--informativeness", args.overrides.informativeness,
                   "Fix the subject sensor's informativeness (0: symbols say nothing of the state, 1: the most)")
      ->check(CLI::Range(0.0, 1.0));
  task->add_option("--confounders", args.overrides.confounders, "Fix the number of confounding elements")
      ->check(CLI::Range(0, 64));
  task->add_option("--occlusion", args.overrides.occlusion, "Fix the share of occluded steps")
      ->check(CLI::Range(0.0, 1.0));
  task->add_option("--demonstrations", args.overrides.demonstrations, "Fix the number of demonstrations")
      ->check(CLI::Range(1, 100000));
  task->add_option("--controlled", args.overrides.controlled, "Fix the number of controlled-run trajectories")
      ->check(CLI::Range(1, 100000));
  task->add_option("--eta", args.overrides.eta, "Fix eta: plausible or uniform")
      ->check(CLI::IsMember({"plausible", "uniform"}));
  task->add_flag("--end-sensor", args.end_sensor,
                 "Add the task's end sensor: 1-3 reports of the terminal state each demonstration entered "
                 "(end_symbols) and its prior (observation_model.end_sensor)");
  task->add_option("--out,-o", args.out, "Write the problem file here instead of stdout");
  return task;
}

}  // namespace

Command add_generate(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "generate",
      "Write a problem file: a built-in domain's (gridworld, random-task), or with --domain F the run a\n"
      "domain file's \"sensor\" section simulates (a starting point for your own files).");
  cmd->require_subcommand(0, 1);
  auto d = std::make_shared<GenerateDomainArgs>();
  cmd->add_option(
      "--domain", d->domain,
      "A domain file (docs/your-task.md \"Your own task\"): the run its \"sensor\" section simulates -- what\n"
      "hbirl-sim-driver publishes for it, the controlled run and the demonstrations with their true steps --\n"
      "as a problem file (hbirl learn --problem, hbirl publish --problem)");
  cmd->add_option("--seed", d->seed, "With --domain: the simulation's seed (the same seed, the same file)")
      ->capture_default_str();
  cmd->add_option("--out,-o", d->out, "With --domain: write the problem file here instead of stdout");
  auto g = std::make_shared<GridworldArgs>();
  CLI::App* grid = add_gridworld_generator(cmd, *g);
  auto t = std::make_shared<RandomTaskArgs>();
  CLI::App* task = add_random_task_generator(cmd, *t);
  return [d, g, grid, t, task] {
    if (!d->domain.empty() && (grid->parsed() || task->parsed()))
      throw InputError("--domain", "generates from a domain file: not with gridworld or random-task");
    if (grid->parsed()) return run_gridworld(*g);
    if (task->parsed()) return run_random_task(*t);
    if (d->domain.empty()) {
      throw InputError("generate", "give a domain file (--domain F) or what to generate: gridworld or random-task");
    }
    return run_generate_from_domain(*d);
  };
}

}  // namespace hbirl::cli
