// The optimiser service (optimiser.hpp).
#include "services/optimiser.hpp"

#include <chrono>
#include <memory>
#include <sstream>

#include "app/learn.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "learner/soft_value_iteration.hpp"
#include "services/lcm_arrays.hpp"
#include "services/keyed_bus.hpp"
#include "services/log_bus.hpp"
#include "services/recording_watch.hpp"

namespace hbirl::services {

namespace {
using Clock = std::chrono::steady_clock;
// The optimiser's progress lines on stderr start so (services/launch.sh shows the latest),
// at most this often.
constexpr const char* kProgress = "progress: ";
constexpr auto kProgressEvery = std::chrono::seconds(2);
constexpr size_t kFramesPerRequest = 500;  // frames asked for in one FRAME_REQUEST
}  // namespace

namespace {

// For the dashboard: the learned observation model, and the newest demonstration's
// posterior as the E-step's last pass computed it (nothing is computed again here).
void publish_model(Bus& bus, Counters& counters, const Mdp& mdp, const Dataset& data, std::int64_t utime, int iteration,
                   const ObservationPrior& alpha, const EStepResult& estep, const LearnedEta* eta) {
  const ObservationModel model = dirichlet_mean(alpha);
  hbirl::observation_model_t o{};
  o.utime = utime;
  o.domain = data.domain;
  o.iteration = iteration;
  o.num_states = mdp.num_states;
  o.num_actions = mdp.num_actions;
  o.num_pairs = mdp.num_pairs();
  o.num_symbols = model.num_symbols();
  o.num_confounders = model.num_confounders();
  o.subject = lcm_rows(model.subject);
  o.confounders = lcm_rows(model.confounders);
  // Learned eta for display; a sensor without contexts whose every eta differs has as many
  // contexts as observations, which no page shows: then none.
  if (eta && eta->learned.rows() <= kMaxContexts) {
    o.num_contexts = static_cast<std::int32_t>(eta->learned.rows());
    o.num_sources = static_cast<std::int32_t>(eta->learned.cols());
    o.stated_eta = lcm_rows(eta->stated);
    o.learned_eta = lcm_rows(eta->learned);
    o.context_observations = lcm_vector(eta->observations);
  }
  publish(bus, channels::kObservationModel, o, counters);
  if (data.observed.empty() || estep.watched.rows() == 0) return;  // an impossible trajectory has none
  hbirl::posterior_t p{};
  p.utime = utime;
  p.domain = data.domain;
  p.iteration = iteration;
  p.episode = data.episodes.back();
  p.num_steps = static_cast<std::int32_t>(estep.watched.rows());
  p.num_states = mdp.num_states;
  p.num_actions = mdp.num_actions;
  p.num_pairs = mdp.num_pairs();
  p.marginals = lcm_rows(estep.watched);
  p.log_likelihood = estep.watched_log_likelihood;
  publish(bus, channels::kPosterior, p, counters);
}

// A run no observation of which came (a sensor stopped at once, learned from with
// --allow-incomplete) has episodes but no alphabet or sources: the domain's, and the
// subject alone when the domain does not state its confounding elements. Learning from it
// gives what the controlled run and the prior say.
void size_unobserved(Dataset& data, const Domain& domain) {
  if (data.num_symbols > 0) return;
  data.num_symbols = domain.num_symbols();
  const std::optional<ObservationPrior> stated = domain.stated_prior();
  data.num_sources = stated ? 1 + stated->num_confounders : 1;
  for (auto* set : {&data.observed, &data.controlled_observed}) {
    for (auto& t : *set) t.eta.resize(0, data.num_sources);
  }
}

// Collects the run from the bus until it is complete. Collected until complete; then
// confirmed: until END_RUN is heard again (or confirm_ms passes), what comes may still
// contradict the run (an END_RUN forged early, then the sensor's next episode) or show it
// was not complete after all (an END_RUN that stated no number of episodes, before the
// sensor's next one began): then collected again.
class RunCollector {
 public:
  // `on_data`: called after every message while collecting (the live estimates).
  RunCollector(Bus& bus, DatasetBuilder& builder, const OptimiserOptions& options, Counters& counters,
               const std::function<bool()>& stop, const std::function<void(const std::string&)>& log,
               std::function<void()> on_data = nullptr)
      : bus_(bus),
        builder_(builder),
        options_(options),
        counters_(counters),
        stop_(stop),
        log_(log),
        on_data_(std::move(on_data)) {}

