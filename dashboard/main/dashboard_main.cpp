// hbirl-dashboard: watch a run in the browser. Listens on the bus, or follows a log that
// lcm-logger is writing (so it works from outside the private network namespace that
// services/launch.sh runs the set in), and serves the page on localhost.
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <thread>

#include "app/domain_args.hpp"
#include "dashboard/server.hpp"
#include "dashboard/state.hpp"
#include "learner/input_error.hpp"
#include "services/lcm_bus.hpp"
#include "services/keyed_bus.hpp"
#include "services/log_bus.hpp"
#include "services/process.hpp"

namespace {

// The command line: where the messages come from, the server, the key and the domain.
struct DashboardArgs {
  std::string url, log, host = "127.0.0.1", web = HBIRL_DASHBOARD_WEB_DIR;
  int port = 8765;
  double wait_log = 60.0;
  hbirl::dashboard::ServerLimits limits;
  std::string key_file;
  hbirl::app::DomainArgs domain_args;
};

// Where the messages come from: the bus (--url) or a log (--log).
void add_source_options(CLI::App& app, DashboardArgs& a) {
  hbirl::app::add_url_option(&app, a.url, "to listen on (not with --log)");
  app.add_option("--log", a.log, "Follow this LCM log (services/launch.sh --record writes OUT/run.lcmlog)");
  app.add_option("--wait-log", a.wait_log, "Wait this many seconds for the log to appear")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
}

// The web server: where it serves, the page, and the limits that keep slow clients from stalling it.
void add_server_options(CLI::App& app, DashboardArgs& a) {
  hbirl::dashboard::ServerLimits& limits = a.limits;
  app.add_option("--host", a.host, "Address to serve on (127.0.0.1: this machine only)")->capture_default_str();
  app.add_option("--port", a.port, "Port to serve on (0: any free one)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  app.add_option("--web", a.web, "Folder with the page (index.html, dashboard.js, ...)")->capture_default_str();
  app.add_option("--max-connections", limits.max_connections,
                 "HTTP requests answered at once, each on a thread of its own, once its whole head has arrived\n"
                 "(as many more complete ones wait in line); one request per connection")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--http-timeout", limits.timeout_s,
                 "Seconds a client may send or take nothing before it is dropped (slow and idle connections)")
      ->check(CLI::Range(0.05, 600.0))
      ->capture_default_str();
  app.add_option("--header-timeout", limits.header_timeout_s,
                 "Seconds a connection has to send its whole request head (request line and headers): one\n"
                 "that has not by then is closed unanswered, however steadily it trickles. Until then it\n"
                 "holds no thread; once its head is in, it has as long again to take the answer")
      ->check(CLI::Range(0.05, 600.0))
      ->capture_default_str();
  app.add_option("--max-waiting-per-client", limits.max_waiting_per_client,
                 "Connections one client address (IPv6: one /64) may have waiting for their heads; a new one\n"
                 "beyond this closes that client's OLDEST waiting connection, so a request sent whole is\n"
                 "still served (at most " +
                     std::to_string(limits.max_waiting) + " wait in all, the oldest closed first)")
      ->check(CLI::Range(1, limits.max_waiting))
      ->capture_default_str();
}

// The bus (--url), or the log (--log) once it appears within --wait-log seconds; null when
// a stop was asked for while waiting.
std::unique_ptr<hbirl::services::Bus> open_bus(const DashboardArgs& a, hbirl::services::Counters& counters) {
  using namespace hbirl;
  if (!a.log.empty()) {
    const auto until =
        std::chrono::steady_clock::now() +
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(a.wait_log));
    while (!std::filesystem::exists(a.log) && std::chrono::steady_clock::now() < until && !services::stop_requested()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (services::stop_requested()) return nullptr;
    auto follow = std::make_unique<services::LogBus>(a.log);  // throws InputError("--log", ...) if it cannot
    follow->follow(true);
    return services::with_key(std::move(follow), a.key_file, counters, services::KeyUse::kReader);
  }
  return services::with_key(std::make_unique<services::LcmBus>(a.url), a.key_file, counters, services::KeyUse::kReader);
}

// One line on stderr: what was shown, and the CPU time it took.
void report_stopped(const hbirl::services::Counters& counters) {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const double cpu = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                     1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  std::fprintf(stderr, "hbirl-dashboard: stopped; %lld messages shown, %lld bad, %.2f s CPU\n",
               static_cast<long long>(counters.messages_in), static_cast<long long>(counters.bad_messages), cpu);
}

int run(int argc, char** argv) {
  using namespace hbirl;
  CLI::App app(
      "hbirl-dashboard: a live view of a learning run in the browser -- the camera with the\n"
      "detections coloured by their most likely source, the expert's (s, a) posterior against\n"
      "ground truth, log-likelihood and ILE per EM iteration, learned against true weights, the\n"
      "learned observation model, and every service's health.\n"
      "Reads the bus (--url) or follows a log as lcm-logger writes it (--log, also a finished one).");
  DashboardArgs a;
  add_source_options(app, a);
  add_server_options(app, a);
  app::add_key_option(&app, a.key_file,
                      "show only messages signed with it, count the rest as bad; without it the dashboard believes\n"
                      "anything on the bus");
  app::add_domain_options(
      &app, a.domain_args,
      "The run's domain when it is a domain file (built-in domains, onion and gridworld, are named by the run)");
  CLI11_PARSE(app, argc, argv);
  const std::shared_ptr<const Domain> domain = app::open_domain_args(a.domain_args, "hbirl-dashboard");
  if (!a.url.empty() && !a.log.empty()) throw InputError("--log", "give --url or --log, not both");

  services::install_stop_handlers();
  // Listen first (a port in use fails at once), then wait for the log to appear. The bus
  // outlives the state that subscribes to it; the server thread ends first of all.
  std::unique_ptr<services::Bus> bus;
  services::Counters counters;
  counters.service = "hbirl-dashboard";
  dashboard::DashboardState state(domain);
  dashboard::Server server(state, a.web, a.limits);
  const int bound = server.bind(a.host, a.port);
  std::thread serving([&server] { server.run(); });
  struct StopServer {  // whatever happens below, the server thread ends before `server` does
    dashboard::Server& server;
    std::thread& thread;
    ~StopServer() {
      server.stop();
      if (thread.joinable()) thread.join();
    }
  } stop_server{server, serving};
  std::fprintf(stderr, "hbirl-dashboard: http://%s:%d/  (%s %s; Ctrl-C to stop)\n",
               a.host == "0.0.0.0" ? "localhost" : a.host.c_str(), bound, a.log.empty() ? "listening on" : "following",
               a.log.empty() ? (a.url.empty() ? "LCM's default URL" : a.url.c_str()) : a.log.c_str());
  bus = open_bus(a, counters);
  if (!bus) return 0;
  state.subscribe(*bus, counters);
  std::unique_ptr<services::Heartbeat> heartbeat;
  if (a.log.empty())
    heartbeat = std::make_unique<services::Heartbeat>(*bus, counters, "dashboard", services::default_id("dashboard"));
  while (!services::stop_requested()) {
    if (bus->handle(100) < 0) break;
    if (heartbeat) heartbeat->tick("running");
  }
  report_stopped(counters);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const hbirl::InputError& e) {
    std::fprintf(stderr, "hbirl-dashboard: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hbirl-dashboard: internal error: %s\n", e.what());
    return 1;
  }
}
