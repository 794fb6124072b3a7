#include "dashboard/server.hpp"

#include <chrono>
#include <filesystem>
#include <thread>

#include "learner/input_error.hpp"
// Last: it brings glibc's <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace hbirl::dashboard {

struct Server::Impl {
  httplib::Server http;
};

Server::Server(const DashboardState& state, const std::string& web_dir) : impl_(std::make_unique<Impl>()) {
  if (!std::filesystem::exists(std::filesystem::path(web_dir) / "index.html")) {
    throw InputError("--web", "no index.html in '" + web_dir + "' (the dashboard's page; built into build/dashboard/web)");
  }
  httplib::Server& http = impl_->http;
  if (!http.set_mount_point("/", web_dir)) throw InputError("--web", "cannot serve '" + web_dir + "'");
  http.Get("/api/state", [&state](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    // Strings from the network may not be UTF-8: replaced, never a failed page.
    res.set_content(state.json(services::wall_utime()).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
                    "application/json");
  });
  http.Get("/api/frame.png", [&state](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    const std::vector<unsigned char> png = state.frame_png();
    if (png.empty()) {
      res.status = 404;
      res.set_content("no camera frame yet", "text/plain");
      return;
    }
    res.set_content(reinterpret_cast<const char*>(png.data()), png.size(), "image/png");
  });
}

Server::~Server() = default;

int Server::bind(const std::string& host, int port) {
  const int bound = port == 0 ? impl_->http.bind_to_any_port(host.c_str()) : (impl_->http.bind_to_port(host.c_str(), port) ? port : -1);
  if (bound < 0) throw InputError("--port", "cannot listen on " + host + ":" + std::to_string(port) + " (in use? try another --port)");
  return bound;
}

void Server::run() { impl_->http.listen_after_bind(); }

void Server::stop() {
  for (int i = 0; i < 200 && !impl_->http.is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  impl_->http.stop();
}

}  // namespace hbirl::dashboard