  // False when asked to stop.
  bool collect() {
    for (;;) {
      if (!collect_until_complete()) return false;
      if (stopped()) return false;
      if (!incomplete_.empty() || ended_) break;  // learning from what came, as allowed (or all there is)
      if (confirmed()) {
        complete_the_recording();
        if (builder_.complete() || ended_) break;
      }
      say("the run went on after it seemed complete: collecting on");
    }
    return !stopped();
  }

  void check_contradiction() const {
    if (!builder_.contradiction().empty()) {
      throw RunFailed(
          "the run contradicts itself: " + builder_.contradiction() +
          " (a forged or stray message? without a run key anyone on the bus can send one; docs/RELIABILITY.md)");
    }
  }

  // What a run learned from as allowed lacks ("" when complete).
  const std::string& incomplete() const { return incomplete_; }
  // FRAME_REQUEST messages sent (for the optimiser's losses and the recording's).
  int frame_requests() const { return frame_requests_; }

  // The run's REWARD was published at `sent` (publish_reward sends it again and returns
  // when it did). Until the recording holds it too, it is sent again each time the
  // recording shows it lost: a message that reached lcm-logger after the REWARD was sent
  // is recorded, the REWARD is not (lcm-logger reads its socket in arrival order).
  // lcm-logger drops what comes faster than it reads (LCM keeps at most ~30 messages per
  // subscription waiting; the end of learning is such a burst) and cannot ask again, and a
  // recording without its REWARD is a run that never finished to its readers
  // (docs/RELIABILITY.md "A recording holds the whole run"). Our heartbeats, once a second,
  // make lcm-logger write what it has. Not for a recording given up on (lcm-logger stopped
  // or dead); given up, and said, after recording_patience_ms in which the recording
  // gained nothing, 30 sendings, or six times that patience in all.
  void record_the_reward(std::int64_t utime, std::int64_t sent, const std::function<std::int64_t()>& publish_reward) {
    const bool followed = recording_ == "complete" || (recording_.empty() && !options_.recording.path.empty());
    if (!followed || ended_) return;  // (an ended bus: a log, where nothing more comes or goes)
    if (!watch_) {                    // learned as allowed from an incomplete run: the REWARD alone is followed
      watch_ = std::make_unique<RecordingWatch>(options_.recording.path, options_.recording.key_file,
                                                options_.max_dataset_bytes);
    }
    watch_->follow_rewards_only();  // (the run's tally is not held any longer)
    const auto patience =
        std::chrono::milliseconds(std::max(options_.recording_patience_ms, 3 * options_.resend_after_ms));
    constexpr int kMostSendings = 30;
    int sendings = 1;
    std::int64_t had = -1;
    const auto since = Clock::now();
    auto last_gain = since;
    const auto give_up = [&](const std::string& why) {
      recording_ = "lacks the run's reward (REWARD)";
      say("the recording " + options_.recording.path + " " + recording_ + ", " + why +
          ": hbirl report will call the run unfinished");
    };
    while (!stopped() && !ended_) {
      try {
        watch_->read(std::chrono::milliseconds(200));
      } catch (const InputError& e) {  // rewritten as something else meanwhile
        give_up(std::string("for it cannot be followed: ") + e.what());
        return;
      }
      if (watch_->holds_reward(utime)) {
        if (sendings > 1) say("the recording holds the reward now: lcm-logger lost it, and it came again");
        return;
      }
      const auto now = Clock::now();
      if (watch_->last_arrival_utime() != had) {
        had = watch_->last_arrival_utime();
        last_gain = now;
      }
      if (now - last_gain > patience) {
        give_up("and has gained nothing for " + std::to_string(patience.count() / 1000) + " s (lcm-logger stopped?)");
        return;
      }
      if (now - since > 6 * patience) {  // (a watch that never reads to the end of what comes)
        give_up("after " + std::to_string(6 * patience.count() / 1000) + " s");
        return;
      }
      if (watch_->caught_up() && watch_->last_arrival_utime() > sent) {  // lost: what came after it is there
        if (sendings == kMostSendings) {
          give_up("though sent " + std::to_string(sendings) + " times (lcm-logger lost it each time)");
          return;
        }
        sent = publish_reward();
        ++sendings;
      }
      if (options_.beat) options_.beat("recording");
      ended_ = bus_.handle(50) < 0;
    }
    give_up(ended_ ? "for the bus ended first" : "for the optimiser was stopped first");
  }
  // What became of the run's recording: "complete", "lacks ...", "cannot be followed: ..."
  // ("": none followed, OptimiserOptions::recording).
  const std::string& recording() const { return recording_; }

