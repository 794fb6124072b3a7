#pragma once
// The onion pipeline's services as libraries (their mains only wire them to a bus and a
// command line): the simulator with its camera, perception, the labeller, and the
// optimiser. Channels and types: the README's table.
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "hbirl/camera_frame_t.hpp"
#include "hbirl/detections_t.hpp"
#include "hbirl/em_progress_t.hpp"
#include "hbirl/frame_request_t.hpp"
#include "hbirl/observation_model_t.hpp"
#include "hbirl/posterior_t.hpp"
#include "hbirl/reward_t.hpp"
#include "perception/blobs.hpp"
#include "services/channels.hpp"
#include "services/dataset.hpp"
#include "services/estep_service.hpp"
#include "services/learning.hpp"
#include "sim_driver/gridworld_observations.hpp"
#include "sim_driver/onion_scene.hpp"

namespace hbirl::services {

// ---- sim_driver ----
// The paper's Gridworld as a simulated sensor: it has no camera, so the simulator
// publishes the observations with their eta itself (OBSERVATIONS, one message per step);
// perception and the labeller are not needed.
struct GridworldSimOptions {
  int confounders = 3;           // |E|
  int per_step = 40;             // observations per step, drawn equally from the subject and each element
  int trajectories = 20;         // demonstrations
  int controlled_trajectories = 20;  // controlled run: the subject alone, true states known
  int length = 10;               // steps per trajectory
  EtaKind eta = EtaKind::kPlausible;
  double step_seconds = 1.0;     // sim time per step (utime of its messages)
};

struct SimDriverOptions {
  std::string domain = "onion";  // or "gridworld"
  // onion
  onion::SceneConfig scene;     // the demonstrations' scene
  int controlled_sorts = 20;    // first, in the controlled scene: the subject prior
  int sorts = 6;                // then the demonstrations
  std::string encoding = "png";          // lossless: replay and live see the same pixels
  // gridworld
  GridworldSimOptions gridworld;
  // both
  std::uint64_t seed = 1;       // onion: demonstrations plan_sorts(seed), controlled run seed + 1
  double max_frames_per_second = 300.0;  // pacing, wall clock (0: as fast as it renders)
};
// The simulator: publishes the whole run (EPISODE, GROUND_TRUTH, and CAMERA frames for the
// onion domain, OBSERVATIONS for the gridworld), then END_RUN, and afterwards answers
// FRAME_REQUEST by publishing the asked frames again, with their steps' ground truth (the
// run is deterministic: the same pixels, the same observations) -- so frames and ground
// truth lost on the way can be recovered.
class SimDriver {
 public:
  SimDriver(Bus& bus, const SimDriverOptions& options, Counters& counters);
  ~SimDriver();
  // Returns false if asked to stop first. `idle` runs after every frame.
  bool publish_run(const std::function<bool()>& stop, const std::function<void()>& idle = nullptr);
  std::int64_t frames_resent() const { return resent_; }
  // Publishes every END_EPISODE marker and END_RUN again (receivers take repeats as one):
  // the learner must not wait forever for an end marker lost on the way.
  void republish_end_markers();
  // Which services must listen before the run starts (perception and the labeller only
  // for a camera).
  std::vector<std::string> listeners() const;

  struct Plan;  // the run: its episodes, and how a frame is published

 private:
  hbirl::episode_marker_t marker(int episode, std::int8_t kind, double time) ;
  hbirl::episode_marker_t end_marker(int episode);
  void on_request(const hbirl::frame_request_t& m);
  void publish_truth(int episode, int step);
  Bus& bus_;
  SimDriverOptions options_;
  Counters& counters_;
  std::unique_ptr<Plan> plan_;
  std::int64_t marker_seq_ = 0, truth_seq_ = 0;
  std::int64_t resent_ = 0;
  Subscriptions subs_;  // last: ends first
};

// Publishes the run with a SimDriver (the in-process tests' way).
bool run_sim_driver(Bus& bus, const SimDriverOptions& options, Counters& counters, const std::function<bool()>& stop,
                    const std::function<void()>& idle = nullptr);

// ---- perception: CAMERA -> DETECTIONS, one message per frame (also when it is empty) ----
class PerceptionService {
 public:
  PerceptionService(Bus& bus, Counters& counters);

 private:
  void on_frame(const hbirl::camera_frame_t& m);
  Bus& bus_;
  Counters& counters_;
  perception::BlobDetector detector_;
  std::int64_t seq_ = 0;
  SequenceTracker frames_;
  Subscriptions subs_;  // last: ends first
};

// ---- labeller: DETECTIONS -> OBSERVATIONS with eta (the paper's rules) ----
class LabellerService {
 public:
  LabellerService(Bus& bus, Counters& counters, bool uniform_eta = false);

 private:
  void on_detections(const hbirl::detections_t& m);
  Bus& bus_;
  Counters& counters_;
  bool uniform_eta_;
  std::int64_t seq_ = 0;
  SequenceTracker detections_;
  Subscriptions subs_;  // last: ends first
};

// ---- optimiser: the data set off the bus, HiddenDataEM with the sampler workers ----
struct OptimiserOptions {
  LearningOptions learning;
  BusExecutorOptions executor;
  int workers = 0;              // wait for this many sampler workers before learning
  int wait_workers_ms = 10000;
  int resend_after_ms = 1000;   // after END_RUN, ask for missing frames when none came for this long
  int quiet_ms = 5000;          // ... and learn without them when still none came for this long
  // Called often (every ~100 ms while collecting, every EM iteration) with what the
  // optimiser is doing ("collecting", "learning"): the process beats its heartbeat there,
  // so services that wait for it (the simulator) and the dashboard hear it throughout.
  std::function<void(const std::string&)> beat;
};
struct OptimiserResult {
  Learned learned;
  Dataset data;
  std::int64_t missing_frames = 0;   // never came, even when asked for again
  int frame_requests = 0;            // FRAME_REQUEST messages sent
  int workers = 0;
  BusBlockExecutor::Stats estep;
};
// Collects the run, learns, publishes EM_PROGRESS and the final REWARD. nullopt if asked
// to stop first.
// `ready` is called once it listens (so a simulator may start).
std::optional<OptimiserResult> run_optimiser(Bus& bus, const OptimiserOptions& options, Counters& counters,
                                             const std::function<bool()>& stop,
                                             const std::function<void(const std::string&)>& log = nullptr,
                                             const std::function<void()>& ready = nullptr);

// Learns offline from a recorded log (hbirl learn --log): the same data set and the same
// learning as the live optimiser, computed here. Throws InputError for unusable logs.
OptimiserResult learn_from_log(const std::string& path, const LearningOptions& options, Counters& counters);

}  // namespace hbirl::services
