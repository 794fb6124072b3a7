// The parts of the optimiser's side of the E-step over the bus, each alone: which worker
// gets which block, the send window, and the roster of workers.
#include <gtest/gtest.h>

#include <map>

#include "services/block_placement.hpp"
#include "services/memory_bus.hpp"
#include "services/send_window.hpp"
#include "services/worker_roster.hpp"
#include "sim_driver/gridworld/gridworld.hpp"

namespace hbirl::services {
namespace {

std::vector<std::uint64_t> digests(int blocks) {
  std::vector<std::uint64_t> out;
  for (int b = 0; b < blocks; ++b) out.push_back(1000 + static_cast<std::uint64_t>(b));
  return out;
}

std::map<std::string, int> shares(const std::vector<std::string>& placed) {
  std::map<std::string, int> out;
  for (const auto& w : placed) ++out[w];
  return out;
}

hbirl::service_status_t heartbeat(const std::string& id, std::vector<std::int64_t> held = {}) {
  hbirl::service_status_t m{};
  m.service = "sampler";
  m.id = id;
  m.state = "running";
  m.mdp_digest = 7;
  m.numerics = 9;
  m.num_held_blocks = static_cast<std::int32_t>(held.size());
  m.held_block = std::move(held);
  return m;
}

// Even shares among proven workers; a block stays with its worker from pass to pass; the
// blocks of a worker that left go to the others, who keep theirs.
TEST(BlockPlacement, EvenStableShares) {
  WorkerRoster roster(7, 9, false, 3.0);
  for (const char* w : {"a", "b", "c"}) roster[w].answers = 1;
  const std::vector<std::uint64_t> d = digests(10);
  std::vector<int> todo(10);
  for (int b = 0; b < 10; ++b) todo[static_cast<size_t>(b)] = b;
  std::vector<std::string> owners(10);
  const std::vector<std::string> first = place_blocks(todo, {"a", "b", "c"}, d, owners, roster);
  EXPECT_EQ(shares(first), (std::map<std::string, int>{{"a", 4}, {"b", 3}, {"c", 3}}));
  EXPECT_EQ(place_blocks(todo, {"a", "b", "c"}, d, owners, roster), first);
  const std::vector<std::string> without_b = place_blocks(todo, {"a", "c"}, d, owners, roster);
  EXPECT_EQ(shares(without_b), (std::map<std::string, int>{{"a", 5}, {"c", 5}}));
  for (int b = 0; b < 10; ++b) {
    if (first[static_cast<size_t>(b)] != "b") {
      EXPECT_EQ(without_b[static_cast<size_t>(b)], first[static_cast<size_t>(b)]) << b;
    }
  }
}

// A worker that never answered gets one block while others have proven themselves; a block
// a worker failed to hold twice goes to another that can -- none here (the new one is on
// trial with its one block): the optimiser computes it.
TEST(BlockPlacement, NewWorkersOnTrialAndBlocksTheyCannotHold) {
  WorkerRoster roster(7, 9, false, 3.0);
  roster["old"].answers = 3;
  roster["new"];
  const std::vector<std::uint64_t> d = digests(6);
  std::vector<std::string> owners(6);
  const std::vector<int> todo = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(shares(place_blocks(todo, {"new", "old"}, d, owners, roster)),
            (std::map<std::string, int>{{"new", 1}, {"old", 5}}));
  roster["old"].unheld[d[2]] = 2;
  roster["old"].last_unheld = Worker::Clock::now();
  const std::vector<std::string> placed = place_blocks(todo, {"new", "old"}, d, owners, roster);
  EXPECT_EQ(placed[2], "");
  EXPECT_EQ(shares(placed), (std::map<std::string, int>{{"", 1}, {"new", 1}, {"old", 4}}));
}

// Heartbeats: blocks acknowledged, made-up digests not kept, a worker on its way out gone.
TEST(WorkerRoster, HeartbeatsAcknowledgeAndForget) {
  WorkerRoster roster(7, 9, true, 3.0);
  roster["w"].sent[1000] = {Worker::Clock::now(), 100};
  const WorkerRoster::Heard heard = roster.hear(heartbeat("w", {1000, 555555}), {1000, 1001});
  EXPECT_EQ(heard.acknowledged, 1);
  EXPECT_FALSE(heard.needs_mdp);
  EXPECT_EQ(roster["w"].held, (std::set<std::uint64_t>{1000}));
  EXPECT_EQ(roster.live(true), std::vector<std::string>{"w"});
  EXPECT_TRUE(roster.live(false).empty());  // never answered: no work once trials are spent
  hbirl::service_status_t other = heartbeat("x");
  other.numerics = 10;
  EXPECT_TRUE(roster.hear(other, {}).new_numerics);
  EXPECT_EQ(roster.live(true), std::vector<std::string>{"w"});  // same numerics only
  hbirl::service_status_t done = heartbeat("w");
  done.state = "done";
  roster.hear(done, {});
  EXPECT_EQ(roster.find("w"), nullptr);
}

// The window: with nothing acknowledged, one block goes at a time once the window is full;
// an acknowledgement makes room.
TEST(SendWindow, SendsWhatTheWindowHolds) {
  Rng rng(3);
  const GridworldTask task = make_gridworld_task({}, 3 * ObservationEStep::kBlockSize, 4, rng);
  std::vector<ObservedTrajectory> observed;
  for (const Trajectory& t : task.trajectories) {
    ObservedTrajectory o;
    o.step_begin.assign(t.size() + 1, 0);
    o.eta.resize(0, 1);
    observed.push_back(o);
  }
  ObservationPrior prior;
  prior.num_symbols = 1;
  prior.subject_alpha = Eigen::MatrixXd::Ones(task.mdp.num_pairs(), 1);
  prior.confounder_alpha = Eigen::MatrixXd::Ones(0, 1);
  const ObservationEStep estep(task.mdp, observed, prior);
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub);
  Counters counters;
  counters.quiet = true;
  WorkerRoster roster(7, 9, false, 3.0);
  SendWindow window(bus, counters, 1, std::chrono::milliseconds(10000));
  const std::vector<std::uint64_t> d = digests(3);
  window.queue({0, 1, 2}, {"w", "w", "w"}, d, roster);
  EXPECT_EQ(window.pump(estep, d, roster), 1);
  EXPECT_EQ(window.pump(estep, d, roster), 0);  // the first is in flight
  roster.hear(heartbeat("w", {static_cast<std::int64_t>(d[0])}), {d.begin(), d.end()});
  EXPECT_EQ(window.pump(estep, d, roster), 1);
  EXPECT_EQ(window.drop(), std::set<std::string>{"w"});
  EXPECT_EQ(window.trajectories_sent(), 2 * ObservationEStep::kBlockSize);
}

}  // namespace
}  // namespace hbirl::services
