#pragma once
// The run's lcm-logger recording as its readers will find it (hbirl learn --log,
// collect_from_log): followed by the optimiser once it has the whole run, so that what
// lcm-logger lost -- a UDP receiver that cannot ask for a message again -- is asked for
// again as the optimiser's own losses are, and the recording is complete whenever the run
// is (docs/RELIABILITY.md "A recording holds the whole run").
#include <chrono>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "services/bus.hpp"
#include "services/dataset.hpp"

namespace hbirl::services {

class LogBus;

class RecordingWatch {
 public:
  // `key_file`: the run's key when its messages are signed ("" when not), so that the
  // recording is read as its readers read it. Nothing is opened until read().
  RecordingWatch(std::string path, std::string key_file, std::int64_t max_dataset_bytes);
  // Reads what lcm-logger has written since the last call, for at most `budget` (a long
  // recording is read over several calls, the caller beating its heartbeat between them);
  // nothing while the file does not exist yet. A file rewritten from its start is read
  // again from scratch. Throws InputError when the file is not a recording.
  void read(std::chrono::milliseconds budget);
  // Whether its readers will take the recording as the whole run: everything read so far,
  // complete as collect_from_log asks it, no damaged event skipped, no contradiction.
  bool complete() const;
  // What it holds, a number that changes with every frame, ground-truth step and episode
  // end it gains, not with repeats (the optimiser gives up on a recording that stops gaining).
  std::int64_t progress() const;
  // The last read() reached the end of what is written.
  bool caught_up() const { return caught_up_; }
  // The frames (and ground-truth steps) of ended episodes it lacks, at most `limit`.
  std::vector<std::tuple<int, int, int>> missing_frame_keys(size_t limit) const;
  // What it lacks, in words.
  std::string lacks() const;
  // From now on only the REWARDs are followed: the tally of the run (a map entry per frame)
  // is dropped, and complete(), progress() and what it lacks are no longer known. Called
  // before the first read(), nothing but the REWARDs is ever read.
  void follow_rewards_only();
  // It holds the run's final REWARD (the one whose utime is `utime`, as the optimiser
  // published it): the run's readers see it learned (hbirl report). Known once only the
  // REWARDs are followed (of what is read from then on), as last_arrival_utime().
  bool holds_reward(std::int64_t utime) const { return final_rewards_.count(utime) > 0; }
  // When the latest message it holds arrived at lcm-logger (its receive time, as recorded;
  // 0 before any). lcm-logger reads one socket in arrival order: a message it holds that
  // arrived after another was sent means that other was received before it, or lost.
  std::int64_t last_arrival_utime() const { return last_arrival_utime_; }
  const std::string& path() const { return path_; }

 private:
  void open();
  void follow_rewards();
  std::string path_;
  std::string key_file_;
  std::int64_t max_dataset_bytes_;
  std::int64_t size_ = 0;               // the file's size when last read
  bool caught_up_ = false;              // the last read() reached the end of what was written
  std::unique_ptr<Counters> counters_;  // its own: a recording's bad messages are not the bus's
  std::unique_ptr<Bus> log_;
  std::unique_ptr<DatasetBuilder> builder_;  // (after log_: its subscriptions end before the log)
  std::set<std::int64_t> final_rewards_;     // the utime of every final REWARD read
  std::int64_t last_arrival_utime_ = 0;
  bool rewards_only_ = false;
  const LogBus* file_ = nullptr;  // log_'s file, for its damage count
};

}  // namespace hbirl::services
