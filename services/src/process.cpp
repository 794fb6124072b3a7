#include "services/process.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <ctime>
#include <thread>

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
std::atomic<int> g_alive_fd{-1};
std::atomic<std::int64_t> g_beats{0};

double cpu_seconds() {
  timespec t{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Once a second: the alive file is touched when the process beat its heartbeat or used
// CPU (at least 5 % of the second) since the last look. A long computation -- an M-step on a
// big task, a worker's large block -- sends no heartbeat but uses CPU; a stopped process
// does neither, nor does one blocked for good (a deadlock, a read that never returns). One
// spinning in a loop is not told from one computing.
void watch_alive() {
  std::int64_t beats = g_beats.load();
  double cpu = cpu_seconds();
  for (;;) {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    const std::int64_t now_beats = g_beats.load();
    const double now_cpu = cpu_seconds();
    if (now_beats != beats || now_cpu - cpu >= 0.05) ::futimens(g_alive_fd.load(), nullptr);
    beats = now_beats;
    cpu = now_cpu;
  }
}
}  // namespace

void set_alive_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0600);
  if (fd < 0) return;  // the supervisor then sees silence, and says so
  ::futimens(fd, nullptr);
  const int before = g_alive_fd.exchange(fd);
  if (before < 0) {
    std::thread(watch_alive).detach();  // ends with the process
  } else {
    ::close(before);
  }
}

void touch_alive_file() { ++g_beats; }

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
