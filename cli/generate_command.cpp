// hbirl generate: write problem files for the built-in domains.
#include "commands.hpp"
#include "learner/input_error.hpp"
#include "problem/json_format.hpp"
#include "sim_driver/gridworld.hpp"

namespace hbirl::cli {

namespace {

struct GridworldArgs {
  int size = 5;
  int trajectories = 20;
  int length = 10;
  int goal = -1;
  double goal_weight = 1.0;
  double intended = 0.9;
  double discount = 0.95;
  std::uint64_t seed = 1;
  std::string out;
};

int run_gridworld(const GridworldArgs& args) {
  GridworldOptions options;
  options.size = args.size;
  options.intended = args.intended;
  options.discount = args.discount;
  Rng rng(args.seed);
  GridworldTask task = make_gridworld_task(options, args.trajectories, args.length, rng);
  if ((args.goal >= 0 && args.goal != task.goal) || args.goal_weight != 1.0) {
    if (args.goal >= 0) task.goal = args.goal;
    task.true_weights.setZero();
    task.true_weights[task.goal] = args.goal_weight;
    task.trajectories = soft_expert_demonstration(task.mdp, task.true_weights, args.trajectories, args.length, rng);
  }
  Problem problem;
  problem.mdp = task.mdp;
  problem.state_names = gridworld_state_names(args.size);
  problem.action_names = gridworld_action_names();
  problem.feature_names = gridworld_feature_names();
  for (auto& trajectory : task.trajectories) {
    DemonstratedTrajectory item;
    item.truth = std::move(trajectory);
    problem.demonstration.push_back(std::move(item));
  }
  problem.true_weights = task.true_weights;
  emit(format_json(problem_to_json(problem)), args.out);
  return 0;
}

}  // namespace

Command add_generate(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "generate",
      "Write a problem file for a built-in domain (a starting point for your own files).");
  cmd->require_subcommand(1);
  auto g = std::make_shared<GridworldArgs>();
  CLI::App* grid = cmd->add_subcommand(
      "gridworld",
      "The paper's Gridworld (SPEC §3): n x n cells, 4 moves that succeed with probability\n"
      "--intended and otherwise slip to one of the other three moves' cells, features =\n"
      "being in each corner, a goal corner with weight 1, and --trajectories demonstrations\n"
      "of --length steps by the soft expert (true state-action pairs only).");
  grid->add_option("--size", g->size, "Cells per side")->check(CLI::Range(2, 1000))->capture_default_str();
  grid->add_option("--trajectories", g->trajectories, "Number of trajectories")
      ->check(CLI::Range(1, 10000000))
      ->capture_default_str();
  grid->add_option("--length", g->length, "Steps per trajectory")->check(CLI::Range(1, 1000000))->capture_default_str();
  grid->add_option("--goal", g->goal,
                   "Goal corner: 0 top-left, 1 top-right, 2 bottom-left, 3 bottom-right (default: drawn from the seed)")
      ->check(CLI::Range(0, 3));
  grid->add_option("--goal-weight", g->goal_weight,
                   "Reward weight of the goal corner; larger = a more decisive soft expert")
      ->check(CLI::Range(-1000.0, 1000.0))
      ->capture_default_str();
  grid->add_option("--intended", g->intended, "Probability that a move goes where intended")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  grid->add_option("--discount", g->discount, "Discount gamma in [0, 1)")
      ->check(CLI::Range(0.0, 0.999999))
      ->capture_default_str();
  grid->add_option("--seed", g->seed, "Seed of the goal and the demonstrations")->capture_default_str();
  grid->add_option("--out,-o", g->out, "Write the problem file here instead of stdout");
  return [g, grid] {
    if (grid->parsed()) return run_gridworld(*g);
    return 2;
  };
}

}  // namespace hbirl::cli