 private:
  bool stopped() const { return stop_ && stop_(); }
  void say(const std::string& s) const {
    if (log_) log_(s);
  }

  // Until the builder is complete, the bus has ended or a quiet run is learned from as it
  // is; false when asked to stop.
  bool collect_until_complete() {
    while (!builder_.complete()) {
      if (stopped()) return false;
      if (options_.beat) options_.beat("collecting");
      if (bus_.handle(100) < 0) {
        ended_ = true;
        break;
      }
      check_contradiction();
      if (on_data_) on_data_();
      // Progress: a frame, or an episode's end (a restarted optimiser asks for every end
      // marker first, 500 a request, before any frame).
      if (builder_.frames() != frames_ || builder_.ended_episodes() != ends_) {
        frames_ = builder_.frames();
        ends_ = builder_.ended_episodes();
        last_frame_ = Clock::now();
      }
      if (builder_.run_ended() && !announced_end_) {
        say("end of the run announced; " + std::to_string(builder_.frames()) + " frames observed so far");
        announced_end_ = true;
      }
      ask_for_lost_frames();
      report_progress();
      if (quiet_too_long()) break;
    }
    return true;
  }

  // A progress line (kProgress) every few seconds while frames come: what a person waiting
  // for the run sees (services/launch.sh shows the latest).
  void report_progress() {
    const auto now = Clock::now();
    if (builder_.frames() == 0 || now - last_progress_ < kProgressEvery) return;
    last_progress_ = now;
    // The controlled run comes first and has no demonstrations: said apart, so that its
    // minutes do not read as "0 demonstrations" of a stuck run.
    const int controlled = builder_.controlled_episodes();
    say(std::string(kProgress) + "collecting: " + std::to_string(builder_.episodes()) + " episodes begun (" +
        std::to_string(controlled) + " controlled, " + std::to_string(builder_.episodes() - controlled) +
        " demonstrations), " + std::to_string(builder_.complete_demonstrations()) + " demonstrations complete, " +
        std::to_string(builder_.frames()) + " frames");
  }

  // Frames lost on the way: ask for them again (a few hundred per request), once a second.
  void ask_for_lost_frames() {
    if (builder_.end_run_heard() && Clock::now() - last_frame_ > std::chrono::milliseconds(options_.resend_after_ms) &&
        Clock::now() - last_request_ > std::chrono::milliseconds(options_.resend_after_ms)) {
      ask_again(builder_.missing_frame_keys(kFramesPerRequest), "lost frame(s)");
      last_request_ = Clock::now();
    }
  }

  // One FRAME_REQUEST for `missing` (episode, step, frame), if any.
  void ask_again(const std::vector<std::tuple<int, int, int>>& missing, const std::string& what) {
    if (missing.empty()) return;
    hbirl::frame_request_t r{};
    r.utime = builder_.build_utime();
    r.requester = "optimiser";
    r.n = static_cast<std::int32_t>(missing.size());
    for (const auto& [episode, step, frame] : missing) {
      r.episode.push_back(episode);
      r.step.push_back(step);
      r.frame.push_back(frame);
    }
    publish(bus_, channels::kFrameRequest, r, counters_);
    say("asked again for " + std::to_string(missing.size()) + " " + what);
    ++frame_requests_;
  }

