#include "dashboard/server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <deque>
#include <filesystem>
#include <functional>
#include <list>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <unordered_map>
#include <vector>

#include "learner/input_error.hpp"
// Last: it brings glibc's <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

// How a connection is served (issue 30). cpp-httplib's own server gives each accepted
// connection a worker thread that reads the request line and headers with a timeout per
// read: a client sending a byte every 1.9 s (under the 2 s timeout) held a thread for as
// long as it kept at it, and 33 of them left no thread for anyone else. Here:
//   - the accepting thread (httplib's) only hands each connection to the gate;
//   - the gate, one thread, waits for the connections' request heads with poll(), looking
//     at what has arrived without reading it (MSG_PEEK). A connection whose whole head is
//     not in by its deadline (--header-timeout after it was accepted), that sends nothing
//     for --http-timeout, or whose head grows past max_head_bytes is closed unanswered.
//     Waiting connections are capped per client address and in total; a new one beyond a
//     cap closes the OLDEST waiting one (see Gate::admit for why not the new one);
//   - a connection whose head is complete goes to the workers (--max-connections threads,
//     as many more complete ones in line), which parse and answer it with httplib's
//     process_request and close it: one request per connection, so a second request can
//     never trickle on a thread. Whatever the client still sends or takes (no route reads
//     a body: methods other than GET and HEAD are answered 405 unread) must be done
//     within --header-timeout of the hand-off, and each read or write within
//     --http-timeout.
// So a thread only ever holds a connection whose request is all there, and for a bounded
// time; slow clients cost the gate a file descriptor and a poll entry each.

namespace hbirl::dashboard {

// Named, not anonymous: Server::Impl holds an HttpServer.
namespace http_detail {

using Clock = std::chrono::steady_clock;

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

void close_socket(int fd) {
  ::shutdown(fd, SHUT_RDWR);
  ::close(fd);
}

bool again(int error) { return error == EAGAIN || error == EWOULDBLOCK || error == EINTR; }

// Waits at most `most` (and not past `deadline`) for `events` on fd; true when they (or an
// error, which the next call reports) came.
bool wait_for(int fd, short events, Clock::time_point deadline, Clock::duration most) {
  for (;;) {
    const auto left = std::min(deadline - Clock::now(), most);
    if (left <= Clock::duration::zero()) return false;
    pollfd p{fd, events, 0};
    const auto ms = std::chrono::ceil<std::chrono::milliseconds>(left).count();
    const int n = ::poll(&p, 1, static_cast<int>(ms));
    if (n > 0) return true;
    if (n < 0 && errno != EINTR) return false;
  }
}

void address_of(const sockaddr_storage& a, std::string& ip, int& port) {
  char text[INET6_ADDRSTRLEN] = "";
  if (a.ss_family == AF_INET) {
    sockaddr_in in{};
    std::memcpy(&in, &a, sizeof in);
    ::inet_ntop(AF_INET, &in.sin_addr, text, sizeof text);
    port = ntohs(in.sin_port);
  } else if (a.ss_family == AF_INET6) {
    sockaddr_in6 in6{};
    std::memcpy(&in6, &a, sizeof in6);
    ::inet_ntop(AF_INET6, &in6.sin6_addr, text, sizeof text);
    port = ntohs(in6.sin6_port);
  }
  ip = text;
}

// A served connection as cpp-httplib reads and writes it (its SocketStream is not in the
// packaged header), with a deadline for the whole exchange on top of the time each read
// or write may wait.
class DeadlineStream final : public httplib::Stream {
 public:
  DeadlineStream(int fd, Clock::time_point deadline, Clock::duration each)
      : fd_(fd), deadline_(deadline), each_(each) {}
  bool is_readable() const override { return begin_ < end_ || wait_for(fd_, POLLIN, deadline_, each_); }
  bool is_writable() const override { return wait_for(fd_, POLLOUT, deadline_, each_); }
  ssize_t read(char* ptr, size_t size) override {
    if (begin_ == end_) {  // buffered: httplib reads the head a byte at a time
      ssize_t n = -1;
      for (;;) {
        if (!wait_for(fd_, POLLIN, deadline_, each_)) return -1;
        n = ::recv(fd_, buffer_, sizeof buffer_, MSG_DONTWAIT);
        if (n >= 0 || !again(errno)) break;
      }
      if (n <= 0) return n;
      begin_ = 0;
      end_ = static_cast<size_t>(n);
    }
    const size_t n = std::min(size, end_ - begin_);
    std::memcpy(ptr, buffer_ + begin_, n);
    begin_ += n;
    return static_cast<ssize_t>(n);
  }
  using httplib::Stream::write;
  ssize_t write(const char* ptr, size_t size) override {
    for (;;) {
      if (!wait_for(fd_, POLLOUT, deadline_, each_)) return -1;
      const ssize_t n = ::send(fd_, ptr, size, MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n >= 0 || !again(errno)) return n;
    }
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    if (::getpeername(fd_, reinterpret_cast<sockaddr*>(&a), &len) == 0) address_of(a, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) == 0) address_of(a, ip, port);
  }
  ::socket_t socket() const override { return fd_; }

