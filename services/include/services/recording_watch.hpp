#pragma once
// The run's lcm-logger recording as its readers will find it (hbirl learn --log,
// collect_from_log): followed by the optimiser once it has the whole run, so that what
// lcm-logger lost -- a UDP receiver that cannot ask for a message again -- is asked for
// again as the optimiser's own losses are, and the recording is complete whenever the run
// is (docs/RELIABILITY.md "A recording holds the whole run").
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "services/bus.hpp"
#include "services/dataset.hpp"

namespace hbirl::services {

class RecordingWatch {
 public:
  // `key_file`: the run's key when its messages are signed ("" when not), so that the
  // recording is read as its readers read it. Nothing is opened until read().
  RecordingWatch(std::string path, std::string key_file, std::int64_t max_dataset_bytes);
  // Reads what lcm-logger has written since the last call (nothing while the file does
  // not exist yet). Throws InputError when the file is not a recording.
  void read();
  // Whether the recording holds the whole run, as collect_from_log asks it.
  bool complete() const { return builder_.complete(); }
  std::int64_t frames() const { return builder_.frames(); }
  // The frames (and ground-truth steps) of ended episodes it lacks, at most `limit`.
  std::vector<std::tuple<int, int, int>> missing_frame_keys(size_t limit) const {
    return builder_.missing_frame_keys(limit);
  }
  // What it lacks, in words.
  std::string lacks() const;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string key_file_;
  Counters counters_;  // its own: a recording's bad messages are not the bus's
  std::unique_ptr<Bus> log_;
  DatasetBuilder builder_;  // (after log_: its subscriptions end before the log)
};

}  // namespace hbirl::services