  // The run is complete here: until its recording is too (OptimiserOptions::recording),
  // what lcm-logger lost is asked for again once a second -- the sensor side sends it to
  // every listener, the logger among them. Given up, and said, once the recording has
  // gained nothing for recording_patience_ms (at least three requests' time): the run is
  // learned from all the same. The watch's tally (a second copy of the data's keys) is
  // dropped before learning (record_the_reward follows the REWARD alone).
  void complete_the_recording() {
    if (options_.recording.path.empty()) return;
    watch_ = std::make_unique<RecordingWatch>(options_.recording.path, options_.recording.key_file,
                                              options_.max_dataset_bytes);
    RecordingWatch& recording = *watch_;
    const auto patience =
        std::chrono::milliseconds(std::max(options_.recording_patience_ms, 3 * options_.resend_after_ms));
    std::int64_t had = -2;
    int asked = 0;
    auto last_gain = Clock::now(), last_request = Clock::now();
    while (!stopped() && !ended_ && builder_.complete()) {
      try {
        recording.read(std::chrono::milliseconds(200));
      } catch (const InputError& e) {  // not a recording: nothing to complete, the run is
        recording_ = std::string("cannot be followed: ") + e.what();
        say("the recording " + recording_ + "; learning from the complete run");
        watch_.reset();
        break;
      }
      if (recording.complete()) {
        recording_ = "complete";
        if (asked > 0) say("the recording holds the whole run now: what lcm-logger lost came again");
        break;
      }
      const auto now = Clock::now();
      if (recording.progress() != had || !recording.caught_up()) {
        had = recording.progress();
        last_gain = now;
      }
      if (now - last_gain > patience) {
        recording_ = "lacks " + recording.lacks();
        say("the recording " + recording.path() + " " + recording_ +
            ", which did not come again (lcm-logger stopped?): hbirl learn --log will refuse it; learning from "
            "the complete run");
        break;
      }
      if (recording.caught_up() && now - last_request > std::chrono::milliseconds(options_.resend_after_ms)) {
        ask_again(recording.missing_frame_keys(kFramesPerRequest), "frame(s) the recording lacks");
        ++asked;
        last_request = now;
      }
      if (options_.beat) options_.beat("collecting");
      ended_ = bus_.handle(50) < 0;
      check_contradiction();
    }
    // The wait is no silence of the run's (quiet_too_long counts from the last frame).
    last_frame_ = Clock::now();
    frames_ = builder_.frames();
    if (watch_ && recording_ == "complete") {
      watch_->follow_rewards_only();
    } else {
      watch_.reset();
    }
  }

  // Nothing for too long after the end of the run: the run fails (RunFailed) or, with
  // allow_incomplete, is learned from as it is (incomplete_ says what it lacks).
  bool quiet_too_long() {
    const auto quiet = Clock::now() - last_frame_;
    if (!(builder_.run_ended() &&
          quiet > std::chrono::milliseconds(options_.allow_incomplete ? options_.quiet_ms
                                                                      : options_.incomplete_after_ms))) {
      return false;
    }
    incomplete_ = std::to_string(builder_.missing_frames()) + " frame(s) and " +
                  std::to_string(builder_.missing_truth()) + " ground-truth step(s) missing, " +
                  std::to_string(builder_.unfinished_episodes()) + " episode(s) without their end";
    const std::string waited = std::to_string(std::chrono::duration_cast<std::chrono::seconds>(quiet).count());
    if (!options_.allow_incomplete) {
      throw RunFailed(
          "the run is incomplete: " + incomplete_ + ", and nothing came for " + waited +
          " s though asked for again (a service that stopped or hung?); --allow-incomplete learns from what came");
    }
    say("no frames for " + waited + " s after the end of the run: learning from what came (" + incomplete_ +
        "), as allowed");
    return true;
  }

  // Whether the run stayed complete (or the bus ended) until END_RUN was heard again or
  // confirm_ms passed.
  bool confirmed() {
    const std::int64_t heard = builder_.end_runs_heard();
    const auto until = Clock::now() + std::chrono::milliseconds(options_.confirm_ms);
    while (!ended_ && builder_.complete() && builder_.end_runs_heard() == heard && Clock::now() < until && !stopped()) {
      if (options_.beat) options_.beat("collecting");
      ended_ = bus_.handle(50) < 0;
      check_contradiction();
    }
    last_frame_ = Clock::now();  // (the confirmation's wait is no silence of the run's either)
    frames_ = builder_.frames();
    return builder_.complete() || ended_;
  }

  Bus& bus_;
  DatasetBuilder& builder_;
  const OptimiserOptions& options_;
  Counters& counters_;
  const std::function<bool()>& stop_;
  const std::function<void(const std::string&)>& log_;
  std::function<void()> on_data_;
  std::int64_t frames_ = -1;
  int ends_ = 0;  // ended episodes, as frames_
  Clock::time_point last_frame_ = Clock::now();
  Clock::time_point last_request_ = Clock::now();
  int frame_requests_ = 0;
  std::string recording_;                  // what became of the recording ("": none followed)
  std::unique_ptr<RecordingWatch> watch_;  // the recording followed, once the run is complete
  bool announced_end_ = false;
  Clock::time_point last_progress_ = Clock::now();
  std::string incomplete_;
  bool ended_ = false;  // the bus has (a log at its end)
};

// The final REWARD's learning: as hbirl learn --log's, without posterior draws (they are
// the live estimates' confidence; the REWARD carries none).
app::LearnSettings final_settings(app::LearnSettings settings) {
  settings.posterior.samples = 0;
  return settings;
}

// The estimate after each demonstration (OptimiserOptions::anytime): when more
// demonstrations are complete than last time, learned on the data so far (here, one
// thread), EM also started from the last estimate, and published on ESTIMATE. A data set
// that cannot be learned from yet (no subject prior, say) is skipped, said once: a live
// estimate never ends the run.
class LiveEstimator {
 public:
  LiveEstimator(Bus& bus, const OptimiserOptions& options, Counters& counters,
                const std::function<void(const std::string&)>& log)
      : bus_(bus), options_(options), counters_(counters), log_(log) {}

