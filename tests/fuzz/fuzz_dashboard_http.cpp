// libFuzzer target: the dashboard's HTTP request handling (dashboard/src/server.cpp on
// cpp-httplib: request line, headers, ranges, chunked and multipart bodies, the static
// page's mount and the two API routes). The server runs as hbirl-dashboard runs it, bound
// to 127.0.0.1 on a free port; each input is written over a fresh TCP connection, whose
// sending side is then shut, and the whole answer read (at most 2 s). The state behind it
// holds one frame and some learning, so /api/state and /api/frame.png have content.
// An extra check: a file next to the page's directory, never served, must never show up
// in an answer (no path escapes the mount).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include "perception/image_codec.hpp"
#include <string>
#include <thread>

#include "dashboard/server.hpp"
#include "dashboard/state.hpp"

namespace {

using namespace hbirl;
namespace fs = std::filesystem;

constexpr char kSecret[] = "hbirl-fuzz-secret-3b1f9c";  // in the file no answer may contain

struct Served {
  fs::path root;
  dashboard::DashboardState state;
  std::unique_ptr<dashboard::Server> server;
  std::thread thread;
  int port = 0;

  Served() {
    char dir[] = "/tmp/hbirl-fuzz-http-XXXXXX";
    if (!mkdtemp(dir)) std::abort();
    root = dir;
    fs::create_directories(root / "web" / "sub");
    std::ofstream(root / "web" / "index.html") << "<!doctype html><title>hbirl</title>\n";
    std::ofstream(root / "web" / "dashboard.js") << "// page\n";
    std::ofstream(root / "web" / "sub" / "style.css") << "body{}\n";
    std::ofstream(root / "secret.txt") << kSecret;
    feed();
    server = std::make_unique<dashboard::Server>(state, (root / "web").string());
    port = server->bind("127.0.0.1", 0);
    thread = std::thread([this] { server->run(); });
  }
  ~Served() {
    server->stop();
    thread.join();
    fs::remove_all(root);
  }

  // A frame with its detections and observations, an EM iteration and a heartbeat.
  void feed() {
    hbirl::episode_marker_t marker{};
    marker.domain = "onion", marker.kind = hbirl::episode_marker_t::BEGIN_EPISODE, marker.num_steps = 1,
    marker.frames_per_step = 1;
    state.on_marker(marker);
    cv::Mat image(24, 32, CV_8UC3, cv::Scalar(40, 120, 200));
    std::vector<unsigned char> png;
    png = hbirl::perception::encode_png(image);
    hbirl::camera_frame_t frame{};
    frame.width = 32, frame.height = 24, frame.encoding = "png", frame.size = static_cast<std::int32_t>(png.size());
    frame.data = png;
    state.on_camera(frame);
    hbirl::detections_t d{};
    d.width = 32, d.height = 24, d.n = 1, d.cls = {hbirl::detections_t::CLASS_ONION}, d.x = {10}, d.y = {10},
    d.area = {9}, d.box_x = {8}, d.box_y = {8}, d.box_w = {4}, d.box_h = {4}, d.dark_share = {0.5f};
    state.on_detections(d);
    hbirl::observations_t o{};
    o.num_symbols = 4, o.num_sources = 2, o.n = 1, o.symbol = {1}, o.eta = {{0.75, 0.25}};
    state.on_observations(o);
    hbirl::em_progress_t p{};
    p.iteration = 1, p.num_features = 2, p.theta = {1, 2}, p.log_likelihood = -3;
    state.on_progress(p);
    hbirl::service_status_t s{};
    s.service = "sampler", s.id = "sampler-1", s.state = "running";
    state.on_status(s, 1);
  }
};

Served* served = nullptr;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  served = new Served();  // never deleted: the server runs until the process ends
  return 0;
}

namespace {

// A connection to the server. Each comes from another loopback address (127.1.0.0/16):
// a closed connection holds its port pair for a minute (TIME_WAIT), and at several
// hundred connections a second one address's ~28000 ports run out (the first long run
// stopped there, on a failed connect).
int connect_to_server() {
  static std::uint32_t n = 0;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) std::abort();
    sockaddr_in from{};
    from.sin_family = AF_INET;
    from.sin_addr.s_addr = htonl(0x7f010000u | (++n & 0xffffu));  // 127.1.x.y, port chosen by the kernel
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<std::uint16_t>(served->port));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&from), sizeof from) == 0 &&
        ::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to) == 0) {
      return fd;
    }
    ::close(fd);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::abort();  // the server no longer accepts connections
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const int fd = connect_to_server();
  const timeval timeout{2, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
  for (std::size_t sent = 0; sent < size;) {
    const ssize_t n = ::send(fd, data + sent, size - sent, MSG_NOSIGNAL);
    if (n <= 0) break;  // the server may close early (a bad request line)
    sent += static_cast<std::size_t>(n);
  }
  ::shutdown(fd, SHUT_WR);
  std::string answer;
  char buffer[16384];
  for (;;) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;  // closed, reset, or 2 s of silence
    answer.append(buffer, static_cast<std::size_t>(n));
    if (answer.size() > (64u << 20)) __builtin_trap();  // an answer no request should get
  }
  ::close(fd);
  if (answer.find(kSecret) != std::string::npos) __builtin_trap();  // a path escaped the page's directory
  return 0;
}
