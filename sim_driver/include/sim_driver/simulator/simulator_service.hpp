#pragma once
// The simulator service, hbirl-sim-driver (docs/services.md "Services and channels"): a domain's
// simulated run on the bus of services/, as a camera or a sensor would publish it.
#include <functional>
#include <memory>
#include <optional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "hbirl/camera_frame_t.hpp"
#include "hbirl/episode_marker_t.hpp"
#include "hbirl/frame_request_t.hpp"
#include "hbirl/ground_truth_t.hpp"
#include "hbirl/observations_t.hpp"
#include "services/bus.hpp"
#include "services/channels.hpp"
#include "services/typed.hpp"
#include "sim_driver/registry/domain.hpp"
#include "sim_driver/registry/simulation_options.hpp"

namespace hbirl {

struct SimulatorOptions {
  SimulationOptions simulation;          // the run (sim_driver/registry/domain.hpp)
  std::string encoding = "png";          // a camera's frames; lossless: replay and live see the same pixels
  double max_frames_per_second = 300.0;  // pacing, wall clock (0: as fast as it renders)
};
// The simulator of a domain (sim_driver/registry/domain.hpp): publishes the whole run (EPISODE,
// GROUND_TRUTH, and CAMERA frames for a domain with a camera, OBSERVATIONS with their
// eta for one with a sensor), then END_RUN, and afterwards answers
// FRAME_REQUEST by publishing the asked frames again, with their steps' ground truth (the
// run is deterministic: the same pixels, the same observations) -- so frames and ground
// truth lost on the way can be recovered.
class Simulator {
 public:
  // Throws InputError for a domain without a simulator or options it cannot run.
  Simulator(services::Bus& bus, const Domain& domain, const SimulatorOptions& options, services::Counters& counters);
  // A run planned elsewhere (e.g. a recorded one, sim_driver/file/recorded_run.hpp), under the
  // domain name its markers carry.
  Simulator(services::Bus& bus, std::string domain_name, std::unique_ptr<Simulation> run,
            const SimulatorOptions& options, services::Counters& counters);
  ~Simulator();
  // Returns false if asked to stop first. `idle` runs after every frame.
  bool publish_run(const std::function<bool()>& stop, const std::function<void()>& idle = nullptr);
  std::int64_t frames_resent() const { return resent_; }
  // Publishes END_RUN again (receivers take repeats as one): the learner must not wait
  // forever for the end of the run lost on the way. It states how many episodes the run
  // had, so their end markers are asked for (FRAME_REQUEST), not repeated: at 10^5
  // episodes that was 10^5 messages a second.
  void republish_end_of_run();
  // Which services must listen before the run starts (perception and the labeller only
  // for a camera).
  std::vector<std::string> listeners() const;
  // Until the listeners' heartbeats are heard, at most `seconds`: those not heard.
  std::vector<std::string> wait_for_listeners(const std::function<bool()>& stop, double seconds,
                                              const std::function<void(const std::string&)>& beat = nullptr);
  // The run piece by piece, as publish_run publishes it (a live sensor's way, live_sensor.hpp):
  // an episode's BEGIN_EPISODE; a step's BEGIN_STEP and ground truth (its frames:
  // publish_frame); its END_EPISODE; END_RUN.
  void publish_begin(int episode);
  void publish_step_begin(int episode, int step);
  void publish_frame(int episode, int step, int frame);
  void publish_end(int episode);
  void publish_end_of_run();
  // After the run: answers FRAME_REQUEST (frames, ground truth, end markers) and repeats
  // END_RUN every second until the optimiser's final REWARD (reward()) or `stop`.
  void serve_until_learned(const std::function<bool()>& stop,
                           const std::function<void(const std::string&)>& beat = nullptr);
  // Hears what comes (FRAME_REQUEST answered, STOP, REWARD) for up to `timeout_ms`.
  int handle(int timeout_ms) { return bus_.handle(timeout_ms); }
  // The final REWARD's theta, once heard.
  const std::optional<Eigen::VectorXd>& reward() const { return reward_; }
  // STOP heard for this run: the sensor side should end the run.
  bool told_to_stop() const { return told_to_stop_; }

  // The whole service: waits until the listeners' heartbeats are heard (at most
  // `start_delay_s`), publishes the run, then answers FRAME_REQUEST and repeats the end
  // markers every second until the optimiser's final REWARD comes or `stop` says so.
  // `beat(state)` is called often (the process's heartbeat), `log` with what happened.
  // Returns false if stopped before the run was published.
  bool serve(const std::function<bool()>& stop, double start_delay_s,
             const std::function<void(const std::string&)>& beat, const std::function<void(const std::string&)>& log);

 private:
  hbirl::episode_marker_t marker(int episode, std::int8_t kind, double time);
  hbirl::episode_marker_t end_marker(int episode);
  hbirl::episode_marker_t end_of_run();
  void on_request(const hbirl::frame_request_t& m);
  void publish_truth(int episode, int step);
  services::Bus& bus_;
  SimulatorOptions options_;
  services::Counters& counters_;
  std::string domain_;
  std::unique_ptr<Simulation> run_;
  std::int64_t marker_seq_ = 0, truth_seq_ = 0, frame_seq_ = 0;
  cv::Mat frame_;
  std::vector<unsigned char> bytes_;
  std::int64_t resent_ = 0;
  // Told to stop (STOP, for this domain): the run ends before the next episode, END_RUN
  // stating the episodes published.
  bool told_to_stop_ = false;
  std::optional<Eigen::VectorXd> reward_;
  int episodes_in_run_ = -1;  // once stopped early; -1: all of run_
  std::vector<bool> ended_;   // the episodes whose END_EPISODE went out (an end asked for again is one of them)
  int episodes_in_run() const;
  services::Subscriptions subs_;  // last: ends first
};

// Publishes the run with a Simulator (the in-process tests' way).
bool run_simulator(services::Bus& bus, const Domain& domain, const SimulatorOptions& options,
                   services::Counters& counters, const std::function<bool()>& stop,
                   const std::function<void()>& idle = nullptr);

}  // namespace hbirl