  // An estimate for each demonstration n of the complete prefix not yet estimated, in
  // order (several, when several came at once): the same estimates whatever the timing.
  void update(const DatasetBuilder& builder) {
    if (builder.complete_demonstrations() == complete_seen_) return;  // nothing ended since (a cheap test)
    complete_seen_ = builder.complete_demonstrations();
    const int ready = builder.complete_demonstration_prefix();
    if (ready <= estimated_) return;
    const Dataset data = builder.build();
    for (int n = estimated_ + 1; n <= ready; ++n) estimate(first_demonstrations(data, static_cast<size_t>(n)));
    estimated_ = ready;
  }

  std::vector<hbirl::estimate_t> take() { return std::move(estimates_); }

 private:
  void estimate(Dataset data) {
    const auto start = Clock::now();
    try {
      const std::shared_ptr<const Domain> domain = domain_of(data, options_.domain);
      size_unobserved(data, *domain);
      app::LearnSettings settings = options_.learning;
      settings.em.warm_start = previous_;
      const Learned learned = learn_from_dataset(*domain, data, settings);
      previous_ = learned.theta;
      publish_estimate(*domain, data, learned, std::chrono::duration<double>(Clock::now() - start).count());
    } catch (const std::exception& e) {  // a live estimate never ends the run: the final learning says what is wrong
      if (!said_) say("no estimate yet from " + std::to_string(data.observed.size()) + " demonstrations: " + e.what());
      said_ = true;
    }
  }

  void say(const std::string& s) const {
    if (log_) log_(s);
  }

  void publish_estimate(const Domain& domain, const Dataset& data, const Learned& learned, double seconds) {
    const Mdp& mdp = domain.mdp();
    hbirl::estimate_t e{};
    e.utime = data.last_utime;
    e.domain = data.domain;
    e.demonstrations = static_cast<std::int32_t>(data.observed.size());
    e.num_features = static_cast<std::int32_t>(learned.theta.size());
    e.theta = lcm_vector(learned.theta);
    e.log_likelihood = learned.log_likelihood;
    e.confidence = learned.confidence.value_or(-1.0);
    e.ile = e.ile_relative = -1.0;
    if (const auto truth = true_weights_of(domain, data)) {
      const InverseLearningError ile = inverse_learning_error(mdp, *truth, learned.theta);
      e.ile = ile.ile;
      e.ile_relative = ile.relative();
    }
    const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(learned.theta));
    e.num_states = mdp.num_states;
    e.num_actions = mdp.num_actions;
    e.policy = lcm_rows(RowMatrix::Map(policy.policy.data(), mdp.num_states, mdp.num_actions));
    e.seconds = seconds;
    publish(bus_, channels::kEstimate, e, counters_);
    estimates_.push_back(e);
    char line[160];
    std::snprintf(line, sizeof line, "estimate after %d demonstrations: confidence %.3f, %.3f s", e.demonstrations,
                  e.confidence, seconds);
    say(line);
    apply_stop_rule(e);
  }

  // The stop rule (OptimiserOptions::stop_at_confidence): k estimates in a row at or above
  // p, then STOP after this and every later estimate while it holds.
  void apply_stop_rule(const hbirl::estimate_t& e) {
    if (options_.stop_at_confidence <= 0.0 || !stop_rule_.holds_with(e.confidence)) return;
    hbirl::stop_t m{};
    m.utime = e.utime;
    m.domain = e.domain;
    m.demonstrations = e.demonstrations;
    m.confidence = e.confidence;
    char reason[120];
    std::snprintf(reason, sizeof reason, "confidence >= %g for %d estimates in a row", options_.stop_at_confidence,
                  stop_rule_.streak());
    m.reason = reason;
    publish(bus_, channels::kStop, m, counters_);
    if (stop_sent_after_ == 0) {
      stop_sent_after_ = e.demonstrations;
      say("seen enough: " + m.reason + " (after " + std::to_string(e.demonstrations) + "); STOP sent");
    }
  }

