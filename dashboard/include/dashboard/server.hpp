#pragma once
// The dashboard's web server (cpp-httplib): the page and its scripts from `web_dir`, and
//   GET /api/state      DashboardState::json(), the page polls it
//   GET /api/frame.png  the latest annotated camera frame (404 until there is one)
// Listens on localhost only unless told otherwise.
#include <memory>
#include <string>

#include "dashboard/state.hpp"

namespace hbirl::dashboard {

// How the server treats its clients (hbirl-dashboard --help; docs/RELIABILITY.md).
struct ServerLimits {
  // Connections served at once; as many more wait in line, and beyond that the server stops
  // accepting until one ends (the kernel holds the rest): a crowd of clients cannot make
  // it start a thread each.
  int max_connections = 16;
  // A client that sends (or takes) nothing for this long is dropped: slow and idle
  // connections free their place instead of holding it.
  double timeout_s = 2.0;
};

class Server {
 public:
  // Throws InputError("--web", ...) when the page is not in web_dir.
  Server(const DashboardState& state, const std::string& web_dir, ServerLimits limits = {});
  ~Server();
  // Binds host:port (port 0: any free port); throws InputError("--port", ...) when it cannot.
  // Returns the port bound.
  int bind(const std::string& host, int port);
  // Serves until stop() (from another thread; it waits for run() to have started).
  void run();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hbirl::dashboard
