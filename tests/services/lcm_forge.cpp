// Test helper: a forger without the run's key, who knows the protocol and sends
// well-formed messages at the worst moment (tests/services/netns_test.sh; docs/RELIABILITY.md).
//   lcm_forge URL end-run N [E] once episode E (default 0) has ended, an END_RUN stating N
//                               episodes (0: not stated; the run has more), in the run's
//                               domain, five times; then exits
//   lcm_forge URL ghosts N HZ   N made-up sampler workers, each heartbeat copying a real
//                               worker's MDP digest, numerics and held blocks, HZ times a
//                               second each, until the final REWARD (or SIGTERM)
#include <chrono>
#include <csignal>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>

#include "hbirl/episode_marker_t.hpp"
#include "hbirl/reward_t.hpp"
#include "hbirl/service_status_t.hpp"
#include "services/channels.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_term(int) { g_stop = 1; }

int forge_end_run(lcm::LCM& lcm, int episodes, int after) {
  hbirl::episode_marker_t seen{};
  bool ended = false;
  struct Watch {
    hbirl::episode_marker_t* seen;
    bool* ended;
    int after;
    void on(const lcm::ReceiveBuffer*, const std::string&, const hbirl::episode_marker_t* m) {
      if (m->kind == hbirl::episode_marker_t::END_EPISODE && m->episode == after && !*ended) {
        *seen = *m;
        *ended = true;
      }
    }
  } watch{&seen, &ended, after};
  lcm.subscribe(hbirl::services::channels::kEpisode.name, &Watch::on, &watch);
  while (!ended && !g_stop) lcm.handleTimeout(100);
  if (!ended) return 1;
  hbirl::episode_marker_t forged = seen;
  forged.kind = hbirl::episode_marker_t::END_RUN;
  forged.episode = 0;
  forged.num_steps = episodes;
  for (int k = 0; k < 5; ++k) {  // repeated, as the simulator repeats its own
    forged.seq = seen.seq + 1 + k;
    lcm.publish(hbirl::services::channels::kEpisode.name, &forged);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::printf("forged END_RUN of %d episodes (5 times) after episode %d ended (%s)\n", episodes, seen.episode,
              seen.domain.c_str());
  return 0;
}

int ghosts(lcm::LCM& lcm, int count, double hz) {
  hbirl::service_status_t real{};
  bool have = false, learned = false;
  struct Watch {
    hbirl::service_status_t* real;
    bool* have;
    bool* learned;
    void on_status(const lcm::ReceiveBuffer*, const std::string&, const hbirl::service_status_t* m) {
      // A real worker's heartbeat that holds blocks (not one of ours).
      if (m->service == "sampler" && m->id.rfind("ghost-", 0) != 0 && m->num_held_blocks > 0) {
        *real = *m;
        *have = true;
      }
    }
    void on_reward(const lcm::ReceiveBuffer*, const std::string&, const hbirl::reward_t* r) {
      *learned = *learned || r->final;
    }
  } watch{&real, &have, &learned};
  lcm.subscribe(hbirl::services::channels::kStatus.name, &Watch::on_status, &watch);
  lcm.subscribe(hbirl::services::channels::kReward.name, &Watch::on_reward, &watch);
  const auto period = std::chrono::duration<double>(1.0 / hz);
  long sent = 0;
  auto next = std::chrono::steady_clock::now();
  while (!g_stop && !learned) {
    lcm.handleTimeout(1);
    if (!have || std::chrono::steady_clock::now() < next) continue;
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    for (int k = 0; k < count; ++k) {
      hbirl::service_status_t ghost = real;
      ghost.id = "ghost-" + std::to_string(k);
      ghost.seq = sent;
      ghost.restarts = 0;
      lcm.publish(hbirl::services::channels::kStatus.name, &ghost);
      ++sent;
    }
  }
  std::printf("%ld ghost heartbeats sent (%d names, %.0f Hz)\n", sent, count, hz);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGTERM, on_term);
  std::signal(SIGINT, on_term);
  if (argc < 4) {
    std::fprintf(stderr, "usage: lcm_forge URL end-run N [E]  |  lcm_forge URL ghosts N HZ\n");
    return 2;
  }
  lcm::LCM lcm(argv[1]);
  if (!lcm.good()) return 1;
  const std::string what = argv[2];
  if (what == "end-run") return forge_end_run(lcm, std::stoi(argv[3]), argc > 4 ? std::stoi(argv[4]) : 0);
  if (what == "ghosts" && argc == 5) return ghosts(lcm, std::stoi(argv[3]), std::stod(argv[4]));
  std::fprintf(stderr, "lcm_forge: unknown '%s'\n", what.c_str());
  return 2;
}
