#pragma once
// Test scaffolding: services as threads, each on its own in-memory bus endpoint, the way
// the processes run them (one thread handles each bus).
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "services/estep_service.hpp"
#include "services/memory_bus.hpp"
#include "services/sampler_worker.hpp"

namespace hbirl::services::testing {

inline Counters quiet(const std::string& name) {
  Counters c;
  c.service = name;
  c.quiet = true;
  return c;
}

// A service built on the endpoint as Service(bus, counters); the thread handles the bus.
template <class Service>
class ServiceThread {
 public:
  template <class... Args>
  ServiceThread(std::shared_ptr<MemoryHub> hub, const std::string& name, const Args&... args)
      : bus_(std::move(hub)), counters_(quiet(name)), service_(bus_, counters_, args...), thread_([this] {
          while (!stop_) bus_.handle(20);
        }) {}
  ~ServiceThread() { stop(); }
  // Ends the thread (then counters() may be read).
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  const Counters& counters() const { return counters_; }

 private:
  MemoryBus bus_;
  Counters counters_;
  Service service_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A sampler worker. After `die_after` blocks it stops answering: its endpoint disconnects,
// like a process killed with SIGKILL.
class WorkerThread {
 public:
  WorkerThread(std::shared_ptr<MemoryHub> hub, const std::string& id, std::int64_t die_after = -1, bool lying = false,
               std::int64_t max_dataset_bytes = SamplerWorker::kDefaultMaxDatasetBytes)
      : bus_(std::move(hub)), counters_(quiet(id)), worker_(bus_, id, counters_, max_dataset_bytes) {
    if (lying) worker_.lie_for_testing();
    thread_ = std::thread([this, die_after] {
      while (!stop_) {
        if (die_after >= 0 && worker_.blocks_computed() >= die_after) {
          bus_.disconnect();
          return;
        }
        if (worker_.handle(20) < 0) return;
      }
    });
  }
  ~WorkerThread() { stop(); }
  // Ends the thread (then counters() may be read).
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  const SamplerWorker& worker() const { return worker_; }
  const Counters& counters() const { return counters_; }

 private:
  MemoryBus bus_;
  Counters counters_;
  SamplerWorker worker_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace hbirl::services::testing