 public:
  int stop_sent_after() const { return stop_sent_after_; }

 private:
  Bus& bus_;
  const OptimiserOptions& options_;
  Counters& counters_;
  const std::function<void(const std::string&)>& log_;
  app::StopRule stop_rule_{options_.stop_at_confidence, options_.stop_after};
  int stop_sent_after_ = 0;
  int estimated_ = 0;       // demonstrations estimated from
  int complete_seen_ = -1;  // the builder's complete demonstrations at the last look
  std::optional<Eigen::VectorXd> previous_;
  bool said_ = false;
  std::vector<hbirl::estimate_t> estimates_;
};

// A builder of the run's data set, subscribed to the bus (expecting the domain's sizes when
// the domain is given).
std::unique_ptr<DatasetBuilder> subscribed_builder(Bus& bus, const OptimiserOptions& options, Counters& counters) {
  auto builder = std::make_unique<DatasetBuilder>();
  if (options.domain) {
    const std::optional<ObservationPrior> stated = options.domain->stated_prior();
    const Mdp& mdp = options.domain->mdp();
    builder->expect(options.domain->name(), options.domain->num_symbols(), stated ? 1 + stated->num_confounders : 0,
                    mdp.num_states, mdp.num_actions);
    builder->expect_ends(std::vector<char>(mdp.terminal.begin(), mdp.terminal.end()),
                         stated ? stated->num_end_symbols() : 0);
  }
  builder->limit(options.max_dataset_bytes);
  builder->subscribe(bus, counters);
  return builder;
}

// EM_PROGRESS after an EM iteration: its log-likelihood and theta, theta's ILE when the true
// weights are known, the E-step's retried and local blocks, and the seconds since `start`.
void publish_progress(Bus& bus, Counters& counters, const Mdp& mdp, std::int64_t utime, int iteration, double ll,
                      const Eigen::VectorXd& theta, const ObservationPrior& alpha,
                      const std::optional<Eigen::VectorXd>& truth, const BusBlockExecutor& executor,
                      Clock::time_point start) {
  hbirl::em_progress_t p{};
  p.utime = utime;
  p.restart = 0;
  p.iteration = iteration;
  p.log_likelihood = ll;
  p.prior_strength = alpha.learn && alpha.update == AlphaUpdate::kPosterior ? alpha.strength : 0.0;
  p.ile = truth ? inverse_learning_error(mdp, *truth, theta).ile : -1.0;
  p.num_features = static_cast<std::int32_t>(theta.size());
  p.theta = lcm_vector(theta);
  const auto s = executor.stats();
  p.retries = static_cast<std::int32_t>(s.retried_blocks);
  p.local_blocks = static_cast<std::int32_t>(s.local_blocks);
  p.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  publish(bus, channels::kEmProgress, p, counters);
}

// REWARD: the learned theta, its soft policy and optimal actions and, when known, the true
// weights and the ILE.
hbirl::reward_t reward_message(const Mdp& mdp, const OptimiserResult& result, std::int64_t utime,
                               const std::optional<Eigen::VectorXd>& truth) {
  hbirl::reward_t r{};
  r.utime = utime;
  r.domain = result.data.domain;
  r.final = true;
  r.num_features = static_cast<std::int32_t>(result.learned.theta.size());
  r.theta = lcm_vector(result.learned.theta);
  r.num_true = truth ? static_cast<std::int32_t>(truth->size()) : 0;
  if (truth) r.true_theta = lcm_vector(*truth);
  const SoftSolution policy = soft_value_iteration(mdp, mdp.features * result.learned.theta);
  r.num_states = mdp.num_states;
  r.num_actions = mdp.num_actions;
  r.policy = lcm_rows(RowMatrix::Map(policy.policy.data(), mdp.num_states, mdp.num_actions));  // pairs are s * A + a
  r.action.assign(static_cast<size_t>(mdp.num_states), -1);
  for (const app::PolicyStep& step : result.learned.policy) r.action[static_cast<size_t>(step.state)] = step.action;
  r.log_likelihood = result.learned.log_likelihood;
  r.ile = result.learned.ile.value_or(-1.0);
  return r;
}

}  // namespace

