// Speed of the onion camera and of perception (docs/BENCHMARKS.md has the figures and the
// command): frames per second on one core, at 320x240 and 640x480, full scene.
#include <benchmark/benchmark.h>

#include "perception/blobs.hpp"
#include "perception/labeller.hpp"
#include "sim_driver/onion/onion.hpp"
#include "sim_driver/onion/scene.hpp"

namespace hbirl::onion {
namespace {

Episode episode() {
  const Mdp mdp = make_onion_mdp();
  return make_episode(expert_sort(mdp, expert_weights(), kAtBin, true), true, 10.0, 3);
}

void BM_RenderFrame(benchmark::State& state) {
  cv::setNumThreads(1);
  SceneConfig config;
  config.width = static_cast<int>(state.range(0));
  const OnionScene scene(config, 1);
  const Episode e = episode();
  cv::Mat frame;
  int i = 0;
  for (auto _ : state) {
    const int t = (i / config.frames_per_step()) % static_cast<int>(e.steps.size());
    scene.render(e, t, i % config.frames_per_step(), frame);
    benchmark::DoNotOptimize(frame.data);
    ++i;
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderFrame)->Arg(320)->Arg(640);

// Blob detection and labelling of pre-rendered frames (a step's 30 frames in turn).
void BM_PerceiveFrame(benchmark::State& state) {
  cv::setNumThreads(1);  // one core: OpenCV's own thread pool would use the other one too
  SceneConfig config;
  config.width = static_cast<int>(state.range(0));
  const OnionScene scene(config, 1);
  const Episode e = episode();
  std::vector<cv::Mat> frames(static_cast<size_t>(config.frames_per_step()));
  for (int k = 0; k < config.frames_per_step(); ++k) scene.render(e, 2, k, frames[static_cast<size_t>(k)]);
  perception::BlobDetector detector;
  perception::LabellerOptions labels;
  labels.width = config.width;
  labels.height = config.height();
  labels.gripper_area = 400.0;
  labels.onion_area = onion_area(config);
  size_t i = 0;
  for (auto _ : state) {
    const auto observations = perception::label(detector.detect(frames[i % frames.size()]), labels);
    benchmark::DoNotOptimize(observations.data());
    ++i;
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PerceiveFrame)->Arg(320)->Arg(640);

}  // namespace
}  // namespace hbirl::onion
