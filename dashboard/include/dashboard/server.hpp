#pragma once
// The dashboard's web server (cpp-httplib): the page and its scripts from `web_dir`, and
//   GET /api/state      DashboardState::json(), the page polls it
//   GET /api/frame.png  the latest annotated camera frame (404 until there is one)
// Listens on localhost only unless told otherwise.
#include <memory>
#include <string>

#include "dashboard/state.hpp"

namespace hbirl::dashboard {

class Server {
 public:
  // Throws InputError("--web", ...) when the page is not in web_dir.
  Server(const DashboardState& state, const std::string& web_dir);
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
