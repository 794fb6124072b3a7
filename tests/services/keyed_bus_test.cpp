#include "services/keyed_bus.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/types.h>

#include <filesystem>
#include <fstream>

#include "hbirl/episode_marker_t.hpp"
#include "learner/input_error.hpp"
#include "services/channels.hpp"
#include "services/log_bus.hpp"
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
  subscribe(receiver, Channel<hbirl::episode_marker_t>{"EPISODE|OTHER"}, in,
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
  raw.publish(channels::kEpisode.name, tampered.data(), static_cast<int>(tampered.size()));
  raw.publish("OTHER", wire.front().data(), static_cast<int>(wire.front().size()));  // signed for EPISODE
  raw.publish(channels::kEpisode.name, wire.front().data(), static_cast<int>(wire.front().size()));  // replayed as is
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
  subscribe(reader, channels::kEpisode, in, [&](const hbirl::episode_marker_t&, const Message&) { ++seen; });
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
  for (const std::string& text : std::vector<std::string>{"", "abc\n", std::string(64, 'g') + "\n",
                                                          std::string(63, 'a') + "\n", std::string(66, 'a')}) {
    std::filesystem::remove(bad);
    std::ofstream(bad) << text;
    ::chmod(bad.c_str(), 0600);
    EXPECT_THROW(RunKey::read(bad.string()), InputError) << "'" << text << "'";
  }
  EXPECT_THROW(RunKey::read(scratch("missing.key").string()), InputError);
  // A run's key file: the key, and the run on a second line; read back the same.
  const auto run_path = scratch("one-run.key");
  const RunKey one_run = key.for_new_run();
  one_run.write(run_path.string());
  const RunKey back = RunKey::read(run_path.string());
  EXPECT_EQ(back.bytes(), key.bytes());
  ASSERT_TRUE(back.run().has_value());
  EXPECT_EQ(*back.run(), *one_run.run());
  ::chmod(path.c_str(), 0600);
  EXPECT_FALSE(RunKey::read(path.string()).run().has_value());
  const std::string hex(64, 'a');
  for (const std::string& text : std::vector<std::string>{
           hex + "\nrun 0000000000000000\n", hex + "\nrun 12345\n", hex + "\nrum 0123456789abcdef\n",
           hex + "\nrun 0123456789abcdeg\n", hex + "\nrun 0123456789abcdef\nmore\n"}) {
    std::filesystem::remove(bad);
    std::ofstream(bad) << text;
    ::chmod(bad.c_str(), 0600);
    EXPECT_THROW(RunKey::read(bad.string()), InputError) << "'" << text << "'";
  }
  std::filesystem::remove(bad);
  std::ofstream(bad) << hex << "\nrun 0123456789abcdef\n";
  ::chmod(bad.c_str(), 0600);
  EXPECT_EQ(*RunKey::read(bad.string()).run(), 0x0123456789abcdefULL);
  std::filesystem::remove_all(path.parent_path());
}

