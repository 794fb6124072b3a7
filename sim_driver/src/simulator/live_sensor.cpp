// A sensor that publishes as it sees (live_sensor.hpp): a Simulation that grows one step at
// a time, published by the simulator's own messages.
#include "sim_driver/simulator/live_sensor.hpp"

#include <chrono>
#include <cmath>

#include "learner/input_error.hpp"
#include "problem/domain_file.hpp"

namespace hbirl {

namespace {
constexpr int kMaxContext = 65535;  // observations_t's contexts (docs/services.md "Services and channels")
constexpr int kMaxSymbols = 32767;  // observations_t's symbols are int16
}  // namespace

// The run so far: its episodes back to back in sim time (as SensorRun's), what was seen of
// each, one frame per step.
class LiveSensor::Run final : public Simulation {
 public:
  bool camera() const override { return false; }
  const ObservedTrajectory& observed(int id) const override { return seen[static_cast<size_t>(id)]; }
  std::vector<ObservedTrajectory> seen;
};

LiveSensor::LiveSensor(services::Bus& bus, const LiveSensorShape& shape, services::Counters& counters) : shape_(shape) {
  if (const std::string wrong = domain_name_problem(shape.domain); !wrong.empty())
    throw InputError("domain", "'" + shape.domain + "' " + wrong);
  if (shape.num_symbols < 1 || shape.num_symbols > kMaxSymbols)
    throw InputError("num_symbols", "must be in [1, " + std::to_string(kMaxSymbols) + "]");
  if (shape.num_sources < 1) throw InputError("num_sources", "must be at least 1 (the subject)");
  if (shape.num_end_symbols < 0 || shape.num_end_symbols > kMaxSymbols)
    throw InputError("num_end_symbols", "must be in [0, " + std::to_string(kMaxSymbols) + "]");
  if (!(shape.step_seconds > 0.0) || !std::isfinite(shape.step_seconds))
    throw InputError("step_seconds", "must be a positive number of seconds");
  if (!shape.true_weights.allFinite()) throw InputError("true_weights", "must be finite");
  auto run = std::make_unique<Run>();
  run->num_symbols = shape.num_symbols;
  run->num_sources = shape.num_sources;
  run->num_end_symbols = shape.num_end_symbols;
  run->step_seconds = shape.step_seconds;
  run->true_weights = shape.true_weights;
  run_ = run.get();
  simulator_ = std::make_unique<Simulator>(bus, shape.domain, std::move(run), SimulatorOptions{}, counters);
}

LiveSensor::~LiveSensor() = default;

bool LiveSensor::wait_for_optimiser(double seconds, const std::function<bool()>& stop) {
  return simulator_->wait_for_listeners(stop, seconds).empty();
}

int LiveSensor::begin_episode(bool controlled) {
  if (run_ended_) throw InputError("begin_episode", "the run has ended (end_run)");
  if (in_episode_)
    throw InputError("begin_episode", "episode " + std::to_string(episodes() - 1) + " is under way: end_episode first");
  double start = 0.0;
  if (!run_->episodes.empty()) {
    const Simulation::Episode& last = run_->episodes.back();
    start = last.start_time + static_cast<double>(last.steps.size()) * shape_.step_seconds;
  }
  Simulation::Episode e;
  e.controlled = controlled;
  e.start_time = start;
  e.has_truth = controlled;
  run_->episodes.push_back(e);
  ObservedTrajectory seen;
  seen.eta.resize(0, shape_.num_sources);
  run_->seen.push_back(std::move(seen));
  in_episode_ = true;
  const int id = episodes() - 1;
  simulator_->publish_begin(id);
  return id;
}

void LiveSensor::step(const std::vector<int>& symbols, const RowMatrix& eta, const std::vector<int>& contexts,
                      std::optional<StateAction> truth) {
  if (!in_episode_) throw InputError("step", "outside an episode: begin_episode first");
  const int id = episodes() - 1;
  Simulation::Episode& e = run_->episodes.back();
  ObservedTrajectory& seen = run_->seen.back();
  const auto n = static_cast<Eigen::Index>(symbols.size());
  if (eta.rows() != n || (n > 0 && eta.cols() != shape_.num_sources)) {
    throw InputError("eta", "must be " + std::to_string(n) + " x " + std::to_string(shape_.num_sources) +
                                " (a row of num_sources per symbol), not " + std::to_string(eta.rows()) + " x " +
                                std::to_string(eta.cols()));
  }
  for (size_t i = 0; i < symbols.size(); ++i) {
    if (symbols[i] < 0 || symbols[i] >= shape_.num_symbols) {
      throw InputError("symbols[" + std::to_string(i) + "]",
                       std::to_string(symbols[i]) + " is not in [0, " + std::to_string(shape_.num_symbols) + ")");
    }
  }
  RowMatrix checked = eta;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (const std::string wrong = normalise_eta(checked.row(i).data(), shape_.num_sources); !wrong.empty())
      throw InputError("eta[" + std::to_string(i) + "]", wrong);
  }
  if (!contexts.empty() && contexts.size() != symbols.size())
    throw InputError("contexts", "must give one per symbol (" + std::to_string(n) + "), or none");
  for (size_t i = 0; i < contexts.size(); ++i) {
    if (contexts[i] < 0 || contexts[i] > kMaxContext)
      throw InputError("contexts[" + std::to_string(i) + "]", "is not in [0, " + std::to_string(kMaxContext) + "]");
  }
  // Contexts are all or none, in the demonstrations and in the controlled run (the
  // optimiser keeps none of a set that gives them for some observations only).
  int& given = contexts_given_[e.controlled ? 1 : 0];
  if (n > 0 && given >= 0 && (given == 1) != !contexts.empty()) {
    throw InputError("contexts", std::string(given == 1 ? "missing" : "given") + ", where the " +
                                     (e.controlled ? "controlled run's" : "demonstrations'") + " observations before " +
                                     (given == 1 ? "had them" : "had none") +
                                     ": give them for every observation or none");
  }
  if (e.controlled && !truth)
    throw InputError("state", "a controlled episode's steps need their true state and action");
  if (!e.controlled && truth) throw InputError("state", "a demonstration's true steps are what is learned: give none");
  if (truth && (truth->state < 0 || truth->action < 0)) throw InputError("state", "a state and an action are >= 0");
  seen.symbols.insert(seen.symbols.end(), symbols.begin(), symbols.end());
  const Eigen::Index rows = seen.eta.rows();
  seen.eta.conservativeResize(rows + n, shape_.num_sources);
  if (n > 0) seen.eta.bottomRows(n) = checked;
  seen.contexts.insert(seen.contexts.end(), contexts.begin(), contexts.end());
  if (n > 0) given = contexts.empty() ? 0 : 1;
  seen.step_begin.push_back(seen.num_observations());
  e.steps.push_back(truth.value_or(StateAction{0, 0}));  // a demonstration's: a placeholder, never published
  const int t = static_cast<int>(e.steps.size()) - 1;
  simulator_->publish_step_begin(id, t);
  simulator_->publish_frame(id, t, 0);
}