 private:
  const int fd_;
  const Clock::time_point deadline_;
  const Clock::duration each_;
  char buffer_[4096];
  size_t begin_ = 0, end_ = 0;
};

// An eventfd: wakes the gate when a connection arrives, a worker frees its place, or it
// is to stop.
class Wake {
 public:
  Wake() : fd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
    if (fd_ < 0) throw std::runtime_error(std::string("dashboard: eventfd: ") + std::strerror(errno));
  }
  ~Wake() { ::close(fd_); }
  Wake(const Wake&) = delete;
  Wake& operator=(const Wake&) = delete;
  void notify() const {
    const std::uint64_t one = 1;
    (void)!::write(fd_, &one, sizeof one);
  }
  void drain() const {
    std::uint64_t n = 0;
    (void)!::read(fd_, &n, sizeof n);
  }
  int fd() const { return fd_; }

 private:
  const int fd_;
};

// The workers: `threads` threads, each serving one connection whose head has arrived;
// at most as many more wait their turn here (beyond that the gate keeps them).
class Workers {
 public:
  Workers(int threads, std::function<void(int)> serve, const Wake& wake)
      : capacity_(static_cast<size_t>(threads)), serve_(std::move(serve)), wake_(wake) {
    for (int i = 0; i < threads; ++i) threads_.emplace_back([this] { work(); });
  }
  ~Workers() { stop(); }
  Workers(const Workers&) = delete;
  Workers& operator=(const Workers&) = delete;
  // Takes fd (true) unless the line is full; never blocks.
  bool offer(int fd) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_ || jobs_.size() >= capacity_) return false;
      jobs_.push_back(fd);
    }
    ready_.notify_one();
    return true;
  }
  // Cuts the connections being served short, closes those in line, joins the threads.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) return;
      stopping_ = true;
      for (int fd : busy_) ::shutdown(fd, SHUT_RDWR);
    }
    ready_.notify_all();
    for (auto& t : threads_) t.join();
    for (int fd : jobs_) close_socket(fd);
    jobs_.clear();
  }

 private:
  void work() {
    for (;;) {
      int fd = -1;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [this] { return !jobs_.empty() || stopping_; });
        if (stopping_) return;
        fd = jobs_.front();
        jobs_.pop_front();
        busy_.insert(fd);
      }
      wake_.notify();  // a place in line is free: the gate may hand over another
      serve_(fd);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        busy_.erase(fd);  // before close: stop() never shuts a reused descriptor
      }
      close_socket(fd);
    }
  }
  const size_t capacity_;
  const std::function<void(int)> serve_;
  const Wake& wake_;
  std::vector<std::thread> threads_;
  std::deque<int> jobs_;
  std::set<int> busy_;
  std::mutex mutex_;
  std::condition_variable ready_;
  bool stopping_ = false;
};

