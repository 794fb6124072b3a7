#include "dashboard/server.hpp"

#include <gtest/gtest.h>

#include <thread>

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

}  // namespace
}  // namespace hbirl::dashboard