std::optional<OptimiserResult> run_optimiser(Bus& bus, const OptimiserOptions& options, Counters& counters,
                                             const std::function<bool()>& stop,
                                             const std::function<void(const std::string&)>& log,
                                             const std::function<void()>& ready) {
  const std::unique_ptr<DatasetBuilder> builder = subscribed_builder(bus, options, counters);
  if (ready) ready();
  const auto say = [&log](const std::string& s) {
    if (log) log(s);
  };
  LiveEstimator estimator(bus, options, counters, log);
  std::function<void()> on_data;
  if (options.anytime) on_data = [&estimator, &builder] { estimator.update(*builder); };
  RunCollector collector(bus, *builder, options, counters, stop, log, std::move(on_data));
  if (!collector.collect()) return std::nullopt;
  OptimiserResult result;
  result.missing_frames = builder->missing_frames();
  result.incomplete = collector.incomplete();
  const std::int64_t frames_observed = builder->frames();
  result.data = builder->take();
  // From here the builder keeps nothing: it watches what still comes for a contradiction
  // (checked before the reward is published); frames are not read while learning.
  result.frame_requests = collector.frame_requests();
  result.recording = collector.recording();
  result.estimates = estimator.take();
  result.stop_sent_after = estimator.stop_sent_after();
  const std::shared_ptr<const Domain> domain = domain_of(result.data, options.domain);
  size_unobserved(result.data, *domain);
  const Mdp& mdp = domain->mdp();
  BusExecutorOptions executor_options = options.executor;
  if (!executor_options.stop) executor_options.stop = stop;
  if (!executor_options.idle && options.beat) executor_options.idle = [beat = options.beat] { beat("learning"); };
  // The workers are sent the demonstrations as the E-step holds them (with an unlisted
  // catch-all's share of eta, if any), each only its blocks'.
  auto executor = std::make_shared<BusBlockExecutor>(bus, mdp, domain->name(), counters, executor_options);
  if (!result.data.contexts_note.empty()) say(result.data.contexts_note);
  say("data: " + std::to_string(result.data.controlled_observed.size()) + " controlled episodes, " +
      std::to_string(result.data.observed.size()) + " demonstrations, " + std::to_string(frames_observed) + " frames");
  if (options.workers > 0) {
    result.workers = executor->wait_for_workers(options.workers, options.wait_workers_ms);
    say(std::to_string(result.workers) + " of " + std::to_string(options.workers) + " sampler workers ready");
  }
  const std::optional<Eigen::VectorXd> truth = true_weights_of(*domain, result.data);
  if (!truth) say("no true weights that fit the domain's features: no ILE");
  const auto start = Clock::now();
  const std::int64_t utime = result.data.last_utime;
  auto last_progress = start - kProgressEvery;
  try {
    result.learned = learn_from_dataset(
        *domain, result.data, final_settings(options.learning), executor,
        [&](int iteration, double ll, const Eigen::VectorXd& theta, const ObservationPrior& alpha,
            const EStepResult& estep, const LearnedEta* eta) {
          if (stop && stop()) throw Stopped();  // also when computing alone
          if (options.beat) options.beat("learning");
          publish_model(bus, counters, mdp, result.data, utime, iteration, alpha, estep, eta);
          publish_progress(bus, counters, mdp, utime, iteration, ll, theta, alpha, truth, *executor, start);
          if (Clock::now() - last_progress >= kProgressEvery) {
            last_progress = Clock::now();
            std::ostringstream line;
            line << kProgress << "learning: EM iteration " << iteration << ", log-likelihood " << ll;
            if (truth) line << ", ILE " << inverse_learning_error(mdp, *truth, theta).ile;
            say(line.str());
          }
        });
  } catch (const Stopped&) {
    say("stopped while learning");
    return std::nullopt;
  }
  result.estep = executor->stats();
  // What came while learning (and is waiting now) may contradict the run: then no reward.
  for (int k = 0; k < 1000000 && bus.handle(0) > 0; ++k) {
  }
  collector.check_contradiction();
  const hbirl::reward_t reward = reward_message(mdp, result, utime, truth);
  const auto publish_reward = [&] {
    publish(bus, channels::kReward, reward, counters);
    return wall_utime();
  };
  const std::int64_t sent = publish_reward();
  {
    std::ostringstream line;
    line << "learned (log-likelihood " << result.learned.log_likelihood << "): the REWARD is published";
    say(line.str());
  }
  collector.record_the_reward(utime, sent, publish_reward);
  result.recording = collector.recording();
  return result;
}

