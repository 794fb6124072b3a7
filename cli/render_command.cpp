// hbirl render: frames of the simulated onion-sorting camera, with what perception saw.
#include <filesystem>
#include <sstream>

#include "commands.hpp"
#include "full_commands.hpp"
#include "learner/input_error.hpp"
#include "perception/blobs.hpp"
#include "perception/image_codec.hpp"
#include "perception/labeller.hpp"
#include "perception/overlay.hpp"
#include "problem/json_format.hpp"
#include "sim_driver/onion/onion.hpp"
#include "sim_driver/onion/scene.hpp"

namespace hbirl::cli {

namespace {

struct RenderArgs {
  std::string config = "all";
  std::string out;
  int sorts = 1;
  int every = 10;
  int width = 320;
  int fps = 15;
  std::uint64_t seed = 1;
  bool raw = false;
  double start = 0.0;
};

int run_render(const RenderArgs& args) {
  onion::SceneConfig config = onion::SceneConfig::parse(args.config, "--config");
  config.width = args.width;
  config.fps = args.fps;
  const onion::OnionScene scene(config, args.seed);
  const Mdp mdp = onion::make_onion_mdp();
  const Eigen::VectorXd weights = onion::expert_weights();
  std::error_code ec;
  std::filesystem::create_directories(args.out, ec);
  if (ec) throw InputError("--out", args.out + ": " + ec.message());

  perception::BlobDetector detector;
  perception::LabellerOptions labels;
  labels.width = config.width;
  labels.height = config.height();
  const onion::GripperSize g = onion::gripper_size(config);
  labels.gripper_area = static_cast<double>(g.width) * g.height;
  labels.onion_area = onion::onion_area(config);

  Rng rng(args.seed, 7);
  double time = args.start;
  nlohmann::json files = nlohmann::json::array();
  cv::Mat frame;
  for (int i = 0; i < args.sorts; ++i) {
    const bool blemished = rng.uniform() < 0.5;
    const Trajectory steps = onion::expert_sort(mdp, weights, rng.uniform_int(3), blemished);
    const onion::Episode episode = onion::make_episode(steps, blemished, time, rng.next_u64());
    const std::vector<std::string> names = onion::state_names();
    const std::vector<std::string> actions = onion::action_names();
    for (int t = 0; t < static_cast<int>(steps.size()); ++t) {
      for (int k = 0; k < config.frames_per_step(); k += args.every) {
        scene.render(episode, t, k, frame);
        const std::vector<perception::Detection> detections = detector.detect(frame);
        const std::vector<perception::Observation> observations = perception::label(detections, labels);
        if (!args.raw) perception::draw_detections(frame, detections, observations);
        char name[64];
        std::snprintf(name, sizeof name, "sort%02d_step%d_frame%02d.png", i, t, k);
        const std::string path = (std::filesystem::path(args.out) / name).string();
        if (!perception::write_png(path, frame)) throw InputError("--out", "could not write " + path);
        nlohmann::json symbols = nlohmann::json::array();
        for (const auto& o : observations) symbols.push_back(o.symbol);
        files.push_back({{"file", path},
                         {"time", scene.time_of(episode, t, k)},
                         {"state", names[static_cast<size_t>(steps[static_cast<size_t>(t)].state)]},
                         {"action", actions[static_cast<size_t>(steps[static_cast<size_t>(t)].action)]},
                         {"symbols", symbols}});
      }
    }
    time += static_cast<double>(steps.size()) * config.step_seconds;
  }
  emit(format_json(nlohmann::json{{"frames", files.size()}, {"out", args.out}, {"files", files}}), "");
  return 0;
}

}  // namespace

Command add_render(CLI::App& app) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand(kRender.name, kRender.description);
  cmd->add_option("--config,-c", a->config,
                  "Scene: controlled, all, or a comma-separated list of blue-shirt, other-onions,\n"
                  "foreground, mirror")
      ->capture_default_str();
  cmd->add_option("--out,-o", a->out, "Output folder")->required();
  cmd->add_option("--sorts", a->sorts, "Number of sorts (trajectories) to render")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--every", a->every, "Write every N-th frame")->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--width", a->width, "Frame width in pixels (height = 3/4 of it)")
      ->check(CLI::Range(onion::camera_view().min_width, onion::camera_view().max_width))
      ->capture_default_str();
  cmd->add_option("--fps", a->fps, "Frames per simulated second")->check(CLI::Range(1, 240))->capture_default_str();
  cmd->add_option("--start", a->start, "Sim time of the first sort, seconds (moves the confounders)")
      ->check(CLI::Range(0.0, 1e7))
      ->capture_default_str();
  cmd->add_option("--seed", a->seed, "Seed of the sorts and the scene")->capture_default_str();
  cmd->add_flag("--raw", a->raw, "Write the camera's frames without the detections drawn on them");
  return [a] { return run_render(*a); };
}

}  // namespace hbirl::cli