// One key, many runs: every run's key file names its run, and its messages are signed for
// it. A bus of run A drops run B's messages, signed with the same key (counted once as bad
// and in other_run); a worker whose key file names no run serves both, each answer signed
// for the run of the request it answers; a reader without a run takes the first it sees.
TEST(KeyedBus, AKeySharedByRunsKeepsEachRunsMessagesApart) {
  auto hub = std::make_shared<MemoryHub>();
  const RunKey shared = RunKey::generate();
  const RunKey run_a = shared.for_new_run(), run_b = shared.for_new_run();
  ASSERT_TRUE(run_a.run() && run_b.run());
  ASSERT_NE(*run_a.run(), *run_b.run());
  Counters ca = quiet("a"), cb = quiet("b"), cw = quiet("worker"), cr = quiet("reader");
  KeyedBus a(std::make_unique<MemoryBus>(hub), run_a, ca), b(std::make_unique<MemoryBus>(hub), run_b, cb);
  KeyedBus worker(std::make_unique<MemoryBus>(hub), shared, cw, KeyUse::kWorker);
  KeyedBus reader(std::make_unique<MemoryBus>(hub), shared, cr, KeyUse::kReader);
  std::vector<int> seen_a, seen_b, seen_reader;
  std::vector<std::pair<int, RunId>> seen_worker;
  subscribe(a, Channel<hbirl::episode_marker_t>{"EPISODE|ANSWER"}, ca,
            [&](const hbirl::episode_marker_t& m, const Message&) { seen_a.push_back(m.episode); });
  subscribe(b, Channel<hbirl::episode_marker_t>{"EPISODE|ANSWER"}, cb,
            [&](const hbirl::episode_marker_t& m, const Message&) { seen_b.push_back(m.episode); });
  subscribe(reader, channels::kEpisode, cr,
            [&](const hbirl::episode_marker_t& m, const Message&) { seen_reader.push_back(m.episode); });
  subscribe(worker, channels::kEpisode, cw, [&](const hbirl::episode_marker_t& m, const Message& raw) {
    seen_worker.emplace_back(m.episode, raw.run);
  });
  publish(a, channels::kEpisode, marker(1), ca);
  publish(b, channels::kEpisode, marker(2), cb);
  for (Bus* bus : std::initializer_list<Bus*>{&a, &b, &worker, &reader}) bus->handle(0);
  EXPECT_EQ(seen_a, (std::vector<int>{1}));
  EXPECT_EQ(seen_b, (std::vector<int>{2}));
  EXPECT_EQ(seen_reader, (std::vector<int>{1}));  // run A came first: B's is another run's
  EXPECT_EQ(seen_worker, (std::vector<std::pair<int, RunId>>{{1, *run_a.run()}, {2, *run_b.run()}}));
  EXPECT_EQ(ca.other_run, 1);
  EXPECT_EQ(ca.bad_messages, 1);
  EXPECT_NE(ca.last_problem.find("another run"), std::string::npos) << ca.last_problem;
  EXPECT_EQ(cb.other_run, 1);
  EXPECT_EQ(cr.other_run, 1);
  EXPECT_EQ(reader.run(), *run_a.run());
  // The worker answers each run in its own: A hears the answer signed for A, B the one for B.
  worker.sign_for_run(*run_b.run());
  publish(worker, Channel<hbirl::episode_marker_t>{"ANSWER"}, marker(20), cw);
  worker.sign_for_run(*run_a.run());
  publish(worker, Channel<hbirl::episode_marker_t>{"ANSWER"}, marker(10), cw);
  a.handle(0);
  b.handle(0);
  EXPECT_EQ(seen_a, (std::vector<int>{1, 10}));
  EXPECT_EQ(seen_b, (std::vector<int>{2, 20}));
  // A service bus ignores sign_for_run: it signs for its own run only.
  a.sign_for_run(*run_b.run());
  publish(a, Channel<hbirl::episode_marker_t>{"ANSWER"}, marker(11), ca);
  b.handle(0);
  EXPECT_EQ(seen_b, (std::vector<int>{2, 20}));
}

// A worker of every run of a key sends nothing before it has heard from a run (a heartbeat
// signed for no run would be counted as another run's by every optimiser); then it signs
// for the first run it heard until a request says otherwise.
TEST(KeyedBus, AWorkerOfEveryRunSignsForNoneUntilItHearsOne) {
  auto hub = std::make_shared<MemoryHub>();
  const RunKey shared = RunKey::generate();
  const RunKey run_a = shared.for_new_run();
  Counters cw = quiet("worker"), ca = quiet("a");
  KeyedBus worker(std::make_unique<MemoryBus>(hub), shared, cw, KeyUse::kWorker);
  KeyedBus a(std::make_unique<MemoryBus>(hub), run_a, ca);
  std::vector<int> seen;
  subscribe(a, Channel<hbirl::episode_marker_t>{"STATUS"}, ca,
            [&](const hbirl::episode_marker_t& m, const Message&) { seen.push_back(m.episode); });
  subscribe(worker, channels::kEpisode, cw, [](const hbirl::episode_marker_t&, const Message&) {});
  publish(worker, Channel<hbirl::episode_marker_t>{"STATUS"}, marker(1), cw);  // before any run: not sent
  a.handle(0);
  EXPECT_TRUE(seen.empty());
  EXPECT_EQ(ca.bad_messages, 0);
  publish(a, channels::kEpisode, marker(7), ca);
  worker.handle(0);
  publish(worker, Channel<hbirl::episode_marker_t>{"STATUS"}, marker(2), cw);
  a.handle(0);
  EXPECT_EQ(seen, (std::vector<int>{2}));
  EXPECT_EQ(ca.bad_messages, 0);
}

