// The run's recording, followed (recording_watch.hpp).
#include "services/recording_watch.hpp"

#include <filesystem>

#include "services/keyed_bus.hpp"
#include "services/log_bus.hpp"

namespace hbirl::services {

RecordingWatch::RecordingWatch(std::string path, std::string key_file, std::int64_t max_dataset_bytes)
    : path_(std::move(path)), key_file_(std::move(key_file)) {
  counters_.service = "recording";
  builder_.limit(max_dataset_bytes);
}

void RecordingWatch::read() {
  if (!log_) {
    std::error_code error;
    if (!std::filesystem::exists(path_, error)) return;  // lcm-logger has not begun it yet
    auto log = std::make_unique<LogBus>(path_);
    log->follow(true);  // lcm-logger is still writing it
    log_ = with_key(std::move(log), key_file_, counters_, KeyUse::kReader);
    builder_.subscribe(*log_, counters_);
  }
  while (log_->handle(0) > 0) {
  }
}

std::string RecordingWatch::lacks() const {
  if (!builder_.run_ended()) return "the run's end (END_RUN)";
  return std::to_string(builder_.unfinished_episodes()) + " episode end(s), " +
         std::to_string(builder_.missing_frames()) + " frame(s) and " + std::to_string(builder_.missing_truth()) +
         " ground-truth step(s)";
}

}  // namespace hbirl::services