// The client a connection counts against: its IPv4 address, or its IPv6 address's first
// 64 bits (one host commonly holds a whole /64).
std::string client_of(int fd) {
  sockaddr_storage a{};
  socklen_t len = sizeof a;
  if (::getpeername(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) return {};
  if (a.ss_family == AF_INET) {
    sockaddr_in in{};
    std::memcpy(&in, &a, sizeof in);
    return std::string(reinterpret_cast<const char*>(&in.sin_addr), 4);
  }
  if (a.ss_family == AF_INET6) {
    sockaddr_in6 in6{};
    std::memcpy(&in6, &a, sizeof in6);
    const auto* bytes = reinterpret_cast<const char*>(in6.sin6_addr.s6_addr);
    if (IN6_IS_ADDR_V4MAPPED(&in6.sin6_addr)) return std::string(bytes + 12, 4);
    return std::string(bytes, 8);
  }
  return {};
}

// Whether `head` holds a whole request head as httplib reads it: after the request line,
// a line that is exactly "\r\n" (httplib skips lines that end in a bare "\n").
bool head_complete(std::string_view head) {
  const size_t first = head.find('\n');
  return first != std::string_view::npos && head.find("\n\r\n", first) != std::string_view::npos;
}

// The gate: one thread that holds connections until their request heads have arrived
// (see the top of this file).
class Gate {
 public:
  Gate(const ServerLimits& limits, Workers& workers, const Wake& wake)
      : header_timeout_(seconds(std::max(0.001, limits.header_timeout_s))),
        idle_timeout_(seconds(std::max(0.001, limits.timeout_s))),
        max_per_client_(static_cast<size_t>(std::max(1, limits.max_waiting_per_client))),
        max_waiting_(static_cast<size_t>(std::max(1, limits.max_waiting))),
        peek_(static_cast<size_t>(std::max(64, limits.max_head_bytes))),
        workers_(workers),
        wake_(wake),
        thread_([this] { run(); }) {}
  ~Gate() { stop(); }
  Gate(const Gate&) = delete;
  Gate& operator=(const Gate&) = delete;

  // A connection just accepted (httplib's accepting thread): never blocks.
  void add(int fd) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!stopping_) {
        arrived_.push_back(fd);
        fd = -1;
      }
    }
    if (fd >= 0) {
      close_socket(fd);
    } else {
      wake_.notify();
    }
  }

  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) return;
      stopping_ = true;
    }
    wake_.notify();
    thread_.join();
    for (const auto& w : waiting_) close_socket(w.fd);
    waiting_.clear();
    for (int fd : arrived_) close_socket(fd);
    arrived_.clear();
  }

 private:
  struct Waiting {
    int fd;
    std::string client;
    Clock::time_point deadline;    // of the whole head
    Clock::time_point idle_until;  // --http-timeout after its last new byte
    Clock::time_point rest_until;  // not polled before (see inspect)
    size_t seen = 0;               // bytes of the head that have arrived
    bool complete = false;         // its head is all there (or the client has shut its side): for a worker
  };
  using Entry = std::list<Waiting>::iterator;

  void run() {
    std::vector<pollfd> polled;
    std::vector<Entry> entries;
    for (;;) {
      std::vector<int> arrived;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (stopping_) return;
        arrived.swap(arrived_);
      }
      auto now = Clock::now();
      for (int fd : arrived) admit(fd, now);
      for (auto it = waiting_.begin(); it != waiting_.end();) {  // past their deadlines: closed unanswered
        const auto next = std::next(it);
        if (!it->complete && (now >= it->deadline || now >= it->idle_until)) drop(it);
        it = next;
      }
      for (auto it = waiting_.begin();
           it != waiting_.end();) {  // complete heads, in order of arrival, while the workers have room
        const auto next = std::next(it);
        if (it->complete) {
          if (!workers_.offer(it->fd)) break;
          forget(it);
        }
        it = next;
      }

      polled.assign(1, pollfd{wake_.fd(), POLLIN, 0});
      entries.assign(1, waiting_.end());
      auto until = now + std::chrono::seconds(1);
      for (auto it = waiting_.begin(); it != waiting_.end(); ++it) {
        if (it->complete) continue;  // waits for a worker: the workers wake us
        until = std::min({until, it->deadline, it->idle_until});
        if (it->rest_until > now) {
          until = std::min(until, it->rest_until);
          continue;
        }
        polled.push_back(pollfd{it->fd, POLLIN | POLLRDHUP, 0});
        entries.push_back(it);
      }
      const auto ms = std::max<long long>(0, std::chrono::ceil<std::chrono::milliseconds>(until - now).count());
      const int n = ::poll(polled.data(), polled.size(), static_cast<int>(ms));
      if (n <= 0) continue;
      if (polled[0].revents) wake_.drain();
      now = Clock::now();
      for (size_t i = 1; i < polled.size(); ++i) {
        if (polled[i].revents) inspect(entries[i], polled[i].revents, now);
      }
    }
  }

  // A new connection joins the waiting ones. When its client already has as many waiting
  // as it may, its OLDEST waiting connection is closed to make room, not the new one:
  // a client that sends its request whole must always be served, and a limit that
  // refused new connections would refuse it whenever an attacker shares its address (a
  // NAT, a proxy, this machine: every test client is 127.0.0.1) and keeps that address
  // at its limit. The oldest is the one most likely to be trickling: a real request's
  // head arrives in one packet, moments after it connects. Beyond the cap on all waiting
  // connections, likewise the oldest of anyone's.
  void admit(int fd, Clock::time_point now) {
    std::string client = client_of(fd);
    if (per_client_[client] >= max_per_client_) drop(oldest(&client));
    if (waiting_.size() >= max_waiting_) drop(oldest(nullptr));
    ++per_client_[client];
    waiting_.push_back(Waiting{fd, std::move(client), now + header_timeout_, now + idle_timeout_, now, 0, false});
    inspect(std::prev(waiting_.end()), 0, now);  // it may have all arrived already
  }

  // The oldest waiting connection (of `client`, if given) still waiting for its head, else
  // the oldest waiting for a worker.
  Entry oldest(const std::string* client) {
    Entry complete = waiting_.end();
    for (auto it = waiting_.begin(); it != waiting_.end(); ++it) {
      if (client && it->client != *client) continue;
      if (!it->complete) return it;
      if (complete == waiting_.end()) complete = it;
    }
    return complete;
  }

  // Looks at what has arrived on a waiting connection, without reading it.
  void inspect(Entry it, short revents, Clock::time_point now) {
    if (revents & (POLLERR | POLLHUP | POLLNVAL)) return drop(it);
    const ssize_t n = ::recv(it->fd, peek_.data(), peek_.size(), MSG_PEEK | MSG_DONTWAIT);
    if (n == 0) return drop(it);  // closed before it sent anything
    if (n < 0) {
      if (!again(errno)) return drop(it);
      if (revents) it->rest_until = now + std::chrono::milliseconds(20);  // see below
      return;
    }
    const auto size = static_cast<size_t>(n);
    if (head_complete(std::string_view(peek_.data(), size)) || (revents & POLLRDHUP)) {
      // Whole, or the client has shut its side (nothing more can come): httplib reads it.
      it->complete = true;
      set_low_water(it->fd, 1);
      return;
    }
    if (size >= peek_.size()) {
      static const char kTooLarge[] =
          "HTTP/1.1 431 Request Header Fields Too Large\r\nContent-Length: 0\r\nConnection: close\r\n\r\n";
      (void)!::send(it->fd, kTooLarge, sizeof kTooLarge - 1, MSG_DONTWAIT | MSG_NOSIGNAL);
      return drop(it);
    }
    if (size == it->seen) {
      // Woken without anything new (the kernel may, e.g. under memory pressure): not
      // polled again for a moment rather than spinning.
      if (revents) it->rest_until = now + std::chrono::milliseconds(20);
      return;
    }
    it->seen = size;
    it->idle_until = now + idle_timeout_;
    // poll() reports it again only once at least one more byte has come (Linux's TCP
    // honours SO_RCVLOWAT in poll): a client trickling its head wakes the gate once per
    // byte it sends, not at every turn of the loop.
    set_low_water(it->fd, static_cast<int>(size) + 1);
  }

  static void set_low_water(int fd, int bytes) { ::setsockopt(fd, SOL_SOCKET, SO_RCVLOWAT, &bytes, sizeof bytes); }

  // No longer waits here (handed to the workers, or about to be closed).
  void forget(Entry it) {
    const auto count = per_client_.find(it->client);
    if (count != per_client_.end() && --count->second == 0) per_client_.erase(count);
    waiting_.erase(it);
  }
  void drop(Entry it) {
    if (it == waiting_.end()) return;
    close_socket(it->fd);
    forget(it);
  }

  const Clock::duration header_timeout_, idle_timeout_;
  const size_t max_per_client_, max_waiting_;
  std::vector<char> peek_;
  Workers& workers_;
  const Wake& wake_;
  std::mutex mutex_;
  std::vector<int> arrived_;  // from the accepting thread
  bool stopping_ = false;
  std::list<Waiting> waiting_;  // in order of arrival (the gate's thread only)
  std::unordered_map<std::string, size_t> per_client_;
  std::thread thread_;  // last: starts once the rest is ready
};

