// A minimal sensor for hbirl's service set (docs/your-task.md "Your own task"): a camera at the end
// of examples/corridor.json's corridor sees a person walk to the exit, and a passer-by now
// and then. It publishes what any sensor must -- EPISODE markers and one OBSERVATIONS
// message per step -- and nothing of hbirl but its message types.
//   corridor_sensor [--url URL] [--episodes N]
#include <chrono>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <random>
#include <string>
#include <thread>

#include "hbirl/episode_marker_t.hpp"
#include "hbirl/observations_t.hpp"
#include "hbirl/service_status_t.hpp"

namespace {

void mark(lcm::LCM& bus, int episode, std::int8_t kind, int step = 0, int num_steps = 0) {
  hbirl::episode_marker_t m{};
  m.domain = "corridor";  // the domain file's name (its "name", else its stem)
  m.episode = episode;
  m.kind = kind;
  m.step = step;
  m.num_steps = num_steps;
  m.ends_in_terminal = num_steps > 0;  // it walked out of the exit
  m.frames_per_step = 1;
  bus.publish("EPISODE", &m);
}

struct OptimiserHeard {  // the optimiser listens once its heartbeat is heard
  bool heard = false;
  void on(const lcm::ReceiveBuffer*, const std::string&, const hbirl::service_status_t* s) {
    heard |= s->service == "optimiser";
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::string url;
  int episodes = 30;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "--url") url = argv[i + 1];
    if (std::string(argv[i]) == "--episodes") episodes = std::stoi(argv[i + 1]);
  }
  lcm::LCM bus(url);
  if (!bus.good()) return std::fprintf(stderr, "corridor_sensor: cannot open LCM at '%s'\n", url.c_str()), 1;
  OptimiserHeard optimiser;
  bus.subscribe("STATUS", &OptimiserHeard::on, &optimiser);
  for (int k = 0; k < 100 && !optimiser.heard; ++k) bus.handleTimeout(100);

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::int64_t seq = 0;
  for (int e = 0; e < episodes; ++e) {
    mark(bus, e, hbirl::episode_marker_t::BEGIN_EPISODE);
    int cell = u(rng) < 0.5 ? 0 : 1, t = 0;
    for (; cell < 3; ++t) {  // the person walks right; a step succeeds 8 times in 10
      mark(bus, e, hbirl::episode_marker_t::BEGIN_STEP, t);
      hbirl::observations_t o{};
      o.utime = (e * 100 + t) * 1000000LL;
      o.seq = ++seq;
      o.episode = e;
      o.step = t;
      o.num_symbols = 2;   // 0: a blob far left, 1: a blob near the exit
      o.num_sources = 2;   // the person, a passer-by
      if (u(rng) < 0.8) {  // the person, seen where they are (the detector errs 1 time in 5)
        o.symbol.push_back(static_cast<std::int16_t>((cell == 2) != (u(rng) < 0.2)));
        o.eta.push_back({0.8, 0.2});
      }
      if (u(rng) < 0.3) {  // a passer-by, mostly far left
        o.symbol.push_back(static_cast<std::int16_t>(u(rng) < 0.25));
        o.eta.push_back({0.3, 0.7});
      }
      o.n = static_cast<std::int32_t>(o.symbol.size());
      bus.publish("OBSERVATIONS", &o);
      if (u(rng) < 0.8) ++cell;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    mark(bus, e, hbirl::episode_marker_t::END_EPISODE, 0, t);
  }
  for (int k = 0; k < 3; ++k) {  // the end of the run, said three times: UDP may lose one
    mark(bus, 0, hbirl::episode_marker_t::END_RUN, 0, episodes);  // num_steps: how many episodes the run had
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::printf("corridor_sensor: %d episodes published\n", episodes);
  return 0;
}
