#include "dashboard/server.hpp"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <thread>
#include <vector>

#include "learner/input_error.hpp"
// Last: it brings glibc's <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace hbirl::dashboard {
namespace {

// The server on a free port of this machine's loopback: the page, its data as JSON, and
// the frame (404 until there is one).
TEST(DashboardServer, ServesThePageTheStateAndTheFrame) {
  DashboardState state;
  hbirl::em_progress_t e{};
  e.iteration = 1;
  e.log_likelihood = -3.5;
  e.num_features = 1;
  e.theta = {0.25};
  state.on_progress(e);
  Server server(state, HBIRL_DASHBOARD_WEB_DIR);
  const int port = server.bind("127.0.0.1", 0);
  ASSERT_GT(port, 0);
  std::thread serving([&server] { server.run(); });
  httplib::Client client("127.0.0.1", port);
  client.set_connection_timeout(5);
  const auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("hbirl dashboard"), std::string::npos);
  const auto script = client.Get("/chartjs-chart-matrix.min.js");
  ASSERT_TRUE(script);
  EXPECT_EQ(script->status, 200);
  const auto json = client.Get("/api/state");
  ASSERT_TRUE(json);
  EXPECT_EQ(json->status, 200);
  EXPECT_EQ(json->get_header_value("Content-Type"), "application/json");
  const nlohmann::json s = nlohmann::json::parse(json->body);
  EXPECT_EQ(s["em"][0]["log_likelihood"], -3.5);
  EXPECT_EQ(s["theta"]["learned"][0], 0.25);
  const auto frame = client.Get("/api/frame.png");
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->status, 404);
  EXPECT_EQ(client.Get("/no/such/file")->status, 404);
  server.stop();
  serving.join();
  EXPECT_THROW(Server(state, "/nonexistent"), InputError);
}

// A raw TCP connection to the server; -1 if it could not connect.
int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// 50 slow clients -- half send the start of a request and then a byte every 4 s, half
// connect and say nothing -- used to stop the dashboard answering for as long as they
// stayed. With a connection limit and a 0.3 s timeout they are dropped in turn and a
// real request is answered while they keep trying.
TEST(DashboardServer, SlowAndIdleConnectionsDoNotStopIt) {
  DashboardState state;
  ServerLimits limits;
  limits.max_connections = 4;
  limits.timeout_s = 0.3;
  Server server(state, HBIRL_DASHBOARD_WEB_DIR, limits);
  const int port = server.bind("127.0.0.1", 0);
  std::thread serving([&server] { server.run(); });
  std::vector<int> slow;
  for (int i = 0; i < 50; ++i) {
    const int fd = connect_to(port);
    ASSERT_GE(fd, 0);
    if (i % 2 == 0) (void)!::send(fd, "GET /api/sta", 12, MSG_NOSIGNAL);
    slow.push_back(fd);
  }
  std::atomic<bool> stop{false};
  std::thread trickle([&] {  // a byte every 4 s on each, while the test runs
    for (int round = 0; !stop; ++round) {
      for (int k = 0; k < 40 && !stop; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      for (int fd : slow) (void)!::send(fd, "t", 1, MSG_NOSIGNAL);
    }
  });
  httplib::Client client("127.0.0.1", port);
  client.set_connection_timeout(30);
  client.set_read_timeout(30);
  const auto json = client.Get("/api/state");
  stop = true;
  trickle.join();
  ASSERT_TRUE(json) << "no answer while 50 slow clients were connected";
  EXPECT_EQ(json->status, 200);
  for (int fd : slow) ::close(fd);
  server.stop();
  serving.join();
}

}  // namespace
}  // namespace hbirl::dashboard
