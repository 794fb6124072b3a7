// The run's recording, followed (recording_watch.hpp).
#include "services/recording_watch.hpp"

#include <algorithm>
#include <filesystem>

#include "services/channels.hpp"
#include "services/keyed_bus.hpp"
#include "services/log_bus.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

RecordingWatch::RecordingWatch(std::string path, std::string key_file, std::int64_t max_dataset_bytes)
    : path_(std::move(path)), key_file_(std::move(key_file)), max_dataset_bytes_(max_dataset_bytes) {}

void RecordingWatch::open() {
  builder_.reset();  // (its subscriptions, on the old log, first)
  log_.reset();
  counters_ = std::make_unique<Counters>();
  counters_->service = "recording";
  counters_->quiet = true;
  auto log = std::make_unique<LogBus>(path_);
  log->follow(true);  // lcm-logger is still writing it
  file_ = log.get();
  log_ = with_key(std::move(log), key_file_, *counters_, KeyUse::kReader);
  if (!rewards_only_) {
    builder_ = std::make_unique<DatasetBuilder>();
    // Whether the recording holds the run, not the run again: the optimiser has its data
    // already (a second copy made it 2.4x the data's size on a run of 10^6 observations).
    builder_->tally_only();
    builder_->limit(max_dataset_bytes_);
    builder_->subscribe(*log_, *counters_);
  }
  final_rewards_.clear();
  last_arrival_utime_ = 0;
  if (rewards_only_) follow_rewards();
  size_ = 0;
}

void RecordingWatch::read(std::chrono::milliseconds budget) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path_, error);
  if (error) {  // lcm-logger has not begun it yet (or never will): nothing more to read now
    caught_up_ = true;
    return;
  }
  if (!log_ || static_cast<std::int64_t>(size) < size_) open();  // rewritten from its start: read anew
  size_ = static_cast<std::int64_t>(size);
  const auto until = std::chrono::steady_clock::now() + budget;
  caught_up_ = false;
  while (std::chrono::steady_clock::now() < until) {
    if (log_->handle(0) <= 0) {
      caught_up_ = true;
      break;
    }
  }
}

// The final REWARDs and every message's arrival time, once only the REWARDs are followed:
// before, a message of a channel the run's readers do not read, signed for another run (a
// worker's heartbeat from its last run, another run's REWARD on a shared bus), would count
// against the recording here and not there.
void RecordingWatch::follow_rewards() {
  subscribe(*log_, channels::kReward, *counters_, [this](const hbirl::reward_t& m, const Message&) {
    if (m.final) final_rewards_.insert(m.utime);
  });
  log_->subscribe(".*",
                  [this](const Message& m) { last_arrival_utime_ = std::max(last_arrival_utime_, m.recv_utime); });
}

void RecordingWatch::follow_rewards_only() {
  if (rewards_only_) return;
  rewards_only_ = true;
  builder_.reset();  // (its subscriptions end; the log and the REWARD's stay)
  if (log_) follow_rewards();
}

bool RecordingWatch::complete() const {
  return builder_ && caught_up_ && builder_->complete() && file_->damaged() == 0 && builder_->contradiction().empty() &&
         counters_->other_run == 0 && counters_->signed_unread == 0;
}

std::int64_t RecordingWatch::progress() const {
  if (!builder_) return -1;
  return builder_->frames() - builder_->missing_truth() - builder_->unfinished_episodes() +
         (builder_->run_ended() ? 1 : 0);
}

std::vector<std::tuple<int, int, int>> RecordingWatch::missing_frame_keys(size_t limit) const {
  if (!builder_) return {};
  return builder_->missing_frame_keys(limit);
}

std::string RecordingWatch::lacks() const {
  if (!builder_) return "everything: the file is not there";
  if (file_->damaged() > 0) return std::to_string(file_->damaged()) + " damaged event(s), which its readers refuse";
  if (!builder_->contradiction().empty()) return "consistency: " + builder_->contradiction();
  if (counters_->other_run > 0 || counters_->signed_unread > 0)
    return "a single run: it holds messages of another run or signed with another key";
  if (!builder_->run_ended()) return "the run's end (END_RUN)";
  return std::to_string(builder_->unfinished_episodes()) + " episode end(s), " +
         std::to_string(builder_->missing_frames()) + " frame(s) and " + std::to_string(builder_->missing_truth()) +
         " ground-truth step(s)";
}

}  // namespace hbirl::services