std::shared_ptr<const Domain> domain_of(const Dataset& data, std::shared_ptr<const Domain> given) {
  if (given) {
    if (!data.domain.empty() && data.domain != given->name()) {
      throw InputError("episode_marker.domain",
                       "'" + data.domain + "' is not the domain learned on ('" + given->name() + "')");
    }
    return given;
  }
  if (data.domain.empty()) throw InputError("episode_marker.domain", "no episode markers: the domain is unknown");
  std::shared_ptr<const Domain> builtin = builtin_domain(data.domain);
  if (!builtin) {
    throw InputError("episode_marker.domain",
                     "'" + data.domain + "' is not a built-in domain: give its domain file (--domain FILE)");
  }
  return builtin;
}

OptimiserResult collect_from_log(const RecordedRun& run, Counters& counters) {
  check_recording_key(run.path, run.key_file);
  auto log = std::make_unique<LogBus>(run.path);
  const LogBus& clock = *log;  // the recording's time
  std::unique_ptr<Bus> bus = with_key(std::move(log), run.key_file, counters, KeyUse::kReader);
  DatasetBuilder builder;
  builder.subscribe(*bus, counters);
  // As the live optimiser does: up to the moment the run is complete, and confirmed (in
  // the recording's time).
  bool ended = false;
  for (;;) {
    while (!builder.complete() && !(ended = bus->handle(0) < 0)) {
    }
    if (ended) break;
    const std::int64_t heard = builder.end_runs_heard(), since = clock.last_utime();
    const std::int64_t confirm_us = std::int64_t{OptimiserOptions{}.confirm_ms} * 1000;
    while (builder.complete() && builder.end_runs_heard() == heard && clock.last_utime() - since < confirm_us &&
           !(ended = bus->handle(0) < 0)) {
    }
    if (builder.complete() || ended) break;
  }
  OptimiserResult result;
  result.missing_frames = builder.missing_frames();
  if (!builder.complete()) {
    result.incomplete =
        std::string(builder.run_ended() ? "the run ended" : "the recording has no END_RUN (the run was cut short)") +
        ", " + std::to_string(builder.unfinished_episodes()) + " episode(s) without their end, " +
        std::to_string(builder.missing_frames()) + " frame(s) missing";
  }
  result.data = builder.take();
  // The rest of the recording (what the live optimiser heard while it learned) is read for
  // contradictions, and for messages of another run; what is wrong with the recording as a
  // whole is said before what its run lacks.
  while (bus->handle(0) >= 0) {
  }
  if (counters.signed_unread > 0) {  // (the first of hbirl's messages was not: check_recording_key let it be read)
    throw InputError("--key", "'" + run.path + "' holds " + std::to_string(counters.signed_unread) +
                                  " messages signed with a run key: give it (launch.sh wrote OUT/run.key)");
  }
  if (counters.other_run > 0 && !RunKey::read(run.key_file).run()) {
    throw InputError(
        "--log", "'" + run.path + "' holds messages of more than one run signed with this key (" +
                     std::to_string(counters.other_run) + " not of the first run " +
                     run_id_text(static_cast<const KeyedBus&>(*bus).run()) +
                     "; a replay recorded with it?): give the key file of the run to read (OUT/run.key names its run)");
  }
  if (!builder.contradiction().empty()) {
    throw InputError("--log", "'" + run.path + "': the run contradicts itself: " + builder.contradiction() +
                                  " (a forged or stray message? docs/RELIABILITY.md)");
  }
  if (!result.incomplete.empty() && !run.allow_incomplete) {
    throw InputError("--log", "'" + run.path + "' is not a complete run: " + result.incomplete +
                                  "; --allow-incomplete learns from the finished episodes");
  }
  return result;
}

OptimiserResult learn_from_log(const RecordedRun& run, const app::LearnSettings& settings, Counters& counters,
                               std::shared_ptr<const Domain> domain) {
  OptimiserResult result = collect_from_log(run, counters);
  const std::shared_ptr<const Domain> learned_on = domain_of(result.data, std::move(domain));
  size_unobserved(result.data, *learned_on);
  result.learned = learn_from_dataset(*learned_on, result.data, settings);
  return result;
}

}  // namespace hbirl::services
