#include "services/process.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <csignal>

#include "services/channels.hpp"

namespace hbirl::services {

namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop = true; }
}  // namespace

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() { return g_stop.load(); }

namespace {
int g_alive_fd = -1;
}  // namespace

void set_alive_file(const std::string& path) {
  if (g_alive_fd >= 0) ::close(g_alive_fd);
  g_alive_fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0600);
  touch_alive_file();
}

void touch_alive_file() {
  if (g_alive_fd >= 0) ::futimens(g_alive_fd, nullptr);  // now
}

std::string default_id(const std::string& service) {
  char host[256] = {0};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  return service + "-" + (host[0] ? host : "host") + "-" + std::to_string(getpid());
}

Heartbeat::Heartbeat(Bus& bus, Counters& counters, std::string service, std::string id)
    : bus_(bus), counters_(counters), service_(std::move(service)), id_(std::move(id)) {}

void Heartbeat::tick(const std::string& state, bool now, int trajectories, std::uint64_t digest) {
  const auto t = std::chrono::steady_clock::now();
  if (!now && t < next_) return;
  next_ = t + std::chrono::seconds(1);
  hbirl::service_status_t s{};
  s.utime = wall_utime();
  s.service = service_;
  s.id = id_;
  s.seq = ++seq_;
  s.state = state;
  s.messages_in = counters_.messages_in;
  s.messages_out = counters_.messages_out;
  s.bad_messages = counters_.bad_messages;
  s.gaps = counters_.gaps;
  s.trajectories = trajectories;
  s.dataset_digest = static_cast<std::int64_t>(digest);
  s.detail = counters_.last_problem;
  s.authenticated = counters_.authenticated;
  s.restarts = counters_.restarts;
  publish(bus_, channels::kStatus, s, counters_);
  touch_alive_file();
}

}  // namespace hbirl::services
