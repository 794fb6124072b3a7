#pragma once
// The dashboard's web server (cpp-httplib): the page and its scripts from `web_dir`, and
//   GET /api/state      DashboardState::json(), the page polls it
//   GET /api/frame.png  the latest annotated camera frame (404 until there is one)
// (GET and HEAD only; one request per connection.) Listens on localhost only unless told
// otherwise.
#include <memory>
#include <string>

#include "dashboard/state.hpp"

namespace hbirl::dashboard {

// How the server treats its clients (hbirl-dashboard --help; docs/RELIABILITY.md).
// A connection first waits, holding no thread, until its whole request head (request line
// and headers) has arrived; then a thread answers its one request and closes it.
struct ServerLimits {
  // Requests answered at once, each on a thread; as many more complete ones wait in line
  // (beyond that they wait with the heads still arriving): a crowd of clients cannot make
  // it start a thread each.
  int max_connections = 16;
  // A client that sends (or takes) nothing for this long is dropped: slow and idle
  // connections free their place instead of holding it.
  double timeout_s = 2.0;
  // A connection whose whole head has not arrived this long after it was accepted is
  // closed unanswered, however steadily it trickles (the timeout above is per byte).
  // Once its head is in, it has as long again to take its answer.
  double header_timeout_s = 5.0;
  // Connections waiting for their heads, per client address (IPv6: per /64) and in all. A
  // new one beyond either closes the OLDEST waiting one (its client's, or anyone's), never
  // the new one: attackers may share the address of a real client (this machine, a NAT),
  // and the real client's request, sent whole, must still be served.
  int max_waiting_per_client = 64;
  int max_waiting = 512;  // well under the usual 1024 open files
  // A head that grows past this without ending is closed (431).
  int max_head_bytes = 16 * 1024;
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
