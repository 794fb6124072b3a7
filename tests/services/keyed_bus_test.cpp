#include "services/keyed_bus.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "hbirl/episode_marker_t.hpp"
#include "learner/input_error.hpp"
#include "services/channels.hpp"
#include "services/memory_bus.hpp"
#include "service_threads.hpp"

namespace hbirl::services {
namespace {

using testing::quiet;

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("hbirl-keyed-bus-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::filesystem::remove(dir / name);
  return dir / name;
}

hbirl::episode_marker_t marker(int episode) {
  hbirl::episode_marker_t m{};
  m.domain = "corridor";
  m.episode = episode;
  m.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
  m.frames_per_step = 1;
  return m;
}

// Messages signed with the run key arrive as they were sent; unsigned ones, ones signed with
// another key, a signed message altered in one byte and one replayed on another channel
// reach no handler, and each is counted once.
TEST(KeyedBus, OnlyMessagesSignedWithTheKeyArrive) {
  auto hub = std::make_shared<MemoryHub>();
  const RunKey key = RunKey::generate(), other = RunKey::generate();
  Counters in = quiet("in"), out = quiet("out"), stranger_counters = quiet("stranger");
  KeyedBus receiver(std::make_unique<MemoryBus>(hub), key, in);
  KeyedBus sender(std::make_unique<MemoryBus>(hub), key, out);
  KeyedBus stranger(std::make_unique<MemoryBus>(hub), other, stranger_counters);
  MemoryBus raw(hub);
  std::vector<int> seen;
  subscribe<hbirl::episode_marker_t>(receiver, "EPISODE|OTHER", in,
                                     [&](const hbirl::episode_marker_t& m, const Message&) { seen.push_back(m.episode); });
  // What the raw endpoint sees of the sender's messages: to tamper with and replay.
  std::vector<std::vector<std::uint8_t>> wire;
  raw.subscribe("EPISODE", [&](const Message& m) { wire.emplace_back(m.data, m.data + m.size); });
  ASSERT_TRUE(publish(sender, channels::kEpisode, marker(1), out));
  ASSERT_TRUE(publish(raw, channels::kEpisode, marker(2), out));       // unsigned
  ASSERT_TRUE(publish(stranger, channels::kEpisode, marker(3), out));  // another key
  raw.handle(0);
  EXPECT_EQ(receiver.handle(0), 3);
  ASSERT_GE(wire.size(), 1u);
  std::vector<std::uint8_t> tampered = wire.front();
  tampered[20] ^= 1;  // inside the encoded marker
  raw.publish(channels::kEpisode, tampered.data(), static_cast<int>(tampered.size()));
  raw.publish("OTHER", wire.front().data(), static_cast<int>(wire.front().size()));  // signed for EPISODE
  raw.publish(channels::kEpisode, wire.front().data(), static_cast<int>(wire.front().size()));  // replayed as is
  EXPECT_EQ(receiver.handle(0), 3);
  EXPECT_EQ(seen, (std::vector<int>{1, 1}));  // the original and its replay (replays: docs/RELIABILITY.md)
  EXPECT_EQ(receiver.rejected(), 4);
  EXPECT_EQ(in.bad_messages, 4);
  EXPECT_TRUE(in.authenticated);
  EXPECT_NE(in.last_problem.find("not signed with this run's key"), std::string::npos) << in.last_problem;
}

// A reader without the key is told the messages are signed, not that they are garbage.
TEST(KeyedBus, UnkeyedReaderSaysGiveTheKey) {
  auto hub = std::make_shared<MemoryHub>();
  Counters out = quiet("out"), in = quiet("in");
  KeyedBus sender(std::make_unique<MemoryBus>(hub), RunKey::generate(), out);
  MemoryBus reader(hub);
  int seen = 0;
  subscribe<hbirl::episode_marker_t>(reader, "EPISODE", in, [&](const hbirl::episode_marker_t&, const Message&) { ++seen; });
  publish(sender, channels::kEpisode, marker(1), out);
  reader.handle(0);
  EXPECT_EQ(seen, 0);
  EXPECT_EQ(in.bad_messages, 1);
  EXPECT_NE(in.last_problem.find("give --key"), std::string::npos) << in.last_problem;
}

// Key files: written 0600 and never over another file; read back the same; refused when
// others may read them, when malformed, or when missing -- each with one line naming --key.
TEST(RunKey, FilesAreOwnerOnlyAndWellFormed) {
  const auto path = scratch("run.key");
  const RunKey key = RunKey::generate();
  key.write(path.string());
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(RunKey::read(path.string()).bytes(), key.bytes());
  EXPECT_NE(RunKey::generate().bytes(), key.bytes());
  try {
    key.write(path.string());
    ADD_FAILURE() << "overwrote a key file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "--key");
  }
  ::chmod(path.c_str(), 0644);
  try {
    RunKey::read(path.string());
    ADD_FAILURE() << "read a key file others may read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("chmod 600"), std::string::npos) << e.what();
  }
  const auto bad = scratch("bad.key");
  for (const std::string& text : std::vector<std::string>{"", "abc\n", std::string(64, 'g') + "\n", std::string(63, 'a') + "\n", std::string(66, 'a')}) {
    std::filesystem::remove(bad);
    std::ofstream(bad) << text;
    ::chmod(bad.c_str(), 0600);
    EXPECT_THROW(RunKey::read(bad.string()), InputError) << "'" << text << "'";
  }
  EXPECT_THROW(RunKey::read(scratch("missing.key").string()), InputError);
  std::filesystem::remove_all(path.parent_path());
}

}  // namespace
}  // namespace hbirl::services
