// Writes the binary seed corpora of the fuzz targets (LCM messages, camera frames) into
// DIR/<target>/ (DIR: tests/fuzz/corpus). Run it by hand when a message type changes:
//   cmake --build BUILD --target fuzz_make_seeds && BUILD/tests/fuzz/fuzz_make_seeds tests/fuzz/corpus
// Seeds are valid messages, so that the fuzzers start past the decoders:
//   fuzz_lcm_decoders      one of every type (tests/services/sample_messages.hpp), its type byte first
//   fuzz_service_handlers  the same one at a time, and three transcripts of a real exchange
//                          recorded off an in-process bus: a small gridworld run (EPISODE,
//                          GROUND_TRUTH, OBSERVATIONS), one E-step pass between the
//                          optimiser's side and a sampler worker (MDP, TRAJECTORY, STATUS,
//                          ESTEP_REQUEST, ESTEP_RESULT), and an onion frame through
//                          perception and the labeller (CAMERA, DETECTIONS, OBSERVATIONS)
//   fuzz_png_frame         onion camera frames, as PNG and as JPEG
#include <atomic>
#include <filesystem>
#include <fstream>
#include <iostream>
#include "perception/image_codec.hpp"
#include <opencv2/imgproc.hpp>
#include <thread>

#include "fuzz_common.hpp"
#include "learner/hidden_data_em.hpp"
#include "sample_messages.hpp"
#include "services/estep_service.hpp"
#include "services/labeller_service.hpp"
#include "services/memory_bus.hpp"
#include "services/perception_service.hpp"
#include "services/sampler_worker.hpp"
#include "sim_driver/simulator/simulator_service.hpp"
#include "sim_driver/registry/domain.hpp"
#include "sim_driver/gridworld/gridworld.hpp"
#include "sim_driver/gridworld/observations.hpp"

