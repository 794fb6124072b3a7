#pragma once
// The optimiser service (docs/services.md "Services and channels"): the data set off the bus (dataset.hpp),
// HiddenDataEM with the E-step on the sampler workers (estep_service.hpp), EM_PROGRESS,
// OBSERVATION_MODEL and POSTERIOR while it learns, and the final REWARD.
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "app/output.hpp"
#include "hbirl/em_progress_t.hpp"
#include "hbirl/estimate_t.hpp"
#include "hbirl/frame_request_t.hpp"
#include "hbirl/observation_model_t.hpp"
#include "hbirl/posterior_t.hpp"
#include "hbirl/reward_t.hpp"
#include "services/channels.hpp"
#include "services/dataset.hpp"
#include "services/estep_service.hpp"
#include "app/learn.hpp"
#include "services/learning.hpp"
#include "problem/json_format.hpp"
#include "sim_driver/registry/domain.hpp"

namespace hbirl::services {

// A recorded run to read: the lcm-logger file, the run's key when it was signed (every
// message is then checked against it, keyed_bus.hpp), and whether a recording that never
// reached END_RUN (a run cut short) may still be learned from.
struct RecordedRun {
  std::string path;
  std::string key_file;
  bool allow_incomplete = false;
};

struct OptimiserOptions {
  // The domain learned on; null: the built-in domain the EPISODE markers name (a domain
  // file must be given: a name off the bus never opens a file).
  std::shared_ptr<const Domain> domain;
  app::LearnSettings learning;  // how it learns (app/learn_settings.hpp)
  BusExecutorOptions executor;
  int workers = 0;  // wait for this many sampler workers before learning
  int wait_workers_ms = 10000;
  int resend_after_ms = 1000;  // after END_RUN, ask for missing frames when none came for this long
  // A run whose frames stop coming before it is complete: learned from what came (and
  // said so: OptimiserResult::incomplete) only when allowed, after quiet_ms without a
  // frame; otherwise it fails (RunFailed) after incomplete_after_ms without one, asking
  // for them again all the while (a hung or restarted service may still send them).
  bool allow_incomplete = false;
  int quiet_ms = 5000;
  int incomplete_after_ms = 60000;
  // Once the run is complete, wait up to this long for END_RUN to be heard again (the
  // simulator repeats it each second): what comes meanwhile may contradict the run.
  int confirm_ms = 1500;
  // The run's lcm-logger recording (its path and the run's key; no path: none): once the
  // run is complete, followed until it holds the whole run too, what lcm-logger lost asked
  // for again (RecordingWatch); given up, and said, after recording_patience_ms in which
  // it gained nothing (lcm-logger stopped?): the run is learned from all the same. After
  // learning, the REWARD is sent again until the recording holds it (the same patience).
  RecordedRun recording;
  int recording_patience_ms = 10000;
  // The most memory the run's observations may take (hbirl-optimiser --max-dataset-mb):
  // frames beyond it are refused, counted, and not kept (DatasetBuilder::limit).
  std::int64_t max_dataset_bytes = std::int64_t{2048} << 20;
  // An estimate after each demonstration that ends with every frame's observations
  // (ESTIMATE), while the run goes on: what app::learn gives on the demonstrations so far,
  // EM also started from the previous estimate (app::learn_anytime's rule), learned here
  // rather than on the workers (a few demonstrations); with its confidence when
  // learning.posterior.samples > 0. The final REWARD is learned as without it.
  bool anytime = false;
  // Knowing when it has seen enough (0: never): once `stop_after` estimates in a row have
  // a confidence >= stop_at_confidence, STOP asks the sensor side to end the run (repeated
  // after every estimate while the rule holds). Needs anytime and posterior draws.
  double stop_at_confidence = 0.0;
  int stop_after = app::StopRule::kDefaultAfter;
  // Called often (every ~100 ms while collecting, every EM iteration) with what the
  // optimiser is doing ("collecting", "learning"): the process beats its heartbeat there,
  // so services that wait for it (the simulator) and the dashboard hear it throughout.
  std::function<void(const std::string&)> beat;
};
// A run that cannot be learned from: what it lacks or how it contradicts itself, in one line.
struct RunFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct OptimiserResult {
  Learned learned;
  Dataset data;
  std::int64_t missing_frames = 0;  // never came, even when asked for again
  int frame_requests = 0;           // FRAME_REQUEST messages sent (the run's losses and the recording's)
  std::string recording;            // what became of the recording followed: "complete", "lacks ..." ("": none)
  int workers = 0;
  BusBlockExecutor::Stats estep;
  std::string incomplete;  // learned with allow_incomplete from a run that lacks this ("" when complete)
  std::vector<hbirl::estimate_t> estimates;  // published while collecting (OptimiserOptions::anytime)
  int stop_sent_after = 0;                   // demonstrations when STOP was first sent (0: never)
};
// Collects the run, learns, publishes EM_PROGRESS and the final REWARD (with a recording
// followed, returns once the recording holds it, or once given up). nullopt if asked
// to stop first; throws RunFailed for a run that is incomplete (unless allowed) or
// contradicts itself (then no REWARD is published).
// `ready` is called once it listens (so a simulator may start).
std::optional<OptimiserResult> run_optimiser(Bus& bus, const OptimiserOptions& options, Counters& counters,
                                             const std::function<bool()>& stop,
                                             const std::function<void(const std::string&)>& log = nullptr,
                                             const std::function<void()>& ready = nullptr);

// The data set of a recorded log, as the live optimiser collected it (up to the moment
// the run was complete; the rest of the log is read for contradictions); `learned` is
// left empty. Throws InputError for unusable logs: damaged, signed with another key,
// holding messages of more than one run (when the key file names none), a run that
// contradicts itself -- and a log whose run never completed, unless allow_incomplete
// (then `incomplete` says what is missing).
OptimiserResult collect_from_log(const RecordedRun& run, Counters& counters);

// Learns offline from a recorded log (hbirl learn --log): the same data set and the same
// learning as the live optimiser, computed here. `domain` as OptimiserOptions::domain.
// Throws InputError for unusable logs.
OptimiserResult learn_from_log(const RecordedRun& run, const app::LearnSettings& settings, Counters& counters,
                               std::shared_ptr<const Domain> domain = nullptr);

// What a learned run reports, in hbirl-optimiser's result and hbirl learn --log's alike
// (docs/services.md "Services and channels"): the domain, theta and how it was learned, and the
// data it came from. `domain` as domain_of's `given`. Json: nlohmann::json or ordered_json.
template <class Json>
void add_learned_run(Json& j, const OptimiserResult& r, std::shared_ptr<const Domain> domain);

// The domain a data set was collected in: `given` when not null (the markers must name
// it), else the built-in domain the markers name. Throws InputError("episode_marker.domain", ...).
std::shared_ptr<const Domain> domain_of(const Dataset& data, std::shared_ptr<const Domain> given);

template <class Json>
void add_learned_run(Json& j, const OptimiserResult& r, std::shared_ptr<const Domain> domain) {
  const auto vector = [](const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
  j["domain"] = r.data.domain;
  const std::shared_ptr<const Domain> learned_in = domain_of(r.data, std::move(domain));
  const DomainNames names = learned_in->names(1);
  j["feature_names"] = names.features;
  j["weights"] = vector(r.learned.theta);
  if (r.data.true_weights) j["true_weights"] = vector(*r.data.true_weights);
  if (r.learned.ile) j["ile"] = *r.learned.ile;
  j["log_likelihood"] = r.learned.log_likelihood;
  j["em_iterations"] = r.learned.em_iterations;
  if (r.learned.confidence) j["confidence"] = *r.learned.confidence;  // with posterior draws (hbirl learn --log)
  if (r.learned.eta) {
    // Rows are the labeller's rules only when every observation came with its context
    // (none given, or dropped as contexts_note says: each distinct eta is a row).
    const bool by_rule = r.data.contexts_note.empty() && every_observation_has_context(r.data.observed);
    const std::vector<std::string> no_names;
    j["learned_eta"] = learned_eta_json(*r.learned.eta, by_rule ? names.contexts : no_names);
  }
  if (r.learned.end_sensor.size() > 0) {  // the learned O_end per terminal state: [state, probabilities]
    const Mdp& mdp = learned_in->mdp();
    Json end = Json::array();
    for (int s = 0; s < mdp.num_states; ++s) {
      if (mdp.is_terminal(s)) end.push_back({s, vector(r.learned.end_sensor.row(s).transpose())});
    }
    j["end_sensor"] = end;
  }
  j["policy"] = app::policy_json<Json>(r.learned.policy, names.states, names.actions);
  j["demonstrations"] = r.learned.trajectories;
  j["controlled_episodes"] = r.data.controlled_observed.size();
  j["dataset_digest"] = r.learned.digest;
  j["missing_frames"] = r.missing_frames;
}

}  // namespace hbirl::services
