#pragma once
// Random learning tasks, for checking hbirl on problems nobody tuned it for
// (`hbirl generate random-task`, `hbirl experiment random-tasks`; docs/results/random_tasks).
//
// A task (from its seed) is an MDP, a true reward, a sensor and how demonstrations are
// watched:
//   MDP      a grid (3x3 to 10x10 cells, 4 moves or 4 moves and "stay", slipping to the
//            other moves' cells) or a random sparse graph (9-100 states, 2-6 actions, a
//            ring through every state so all are connected, each action's intended
//            successor with probability 0.6-1 and 1-2 others), discount 0.9-0.97,
//            1-3 terminal states (1-2 goals, the rest traps), uniform start over the
//            other states.
//   reward   2-5 features: a step cost (every action), entering a goal and entering a trap
//            (the probability that the action does), and "terrain" (a random third of the
//            states); a random theta (cost < 0, goal > 0, trap < 0, terrain either sign),
//            redrawn until the optimal policy is not trivial (it uses at least two actions,
//            and always taking action 0 loses at least 5% of the optimal value), then
//            scaled (by 1/4 to 10) so that the soft expert takes an optimal action with
//            probability 0.5-0.9 on average over the states, as far as that range allows
//            (how sure the expert is; the realised value is `decisiveness`).
//   sensor   4-24 symbols; the subject's O_{s,a} = (1 - k) uniform + k (0.75 D_s + 0.25 D_sa)
//            with D ~ Dirichlet(1/2) and informativeness k in [0.3, 1]; 0-7 confounding
//            elements, O_e ~ Dirichlet(1); each observation comes from the subject with
//            probability 0.25-0.75 (1 without elements), else from an element chosen evenly.
//   watching 4-20 observations per step, 0-30% of steps occluded, plausible or uniform eta
//            (sim_driver/gridworld/observations.hpp), 5-40 demonstrations of at most 8-25
//            steps by the soft expert (ending early in a terminal state).
//   prior    the subject's Dirichlet prior from a controlled run (the subject alone, true
//            steps known) of 5-30 trajectories: its symbol counts per (s, a) plus 1.
//   end      an end sensor (used by the methods that say so): one symbol per terminal
//            state, O_end(s) putting accuracy 0.55-0.95 on s's own symbol and the rest
//            evenly on the others; 1-3 reports of the state entered per trajectory that
//            entered one; its prior a calibration's counts plus 1: 2-10 reports of each
//            terminal state, staged without the expert (an onion put in the bin and on
//            the floor). Drawn from streams of its own: the rest of the task is the same
//            with or without it.
// A task's data are drawn from (seed, draw): the same task watched again.
#include <cstdint>
#include <string>
#include <vector>

#include "learner/mdp.hpp"
#include "learner/observations.hpp"
#include "learner/trajectory.hpp"
#include "sim_driver/gridworld/observations.hpp"

namespace hbirl {

// Fixes some of a task's random choices (a negative value or empty string: drawn).
struct RandomTaskOverrides {
  double informativeness = -1.0;
  int confounders = -1;
  double occlusion = -1.0;
  int demonstrations = -1;
  int controlled = -1;  // trajectories of the controlled run (the rest of the data as drawn)
  std::string eta;      // "plausible" or "uniform"
};

struct RandomTask {
  std::uint64_t seed = 0;
  int draw = 0;
  std::string layout;  // "grid" or "graph"
  Mdp mdp;
  std::vector<std::string> state_names, action_names, feature_names;
  Eigen::VectorXd true_weights;
  double decisiveness = 0.0;  // the soft expert's mean probability of an optimal action
  int goals = 0;
  int traps = 0;

  int num_symbols = 0;
  int num_confounders = 0;
  double informativeness = 0.0;
  double subject_share = 1.0;
  EtaKind eta = EtaKind::kPlausible;
  double occlusion = 0.0;
  int per_step = 0;
  int length = 0;
  Eigen::MatrixXd subject_o;     // (S*A) x symbols, the truth
  Eigen::MatrixXd confounder_o;  // E x symbols, the truth

  std::vector<Trajectory> demonstrations;  // the truth
  std::vector<int> entered;                // per demonstration, the terminal state it entered (-1: cut off)
  GridworldObservations observed;          // what the sensor saw, true sources kept
  std::vector<Trajectory> controlled;      // the controlled run
  ObservationPrior prior;                  // subject from the controlled run, elements flat

  double end_accuracy = 0.0;                  // the end sensor's O_end(s, s's own symbol)
  Eigen::MatrixXd end_o;                      // S x terminal states, the truth (terminal rows)
  std::vector<std::vector<int>> end_reports;  // per demonstration, what the end sensor said
  int end_calibration = 0;                    // reports of each terminal state in its calibration
  Eigen::MatrixXd end_alpha;                  // its prior from the calibration (terminal rows)
};

RandomTask make_random_task(std::uint64_t seed, int draw = 0, const RandomTaskOverrides& overrides = {});

const char* eta_kind_name(EtaKind kind);

}  // namespace hbirl