namespace {

using namespace hbirl;
using namespace hbirl::services;
namespace fs = std::filesystem;

void write(const fs::path& file, const std::vector<std::uint8_t>& bytes) {
  fs::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

int channel_index(const std::string& name) {
  for (int k = 0; k < fuzz::kNumChannels; ++k) {
    if (fuzz::channel(k) == name) return k;
  }
  return -1;
}

Counters quiet(const std::string& name) {
  Counters c;
  c.service = name;
  c.quiet = true;
  return c;
}

// Everything published on `hub` while it listens, as fuzz records (at most `limit`).
class Recorder {
 public:
  explicit Recorder(std::shared_ptr<MemoryHub> hub) : bus_(std::move(hub)) {
    bus_.subscribe(
        ".*",
        [this](const Message& m) {
          const int k = channel_index(m.channel);
          if (k < 0 || m.size > 0xffff) return;
          const std::vector<std::uint8_t> r = fuzz::record(k, std::vector<std::uint8_t>(m.data, m.data + m.size));
          records_.push_back(r);
        },
        1 << 20);
  }
  std::vector<std::vector<std::uint8_t>> take() {
    bus_.handle(0);
    return std::move(records_);
  }

 private:
  MemoryBus bus_;
  std::vector<std::vector<std::uint8_t>> records_;
};

std::vector<std::uint8_t> join(const std::vector<std::vector<std::uint8_t>>& records, size_t limit) {
  std::vector<std::uint8_t> out;
  for (size_t i = 0; i < records.size() && i < limit; ++i) out.insert(out.end(), records[i].begin(), records[i].end());
  return out;
}

// A small gridworld run as the simulator publishes it.
std::vector<std::uint8_t> gridworld_run() {
  auto hub = std::make_shared<MemoryHub>();
  Recorder rec(hub);
  MemoryBus bus(hub);
  Counters c = quiet("sim");
  DomainOptions d;
  d.gridworld_size = 3;
  const auto domain = open_domain("gridworld", d);
  SimulatorOptions o;
  o.simulation.trajectories = 1;
  o.simulation.controlled_trajectories = 1;
  o.simulation.length = 2;
  o.simulation.per_step = 4;
  o.simulation.confounders = 1;
  o.max_frames_per_second = 0;
  Simulator driver(bus, *domain, o, c);
  driver.publish_run(nullptr);
  return join(rec.take(), 40);
}

// One E-step pass over the bus: the optimiser's side and one worker (the data set and MDP
// sent, heartbeats, the first request and its answer).
std::vector<std::uint8_t> estep_pass() {
  auto hub = std::make_shared<MemoryHub>();
  Recorder rec(hub);
  Rng rng(5);
  GridworldOptions g;
  g.size = 2;
  const GridworldTask task = make_gridworld_task(g, 2, 3, rng);
  GridworldObservationOptions oo;
  oo.per_step = 2;
  const Eigen::MatrixXd subject = gridworld_subject_observation_model(2, 1.0);
  const Eigen::MatrixXd elements = random_confounder_observation_model(1, rng);
  const std::vector<ObservedTrajectory> observed =
      observe_gridworld(task.mdp, task.trajectories, subject, elements, oo, rng).trajectories;
  ObservationPrior prior;
  prior.num_symbols = static_cast<int>(subject.cols());
  prior.num_confounders = 1;
  prior.subject_alpha = Eigen::MatrixXd::Ones(subject.rows(), subject.cols());
  prior.confounder_alpha = Eigen::MatrixXd::Ones(1, subject.cols());
  prior.learn_eta = false;

  MemoryBus worker_bus(hub);
  Counters wc = quiet("sampler");
  SamplerWorker worker(worker_bus, fuzz::kFuzzSampler, wc);
  std::atomic<bool> stop{false};
  std::thread t([&] {
    while (!stop) worker.handle(5);
  });
  MemoryBus bus(hub);
  Counters c = quiet("optimiser");
  BusExecutorOptions eo;
  eo.spot_check = false;
  auto executor = std::make_shared<BusBlockExecutor>(bus, task.mdp, "gridworld", c, eo);
  executor->wait_for_workers(1, 5000);
  ObservationEStepOptions options;
  options.executor = executor;
  const ObservationEStep estep(task.mdp, observed, prior, options);
  LearnOptions learn;
  learn.threads = 1;
  learn.max_em_iterations = 1;
  learn_reward(task.mdp, estep, learn);
  stop = true;
  t.join();
  return join(rec.take(), 11);  // up to the first request and its answer: small inputs run faster
}

// An onion camera frame, PNG-encoded.
std::vector<std::uint8_t> onion_frame(int episode, int step, int frame) {
  const auto domain = open_domain("onion");
  SimulationOptions o;
  o.controlled_sorts = 1;
  o.sorts = 1;
  const auto run = domain->simulate(o);
  cv::Mat image;
  run->render(episode, step, frame, image);
  std::vector<std::uint8_t> png;
  png = hbirl::perception::encode_png(image, 9);
  return png;
}

// The frame through perception and the labeller.
std::vector<std::uint8_t> onion_chain(const std::vector<std::uint8_t>& png) {
  auto hub = std::make_shared<MemoryHub>();
  Recorder rec(hub);
  MemoryBus bus(hub);
  Counters c = quiet("chain");
  PerceptionService perception(bus, c);
  LabellerService labeller(bus, c, *builtin_domain("onion")->camera());
  const cv::Mat image = hbirl::perception::decode_image(png);
  hbirl::episode_marker_t marker{};
  marker.domain = "onion", marker.kind = hbirl::episode_marker_t::BEGIN_EPISODE, marker.num_steps = 1,
  marker.frames_per_step = 1;
  publish(bus, channels::kEpisode, marker, c);
  hbirl::camera_frame_t f{};
  f.width = image.cols, f.height = image.rows, f.encoding = "png", f.size = static_cast<std::int32_t>(png.size()),
  f.data = png;
  publish(bus, channels::kCamera, f, c);
  for (int i = 0; i < 4; ++i) bus.handle(0);
  return join(rec.take(), 10);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_make_seeds CORPUS_DIR\n";
    return 2;
  }
  const fs::path dir = argv[1];
  for (const auto& s : test::sample_messages()) {
    const int k = channel_index(s.channel);
    std::vector<std::uint8_t> typed{static_cast<std::uint8_t>(k)};
    typed.insert(typed.end(), s.bytes.begin(), s.bytes.end());
    write(dir / "fuzz_lcm_decoders" / (s.type + ".bin"), typed);
    write(dir / "fuzz_service_handlers" / (s.type + ".bin"), fuzz::record(k, s.bytes));
  }
  write(dir / "fuzz_service_handlers" / "gridworld_run.bin", gridworld_run());
  write(dir / "fuzz_service_handlers" / "estep_pass.bin", estep_pass());
  const std::vector<std::uint8_t> png = onion_frame(0, 0, 0);
  write(dir / "fuzz_service_handlers" / "onion_frame_chain.bin", onion_chain(png));
  write(dir / "fuzz_png_frame" / "onion_frame.png", png);
  cv::Mat image = hbirl::perception::decode_image(png);
  std::vector<std::uint8_t> jpeg;
  jpeg = hbirl::perception::encode_jpeg(image, 60);
  write(dir / "fuzz_png_frame" / "onion_frame.jpg", jpeg);
  cv::Mat small;
  cv::resize(image, small, cv::Size(image.cols / 4, image.rows / 4), 0, 0, cv::INTER_AREA);
  std::vector<std::uint8_t> small_png;
  small_png = hbirl::perception::encode_png(small, 9);
  write(dir / "fuzz_png_frame" / "onion_frame_quarter.png", small_png);
  std::vector<std::uint8_t> tiny;
  tiny = hbirl::perception::encode_png(cv::Mat(1, 1, CV_8UC3, cv::Scalar(0, 0, 255)));
  write(dir / "fuzz_png_frame" / "one_pixel.png", tiny);
  std::cout << "seeds written to " << dir << "\n";
  return 0;
}
