#pragma once
// The learner's data, assembled from the stream (docs/services.md "Services and channels"): episodes and their steps
// (EPISODE), the observations of every frame (OBSERVATIONS) and, for controlled-run
// episodes, the expert's true (s, a) at every step (GROUND_TRUTH). Channels arrive out
// of step with each other (observations come two services later than the markers), so
// everything is placed by its (episode, step, frame) fields, never by arrival order, and
// a replayed log gives the same data as the live run.
#include <array>
#include <map>
#include <optional>
#include <tuple>
#include <vector>

#include "hbirl/episode_marker_t.hpp"
#include "hbirl/ground_truth_t.hpp"
#include "hbirl/observations_t.hpp"
#include "learner/observations.hpp"
#include "learner/trajectory.hpp"
#include "services/bus.hpp"
#include "services/channels.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

struct Dataset {
  std::string domain;
  int num_symbols = 0;
  int num_sources = 0;                                  // 1 + confounding elements
  std::vector<int> episodes;                            // the demonstrations' episode numbers
  std::vector<ObservedTrajectory> observed;             // the demonstrations
  std::vector<Trajectory> truth;                        // their true steps, when ground truth came
  std::vector<ObservedTrajectory> controlled_observed;  // the controlled run
  std::vector<Trajectory> controlled_truth;
  std::optional<Eigen::VectorXd> true_weights;  // the expert's, when the ground truth gave them
  std::int64_t last_utime = 0;                  // sim time of the newest message used
  int skipped_controlled = 0;                   // controlled episodes left out: ground truth incomplete
  std::string contexts_note;  // non-empty: contexts were given for some observations only, and ignored
};

// The data set with its first `n` demonstrations only (the controlled run kept).
Dataset first_demonstrations(Dataset data, size_t n);

class DatasetBuilder {
 public:
  DatasetBuilder();
  // Subscribes to the three channels; bad messages are counted in `counters`.
  void subscribe(Bus& bus, Counters& counters);
  // The domain learned on, when known before the run: its name in the markers, its
  // symbols and (if it states them) its sources, its states and actions in the ground
  // truth are checked on every message (0: any), so a sensor that does not fit is refused
  // message by message, not after the run.
  void expect(const std::string& domain, int num_symbols, int num_sources, int num_states, int num_actions);
  // What may be said of how an episode ended: a terminal state of `terminal` (one flag per
  // state) and reports of an end sensor of `end_symbols` symbols (0: none may come). Until
  // called, anything the markers' own validation allows.
  void expect_ends(std::vector<char> terminal, int end_symbols);
  // At most this many bytes of observations are kept: a frame that would take the data
  // set past it is refused (InputError naming --max-dataset-mb) and not kept, whoever
  // floods the bus with made-up frames.
  void limit(std::int64_t max_bytes) { max_bytes_ = max_bytes; }
  // Keeps of each frame only that it came and its digest, not its observations: a builder
  // that counts what a run holds (RecordingWatch: is the recording the whole run?) and
  // still finds a later copy that differs, without a second copy of the data. Its
  // counts and refusals are a full builder's; build() and take() throw std::logic_error.
  // Called before any frame (else std::logic_error).
  void tally_only();
  // The observations its frames hold now (0 for a tally).
  std::int64_t held_observations() const;
  // Each throws InputError naming the field of a message that does not fit. Messages come
  // as typed subscribe() hands them over: having passed their type's validate() (messages.hpp).
  void on_marker(const hbirl::episode_marker_t& m);
  void on_observations(const hbirl::observations_t& m);
  void on_truth(const hbirl::ground_truth_t& m);

  bool run_ended() const { return run_ended_; }
  // An END_RUN stating a number of episodes was heard, believed or not (one before any
  // episode ended is not, docs/RELIABILITY.md): their end markers may be asked for, so that
  // an optimiser that missed them all -- restarted, or every one lost -- still gets the run.
  bool end_run_heard() const { return run_ended_ || end_run_stated_ > 0; }
  // Non-empty when the run's own messages contradict each other: two END_RUNs stating
  // different numbers of episodes, or an episode at or past the number END_RUN states
  // (begun before it, or after). Nothing says which message was forged: a run that says
  // this cannot be learned from (docs/RELIABILITY.md), it fails, loudly.
  const std::string& contradiction() const { return contradiction_; }
  // How many END_RUN markers were heard (the simulator repeats its own each second).
  std::int64_t end_runs_heard() const { return end_runs_heard_; }
  // The run has ended and every episode has every frame's observations.
  // ... and every controlled episode has every step's ground truth (its prior needs them).
  bool complete() const;
  std::int64_t missing_frames() const;  // of episodes that ended
  int unfinished_episodes() const;      // begun, never ended
  std::int64_t missing_truth() const;   // steps of controlled episodes that ended
  // Up to `limit` missing (episode, step, frame), in order: once the run has ended, first
  // (episode, -1, -1) for each of its episodes whose end marker has not come (FRAME_REQUEST
  // asks for the marker so), then the frames of episodes that ended; a controlled step
  // without its ground truth is asked for as its frame 0 (the simulator sends the truth of
  // every step it sends frames of).
  std::vector<std::tuple<int, int, int>> missing_frame_keys(size_t limit) const;
  std::int64_t build_utime() const { return last_utime_; }
  std::int64_t frames() const { return frames_; }
  int episodes() const { return static_cast<int>(episodes_.size()); }
  // Episodes of the run that have ended (an end marker asked for again that came is progress).
  int ended_episodes() const { return ended_in_run_; }
  // Of them, those a marker said are controlled (the controlled run's, paper §III-B).
  int controlled_episodes() const;
  // Demonstrations of the run that ended with every frame's observations.
  int complete_demonstrations() const { return complete_demonstrations_; }
  // How many of the run's first demonstrations, in episode order, ended with every frame's
  // observations (the optimiser's estimate after each one, optimiser.hpp): the same
  // whatever order the messages came in.
  int complete_demonstration_prefix() const;
  // The data of the episodes that ended, in episode order (controlled episodes whose
  // ground truth is incomplete are left out and counted).
  Dataset build() const;
  // The same data set, taken out: each episode's frames are let go as soon as they are
  // assembled, so that the observations are never held twice. The builder's frames are
  // gone afterwards (what it knows of the run as a whole stays): read missing_frames(),
  // complete() and the like first; it is not meant to collect again. From then on it
  // watches the run for a contradiction: it keeps the episodes' markers and a digest of
  // each frame and ground-truth step taken, so that a copy arriving later which differs
  // (the sensor's, when a forger's came first) still contradicts the run; nothing new is kept.
  Dataset take();