void LiveSensor::end_episode(bool ends_in_terminal, int end_state, const std::vector<int>& end_symbols) {
  if (!in_episode_) throw InputError("end_episode", "outside an episode: begin_episode first");
  Simulation::Episode& e = run_->episodes.back();
  ObservedTrajectory& seen = run_->seen.back();
  if (e.steps.empty()) throw InputError("end_episode", "an episode needs at least one step");
  if (end_state < -1) throw InputError("end_state", "must be a state, or -1 (not known)");
  if (!ends_in_terminal && (end_state >= 0 || !end_symbols.empty()))
    throw InputError(end_state >= 0 ? "end_state" : "end_symbols",
                     "only an episode that ends in a terminal state has one");
  if (e.controlled && (end_state >= 0 || !end_symbols.empty()))
    throw InputError(end_state >= 0 ? "end_state" : "end_symbols",
                     "a controlled episode's end is known from its steps");
  for (size_t i = 0; i < end_symbols.size(); ++i) {
    if (end_symbols[i] < 0 || end_symbols[i] >= shape_.num_end_symbols) {
      throw InputError("end_symbols[" + std::to_string(i) + "]",
                       std::to_string(end_symbols[i]) + " is not in [0, " + std::to_string(shape_.num_end_symbols) +
                           ")" +
                           (shape_.num_end_symbols == 0 ? ": the sensor has no end sensor (num_end_symbols)" : ""));
    }
  }
  e.ends_in_terminal = ends_in_terminal;
  seen.ends_in_terminal = ends_in_terminal;
  seen.end_state = end_state;
  seen.end_symbols = end_symbols;
  in_episode_ = false;
  simulator_->publish_end(episodes() - 1);
}

void LiveSensor::end_run() {
  if (run_ended_) throw InputError("end_run", "the run has ended already");
  if (in_episode_)
    throw InputError("end_run", "episode " + std::to_string(episodes() - 1) + " is under way: end_episode first");
  if (episodes() == 0) throw InputError("end_run", "the run has no episode");
  run_ended_ = true;
  simulator_->publish_end_of_run();
}

int LiveSensor::handle(int timeout_ms) { return simulator_->handle(timeout_ms); }

bool LiveSensor::stop_requested() const { return simulator_->told_to_stop(); }

std::optional<Eigen::VectorXd> LiveSensor::wait_for_reward(double seconds, const std::function<bool()>& stop) {
  if (!run_ended_) throw InputError("wait_for_reward", "the run has not ended: end_run first");
  if (!(seconds >= 0.0) || !std::isfinite(seconds))
    throw InputError("timeout", "must be a finite number of seconds >= 0");
  seconds = std::min(seconds, 1e6);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                            std::chrono::duration<double>(seconds));
  simulator_->serve_until_learned([&] { return (stop && stop()) || std::chrono::steady_clock::now() >= until; });
  return simulator_->reward();
}

int LiveSensor::episodes() const { return static_cast<int>(run_->episodes.size()); }

std::int64_t LiveSensor::frames_resent() const { return simulator_->frames_resent(); }

}  // namespace hbirl
