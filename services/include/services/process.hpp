#pragma once
// What every service process shares: stopping cleanly on SIGINT/SIGTERM, its id, and the
// heartbeat on STATUS.
#include <chrono>
#include <string>

#include "hbirl/service_status_t.hpp"
#include "services/bus.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

// Installs handlers for SIGINT and SIGTERM that ask the process to stop.
void install_stop_handlers();
bool stop_requested();

// "<service>-<host>-<pid>": unique on a network of machines.
std::string default_id(const std::string& service);

// Liveness for a supervisor (services/launch.sh): `path` is touched once a second while
// the process beats its heartbeat (touch_alive_file(), called with every heartbeat) or
// computes (uses CPU), so a service alive but silent -- stopped, or blocked for good -- is
// seen as such by the file's age, and one busy computing is not. Errors are ignored: the
// supervisor then sees silence.
void set_alive_file(const std::string& path);
void touch_alive_file();

class Heartbeat {
 public:
  Heartbeat(Bus& bus, Counters& counters, std::string service, std::string id);
  // Publishes the status when a second has passed since the last one (or at once with
  // `now`): the state ("starting", "running", "done", "failed") and the counters.
  void tick(const std::string& state, bool now = false, int trajectories = 0, std::uint64_t digest = 0);
  const std::string& id() const { return id_; }

 private:
  Bus& bus_;
  Counters& counters_;
  std::string service_, id_;
  std::int64_t seq_ = 0;
  std::chrono::steady_clock::time_point next_{};
};

}  // namespace hbirl::services