 private:
  struct Frame {
    std::vector<int> symbols;
    std::vector<double> eta;    // rows of num_sources
    std::vector<int> contexts;  // one per symbol, or none
    std::uint64_t digest = 0;   // tally_only(): frame_digest of what the three held
  };
  std::uint64_t frame_digest(const Frame& f) const;
  void watch_frame(const hbirl::observations_t& m, const Frame& f);
  struct Episode {
    bool controlled = false;
    bool marked = false;  // a marker has said whether it is controlled (then later ones must agree)
    bool ended = false;
    bool ends_in_terminal = false;
    int end_state = -1;            // the terminal state entered, when known for certain
    std::vector<int> end_reports;  // the end sensor's
    int num_steps = 0;
    int frames_per_step = 0;
    std::map<std::pair<int, int>, Frame> frames;  // (step, frame)
    std::map<int, StateAction> truth;             // step -> (s, a)
    std::int64_t have_frames = 0;                 // once ended: frames within num_steps x frames_per_step
    std::int64_t have_truth = 0;                  // once ended: truth steps within num_steps
  };
  Episode& episode(int id);
  void count(const Episode& e, int id, int sign);
  static void recount(Episode& e);
  Dataset empty_dataset() const;                                 // the run's facts, no episodes yet
  void add_episode(Dataset& d, int id, const Episode& e) const;  // if it ended and belongs to the run
  static void finish_dataset(Dataset& d);
  void mark_controlled(Episode& e, const hbirl::episode_marker_t& m);
  // on_marker by kind: BEGIN_EPISODE or BEGIN_STEP, END_EPISODE, END_RUN.
  void on_begin_marker(const hbirl::episode_marker_t& m);
  void on_end_episode(const hbirl::episode_marker_t& m);
  void on_end_run(const hbirl::episode_marker_t& m);
  // Episode `id` belongs to the run: any, until END_RUN states how many it had.
  bool in_run(int id) const { return run_episodes_ == 0 || id < run_episodes_; }

  void contradicted(const std::string& why);
  void saw_episode(int id);  // a message about episode `id` came
  // Taken (watching_): the checks of a message against what was taken.
  void watch_marker(const hbirl::episode_marker_t& m);
  void watch_truth(const hbirl::ground_truth_t& m);

  std::string domain_;
  std::string expected_domain_;
  std::string contradiction_;
  int last_episode_ = -1;  // the highest episode any message was about
  std::int64_t end_runs_heard_ = 0;
  bool watching_ = false;  // taken: only watching for a contradiction
  bool tally_only_ = false;
  // What was taken, to check later copies against: (episode, step, frame) -> the frame's
  // digest, and (episode, step) -> its truth; sorted (24 and 16 bytes a frame and a step).
  std::vector<std::pair<std::tuple<int, int, int>, std::uint64_t>> taken_frames_;
  std::vector<std::pair<std::pair<int, int>, StateAction>> taken_truth_;
  std::map<int, Episode> taken_episodes_;      // without their frames and truth
  bool taken_complete_ = false;                // the run was complete when taken
  std::array<std::uint8_t, 16> digest_key_{};  // frame_digest's, random
  int expected_symbols_ = 0, expected_sources_ = 0, expected_states_ = 0, expected_actions_ = 0;  // 0: any
  std::optional<std::pair<std::vector<char>, int>> expected_ends_;  // terminal states, end alphabet
  std::map<int, Episode> episodes_;
  int num_symbols_ = 0, num_sources_ = 0;
  bool run_ended_ = false;
  int run_episodes_ = 0;    // as END_RUN states it (0: not stated)
  int end_run_stated_ = 0;  // the most episodes any END_RUN stated, believed or not
  std::int64_t bytes_ = 0, max_bytes_ = std::int64_t{2048} << 20;  // of the frames kept
  std::int64_t frames_ = 0;
  // Kept as messages come (count): of the ended episodes of the run, the frames and the
  // controlled episodes' truth steps they lack, and how many they are; episodes begun
  // outside the run (ids past END_RUN's count).
  std::int64_t missing_frames_ = 0, missing_truth_ = 0, outside_run_ = 0;
  int ended_in_run_ = 0;
  int complete_demonstrations_ = 0;  // of them
  std::int64_t last_utime_ = 0;
  std::optional<Eigen::VectorXd> true_weights_;
  bool weights_conflict_ = false;
  SequenceTracker marker_seq_, observation_seq_, truth_seq_;
  Counters* counters_ = nullptr;
  Subscriptions subs_;  // last: ends first
};

}  // namespace hbirl::services
