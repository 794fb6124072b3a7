#pragma once
// What the dashboard shows, assembled from the bus (issue 6): the latest camera frame with
// its detections coloured by their most likely source (the labeller's eta), the newest
// demonstration's (s, a) posterior against ground truth, log-likelihood and ILE per EM
// iteration, learned theta against the true weights, the learned observation model, and
// every service's health. The web page (dashboard/web) and `hbirl report` read it as
// JSON (json()); the annotated frame comes as PNG (frame_png()).
//
// Thread-safe: the bus thread feeds it, the web server's threads read it.
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "hbirl/camera_frame_t.hpp"
#include "hbirl/detections_t.hpp"
#include "hbirl/em_progress_t.hpp"
#include "hbirl/estimate_t.hpp"
#include "hbirl/episode_marker_t.hpp"
#include "hbirl/ground_truth_t.hpp"
#include "hbirl/observation_model_t.hpp"
#include "hbirl/observations_t.hpp"
#include "hbirl/posterior_t.hpp"
#include "hbirl/reward_t.hpp"
#include "hbirl/service_status_t.hpp"
#include "services/bus.hpp"
#include "services/typed.hpp"
#include "sim_driver/registry/domain.hpp"

namespace hbirl::dashboard {

class DashboardState {
 public:
  // The page labels things with the names of the domain the EPISODE markers name: `given`
  // when it is that one (a domain file), else a built-in domain from the registry.
  explicit DashboardState(std::shared_ptr<const Domain> given = nullptr) : given_(std::move(given)) {}

  // Subscribes to every channel it shows; bad messages are counted in `counters`.
  void subscribe(services::Bus& bus, services::Counters& counters);

  // The handlers (each validates its message -- beyond its type's validate(), which typed
  // subscribe() has called: services/messages.hpp -- and throws InputError naming the field).
  // `now_utime` is the wall clock when it arrived (for heartbeat ages).
  void on_camera(const hbirl::camera_frame_t& m);
  void on_detections(const hbirl::detections_t& m);
  void on_observations(const hbirl::observations_t& m);
  void on_marker(const hbirl::episode_marker_t& m);
  void on_truth(const hbirl::ground_truth_t& m);
  void on_progress(const hbirl::em_progress_t& m);
  void on_reward(const hbirl::reward_t& m);
  void on_estimate(const hbirl::estimate_t& m);
  void on_status(const hbirl::service_status_t& m, std::int64_t now_utime);
  void on_model(const hbirl::observation_model_t& m);
  void on_posterior(const hbirl::posterior_t& m);

  // Everything the page shows. `now_utime`: wall clock, for heartbeat ages. Keys:
  //   version, domain, names {states, actions, features, symbols, sources}, source_colours,
  //   run {episode, step, controlled, ended, sim_seconds, frames, episodes_ended},
  //   camera {episode, step, frame, sim_seconds, width, height, detections [{class, box,
  //     symbol, symbol_name, eta, source}]} | null,
  //   observations {episode, step, frame, n, by_source_symbol [source][symbol]} | null,
  //   em [{iteration, log_likelihood, ile, seconds, retries, local_blocks}],
  //   theta {learned, true, final} | null, reward {final, ile, log_likelihood, policy {states, shown:
  //   [{state, action, probability}] in at most 100 states, by name}} | null,
  //   estimates [{demonstrations, confidence, ile_relative, seconds}] (the optimiser's
  //     estimate after each demonstration, --anytime; confidence and ILE null when unknown),
  //   posterior {episode, iteration, steps, state_marginals [t][state], action_marginals
  //     [t][action], most_likely
  //     [{state, action, probability}], truth [{state, action}] | null, log_likelihood} | null,
  //   model {iteration, num_states, num_actions, subject [pair][symbol], confounders
  //     [element][symbol]} | null,
  //   services [{id, service, state, seconds_since_heartbeat, messages_in, messages_out,
  //     bad_messages, gaps, trajectories, detail}], estep {retried_blocks, local_blocks} | null.
  // Unknown values are null (never NaN); strings from the network may hold invalid UTF-8:
  // dump with error_handler_t::replace.
  nlohmann::json json(std::int64_t now_utime) const;
  // The latest frame that has its detections and observations, annotated, as PNG; empty
  // when there is none yet.
  std::vector<unsigned char> frame_png() const;
  // Changes whenever anything shown changes.
  std::int64_t version() const;

 private:
  using Key = std::tuple<int, int, int>;  // (episode, step, frame)
  struct Pending {
    std::uint64_t order = 0;           // arrival: the oldest are dropped first
    std::vector<unsigned char> image;  // encoded, as sent
    std::int64_t utime = 0;            // the camera's
    std::optional<hbirl::detections_t> detections;
  };
  struct Frame {
    Key key{};
    std::int64_t utime = 0;
    std::vector<unsigned char> image;
    hbirl::detections_t detections;
    hbirl::observations_t observations;
  };
  struct Service {
    hbirl::service_status_t status;
    std::int64_t heard_utime = 0;  // wall clock when it arrived
  };
  void changed() { ++version_; }
  void set_domain(const std::string& domain);

  mutable std::mutex mutex_;
  std::int64_t version_ = 0;
  std::shared_ptr<const Domain> given_;
  std::shared_ptr<const Domain> domain_object_;  // of domain_
  std::string domain_;
  int num_sources_ = 0;
  // The run.
  int episode_ = -1, step_ = -1;
  bool controlled_ = false, run_ended_ = false;
  std::int64_t sim_utime_ = 0, frames_ = 0;
  int episodes_ended_ = 0;
  std::map<int, std::map<int, std::pair<int, int>>> truth_;  // episode -> step -> (s, a)
  std::optional<std::vector<double>> true_weights_;
  // The camera.
  std::map<Key, Pending> pending_;
  std::uint64_t pending_order_ = 0;
  std::optional<Frame> frame_;
  std::int64_t frame_serial_ = 0;  // counts frame_ changes
  mutable std::int64_t png_version_ = -1;
  mutable std::vector<unsigned char> png_;
  std::optional<hbirl::observations_t> last_observations_;
  // Learning.
  std::vector<hbirl::em_progress_t> progress_;
  std::optional<hbirl::reward_t> reward_;
  std::vector<hbirl::estimate_t> estimates_;  // without their policies
  std::optional<hbirl::observation_model_t> model_;
  std::optional<hbirl::posterior_t> posterior_;
  std::map<std::string, Service> services_;
  services::Subscriptions subs_;  // last: ends first
};

}  // namespace hbirl::dashboard
