#include "dashboard/server.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "learner/input_error.hpp"
// Last: it brings glibc's <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace hbirl::dashboard {

namespace {

// cpp-httplib's task queue with a bound: `workers` threads serve connections, at most as
// many more wait, and enqueue() -- called by the accepting thread -- blocks while the line
// is full, so the server stops accepting instead of growing without end.
class BoundedPool final : public httplib::TaskQueue {
 public:
  explicit BoundedPool(int workers) : capacity_(static_cast<size_t>(workers)) {
    for (int i = 0; i < workers; ++i) threads_.emplace_back([this] { work(); });
  }
  void enqueue(std::function<void()> fn) override {
    std::unique_lock<std::mutex> lock(mutex_);
    room_.wait(lock, [this] { return jobs_.size() < capacity_ || stopping_; });
    jobs_.push_back(std::move(fn));
    ready_.notify_one();
  }
  void shutdown() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    ready_.notify_all();
    room_.notify_all();
    for (auto& t : threads_) t.join();
  }

 private:
  void work() {
    for (;;) {
      std::function<void()> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [this] { return !jobs_.empty() || stopping_; });
        if (jobs_.empty()) return;  // stopping, and the line is empty
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
      room_.notify_one();
      job();  // serves one connection and closes it
    }
  }
  const size_t capacity_;
  std::vector<std::thread> threads_;
  std::deque<std::function<void()>> jobs_;
  std::mutex mutex_;
  std::condition_variable ready_, room_;
  bool stopping_ = false;
};

}  // namespace

struct Server::Impl {
  httplib::Server http;
};

Server::Server(const DashboardState& state, const std::string& web_dir, ServerLimits limits) : impl_(std::make_unique<Impl>()) {
  if (!std::filesystem::exists(std::filesystem::path(web_dir) / "index.html")) {
    throw InputError("--web", "no index.html in '" + web_dir + "' (the dashboard's page; built into build/dashboard/web)");
  }
  httplib::Server& http = impl_->http;
  const int workers = std::max(1, limits.max_connections);
  http.new_task_queue = [workers] { return new BoundedPool(workers); };
  const auto timeout = std::chrono::microseconds(static_cast<long long>(std::max(0.001, limits.timeout_s) * 1e6));
  http.set_read_timeout(timeout);
  http.set_write_timeout(timeout);
  http.set_keep_alive_timeout(static_cast<time_t>(std::max(1.0, limits.timeout_s)));
  http.set_keep_alive_max_count(5);
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
