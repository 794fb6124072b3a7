#pragma once
// A sensor that publishes as it sees (the Python package's hbirl.Sensor, docs/python.md
// "Python sensors"): episodes and steps come one at a time and go onto the bus at once, as
// the simulator's own messages (simulator_service.hpp), and are kept: a frame lost on the
// way (a frame, its step's ground truth, an episode's end marker) is sent again on
// FRAME_REQUEST, END_RUN is repeated until the optimiser's reward, and STOP is heard -- the
// protocol every hbirl sensor keeps.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "learner/observations.hpp"
#include "learner/trajectory.hpp"
#include "services/bus.hpp"
#include "services/typed.hpp"
#include "sim_driver/simulator/simulator_service.hpp"

namespace hbirl {

struct LiveSensorShape {
  std::string domain;            // the name the optimiser knows the domain by (its file's "name", else its stem)
  int num_symbols = 0;           // the observation alphabet
  int num_sources = 1;           // the subject and the confounding elements
  int num_end_symbols = 0;       // an end sensor's alphabet (0: none)
  double step_seconds = 1.0;     // sim time per step (the messages' utime)
  Eigen::VectorXd true_weights;  // sent with the controlled run's ground truth when known (empty: not)
};

class LiveSensor {
 public:
  // Throws InputError for a shape no optimiser could take (names the field).
  LiveSensor(services::Bus& bus, const LiveSensorShape& shape, services::Counters& counters);
  ~LiveSensor();
  // Until the optimiser's heartbeat is heard, at most `seconds`: whether it was.
  bool wait_for_optimiser(double seconds, const std::function<bool()>& stop = nullptr);
  // A new episode (BEGIN_EPISODE): its number. A controlled one (the subject alone, its
  // true steps known) must give each step's state and action.
  int begin_episode(bool controlled);
  // One step's observations: symbols, their eta (one row of num_sources per symbol, each
  // summing to 1) and optionally contexts (which rule gave each eta, 0 .. 65535);
  // `truth`: the true (state, action), required in a controlled episode, refused in a
  // demonstration (its truth is what is learned).
  void step(const std::vector<int>& symbols, const RowMatrix& eta, const std::vector<int>& contexts,
            std::optional<StateAction> truth);
  // The episode's end (END_EPISODE): whether its last action entered a terminal state,
  // and what was seen of which (end_state, -1: not known; an end sensor's reports).
  void end_episode(bool ends_in_terminal, int end_state, const std::vector<int>& end_symbols);
  // The end of the run (END_RUN, stating its episodes): no episode may be under way.
  void end_run();
  // Hears what comes (FRAME_REQUEST answered, STOP) for up to `timeout_ms`.
  int handle(int timeout_ms);
  // STOP heard: the optimiser has seen enough; end the run after this episode.
  bool stop_requested() const;
  // After end_run: answers FRAME_REQUEST and repeats END_RUN until the optimiser's final
  // REWARD (its theta) or `seconds`/`stop` (nullopt).
  std::optional<Eigen::VectorXd> wait_for_reward(double seconds, const std::function<bool()>& stop = nullptr);
  int episodes() const;
  bool in_episode() const { return in_episode_; }
  bool run_ended() const { return run_ended_; }
  std::int64_t frames_resent() const;

 private:
  class Run;
  Run* run_ = nullptr;  // owned by simulator_
  std::unique_ptr<Simulator> simulator_;
  LiveSensorShape shape_;
  bool in_episode_ = false;
  bool run_ended_ = false;
  int contexts_given_[2] = {-1, -1};  // demonstrations, controlled run: -1 not yet known, 0 none, 1 given
};

}  // namespace hbirl