// httplib's task queue that runs each task at once, on the accepting thread: the task is
// handing the connection to the gate, which never blocks.
class HandOff final : public httplib::TaskQueue {
 public:
  void enqueue(std::function<void()> fn) override { fn(); }
  void shutdown() override {}
};

// httplib's server, its connections handed to the gate instead of each to a thread.
class HttpServer final : public httplib::Server {
 public:
  explicit HttpServer(const ServerLimits& limits)
      : budget_(seconds(std::max(0.001, limits.header_timeout_s))), each_(seconds(std::max(0.001, limits.timeout_s))) {
    new_task_queue = [] { return new HandOff; };
  }
  // Set while run() serves (the accepting thread reads it: the thread that sets it).
  Gate* gate = nullptr;

  // httplib listens with a backlog of 5 (compiled into the library): a burst of a few
  // connections -- the slow clients' -- filled it and the kernel dropped the next ones'
  // SYNs, which their clients sent again only a second later (tested: a normal request
  // waited 1 s). Listening again on the bound socket only sets a longer line; the
  // accepting thread empties it at once, since it never waits for anything.
  void lengthen_backlog() {
    const int sock = svr_sock_;
    if (sock >= 0) ::listen(sock, SOMAXCONN);
  }

  // A worker's job: answers the one request of a connection whose head has arrived.
  void serve(int fd) {
    DeadlineStream stream(fd, Clock::now() + budget_, each_);
    bool closed = true;
    process_request(stream, /*close_connection=*/true, closed, nullptr);
  }