// A service's key file must name its run; a worker's and a reader's need not.
TEST(KeyedBus, AServiceNeedsAKeyFileThatNamesItsRun) {
  const auto shared = scratch("shared.key"), run = scratch("run.key");
  const RunKey key = RunKey::generate();
  key.write(shared.string());
  key.for_new_run().write(run.string());
  Counters c = quiet("service");
  try {
    with_key(std::make_unique<MemoryBus>(std::make_shared<MemoryHub>()), shared.string(), c, KeyUse::kService);
    ADD_FAILURE() << "a service took a key file for many runs";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "--key");
    EXPECT_NE(std::string(e.what()).find("names no run"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(
      with_key(std::make_unique<MemoryBus>(std::make_shared<MemoryHub>()), run.string(), c, KeyUse::kService));
  EXPECT_NO_THROW(
      with_key(std::make_unique<MemoryBus>(std::make_shared<MemoryHub>()), shared.string(), c, KeyUse::kWorker));
  EXPECT_NO_THROW(
      with_key(std::make_unique<MemoryBus>(std::make_shared<MemoryHub>()), shared.string(), c, KeyUse::kReader));
  std::filesystem::remove_all(shared.parent_path());
}

// A key file that is a FIFO is refused at once (opening it used to wait for a writer).
TEST(RunKey, AFifoIsRefusedWithoutWaiting) {
  const auto fifo = scratch("fifo.key");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    RunKey::read(fifo.string());
    ADD_FAILURE() << "read a FIFO as a key";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(fifo.parent_path());
}

// A recording's key is checked before the recording is read: a signed recording without a
// key, one read with another key, and an unsigned one read with a key are each refused in
// one line naming --key; with its run's key file it passes.
TEST(KeyedBus, ARecordingsKeyIsCheckedBeforeItIsRead) {
  const auto log_path = scratch("run.lcmlog"), run_key = scratch("run.key"), other_key = scratch("other.key"),
             plain = scratch("plain.lcmlog");
  const RunKey key = RunKey::generate().for_new_run();
  key.write(run_key.string());
  RunKey::generate().write(other_key.string());
  const auto record = [](const std::filesystem::path& path, const RunKey* signing) {
    const auto source = scratch("source.lcmlog");  // an empty recording to write beside
    { std::ofstream create(source); }
    Counters c = quiet("recorder");
    std::unique_ptr<Bus> out = std::make_unique<LogBus>(source.string(), path.string());
    if (signing) out = std::make_unique<KeyedBus>(std::move(out), *signing, c);
    for (int e = 0; e < 5; ++e) publish(*out, channels::kEpisode, marker(e), c);
  };
  record(log_path, &key);
  record(plain, nullptr);
  const auto refused = [](const std::string& log, const std::string& key_file, const std::string& says) {
    try {
      check_recording_key(log, key_file);
      ADD_FAILURE() << log << " with key '" << key_file << "' was not refused";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "--key");
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  // A thousand and more messages ending in a made-up trailer, recorded first (anyone can
  // send them): the key is still found to be the right one, further on.
  const auto forged_first = scratch("forged-first.lcmlog");
  {
    std::ofstream out(forged_first, std::ios::binary);
    const std::string fake(kTrailerBytes, '\0');
    for (int k = 0; k < 1500; ++k) {
      std::string data = "junk" + fake;
      std::copy(kTrailerMarker, kTrailerMarker + 4, data.end() - 4);
      std::string event = {'\xED', '\xA1', '\xDA', '\x01'};
      event += std::string(16, '\0');
      const auto be32 = [&event](std::uint32_t v) {
        for (int s = 24; s >= 0; s -= 8) event.push_back(static_cast<char>((v >> s) & 0xFF));
      };
      be32(7);
      be32(static_cast<std::uint32_t>(data.size()));
      out << event << "EPISODE" << data;
    }
    std::ifstream in(log_path, std::ios::binary);
    out << in.rdbuf();
  }
  EXPECT_NO_THROW(check_recording_key(forged_first.string(), run_key.string()));
  refused(log_path.string(), "", "give it");
  refused(log_path.string(), other_key.string(), "the wrong key");
  refused(plain.string(), run_key.string(), "not signed");
  EXPECT_NO_THROW(check_recording_key(log_path.string(), run_key.string()));
  EXPECT_NO_THROW(check_recording_key(plain.string(), ""));
  std::filesystem::remove_all(log_path.parent_path());
}

}  // namespace
}  // namespace hbirl::services
