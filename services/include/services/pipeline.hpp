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
#include "hbirl/reward_t.hpp"
#include "perception/blobs.hpp"
#include "services/dataset.hpp"
#include "services/estep_service.hpp"
#include "services/learning.hpp"
#include "sim_driver/onion_scene.hpp"

namespace hbirl::services {

namespace channels {
inline const std::string kCamera = "CAMERA";
inline const std::string kDetections = "DETECTIONS";
inline const std::string kEmProgress = "EM_PROGRESS";
inline const std::string kReward = "REWARD";
inline const std::string kFrameRequest = "FRAME_REQUEST";
}  // namespace channels

// ---- sim_driver ----
struct SimDriverOptions {
  onion::SceneConfig scene;     // the demonstrations' scene
  int controlled_sorts = 20;    // first, in the controlled scene: the subject prior
  int sorts = 6;                // then the demonstrations
  std::uint64_t seed = 1;       // demonstrations: plan_sorts(seed); controlled run: seed + 1
  double max_frames_per_second = 300.0;  // pacing, wall clock (0: as fast as it renders)
  std::string encoding = "png";          // lossless: replay and live see the same pixels
};
// The simulator: publishes the whole run (EPISODE, GROUND_TRUTH, CAMERA), then END_RUN,
// and afterwards answers FRAME_REQUEST by rendering the asked frames again (the scene is
// deterministic: the same pixels) -- so frames lost on the way can be recovered.
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

 private:
  struct Plan;
  hbirl::episode_marker_t end_marker(int episode);
  std::int64_t marker_seq_ = 0;
  void publish_frame(int episode, int step, int frame);
  void on_request(const hbirl::frame_request_t& m);
  Bus& bus_;
  SimDriverOptions options_;
  Counters& counters_;
  std::unique_ptr<Plan> plan_;
  std::int64_t frame_seq_ = 0;
  std::int64_t resent_ = 0;
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
};

// ---- optimiser: the data set off the bus, HiddenDataEM with the sampler workers ----
struct OptimiserOptions {
  LearningOptions learning;
  BusExecutorOptions executor;
  int workers = 0;              // wait for this many sampler workers before learning
  int wait_workers_ms = 10000;
  int resend_after_ms = 1000;   // after END_RUN, ask for missing frames when none came for this long
  int quiet_ms = 5000;          // ... and learn without them when still none came for this long
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