 private:
  bool process_and_close_socket(::socket_t sock) override {  // httplib's private virtual
    if (gate) {
      gate->add(sock);
    } else {
      close_socket(sock);
    }
    return true;
  }
  const Clock::duration budget_, each_;
};

}  // namespace http_detail

using http_detail::Gate;
using http_detail::HttpServer;
using http_detail::Wake;
using http_detail::Workers;

struct Server::Impl {
  explicit Impl(const ServerLimits& l) : limits(l), http(l) {}
  const ServerLimits limits;
  HttpServer http;
};

Server::Server(const DashboardState& state, const std::string& web_dir, ServerLimits limits)
    : impl_(std::make_unique<Impl>(limits)) {
  if (!std::filesystem::exists(std::filesystem::path(web_dir) / "index.html")) {
    throw InputError("--web",
                     "no index.html in '" + web_dir + "' (the dashboard's page; built into build/dashboard/web)");
  }
  httplib::Server& http = impl_->http;
  if (!http.set_mount_point("/", web_dir)) throw InputError("--web", "cannot serve '" + web_dir + "'");
  // Only GET and HEAD are served; anything else is answered before its body would be read
  // (httplib reads the body of a POST, PUT, ... before routing it: a slow or huge body).
  http.set_pre_routing_handler([](const httplib::Request& req, httplib::Response& res) {
    if (req.method == "GET" || req.method == "HEAD") return httplib::Server::HandlerResponse::Unhandled;
    res.status = 405;
    res.set_header("Allow", "GET, HEAD");
    return httplib::Server::HandlerResponse::Handled;
  });
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
  const int bound = port == 0 ? impl_->http.bind_to_any_port(host.c_str())
                              : (impl_->http.bind_to_port(host.c_str(), port) ? port : -1);
  if (bound < 0)
    throw InputError("--port",
                     "cannot listen on " + host + ":" + std::to_string(port) + " (in use? try another --port)");
  impl_->http.lengthen_backlog();
  return bound;
}

void Server::run() {
  HttpServer& http = impl_->http;
  Wake wake;
  Workers workers(
      std::max(1, impl_->limits.max_connections), [&http](int fd) { http.serve(fd); }, wake);
  Gate gate(impl_->limits, workers, wake);
  http.gate = &gate;
  http.listen_after_bind();  // accepts until stop()
  http.gate = nullptr;
  gate.stop();  // first: it hands connections to the workers
  workers.stop();
}

void Server::stop() {
  for (int i = 0; i < 200 && !impl_->http.is_running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  impl_->http.stop();
}

}  // namespace hbirl::dashboard
