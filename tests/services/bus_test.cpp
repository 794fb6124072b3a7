#include "services/bus.hpp"

#include <gtest/gtest.h>

#include <malloc.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <thread>

#include "hbirl/observations_t.hpp"
#include "hbirl/service_status_t.hpp"
#include "learner/input_error.hpp"
#include "services/lcm_bus.hpp"
#include "services/log_bus.hpp"
#include "services/memory_bus.hpp"
#include "services/typed.hpp"
#include "service_threads.hpp"
#include "sample_messages.hpp"

namespace hbirl::services {
namespace {

hbirl::observations_t observations(std::int64_t seq, int n) {
  hbirl::observations_t m{};
  m.utime = 1000 * seq;
  m.seq = seq;
  m.episode = 2;
  m.step = 3;
  m.frame = 4;
  m.num_symbols = 22;
  m.num_sources = 2;
  m.n = n;
  for (int i = 0; i < n; ++i) {
    m.symbol.push_back(static_cast<int16_t>(i));
    m.eta.push_back({0.75, 0.25});
  }
  return m;
}

Counters quiet_counters() { return testing::quiet("test"); }

long max_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

// A 52-byte message whose length field says 100 million observations: lcm-gen's decoder
// would allocate and zero them (200 MB of symbols, 2.4 GB of eta rows) before noticing
// the bytes are not there; the generated headers are bounded (lcmtypes/bound_arrays.cmake)
// and refuse it at once.
TEST(LcmTypes, HostileLengthFieldsAreRefusedWithoutAllocating) {
  hbirl::observations_t m = observations(1, 0);
  std::vector<std::uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  ASSERT_EQ(bytes.size(), 52u);  // hash, 2 x int64, 6 x int32 (n at 44), num_context
  const std::uint32_t n = 100000000;
  for (int i = 0; i < 4; ++i) bytes[44 + static_cast<size_t>(i)] = static_cast<std::uint8_t>(n >> (24 - 8 * i));
  const long before = max_rss_kb();
  hbirl::observations_t hostile;
  EXPECT_LT(hostile.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  EXPECT_LT(max_rss_kb() - before, 50 * 1024) << "kB more at the peak";
  for (int i = 0; i < 4; ++i) bytes[44 + static_cast<size_t>(i)] = 0xff;  // n = -1
  EXPECT_LT(hostile.decode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  // The real message still decodes.
  const hbirl::observations_t good = observations(2, 3);
  std::vector<std::uint8_t> ok(static_cast<size_t>(good.getEncodedSize()));
  good.encode(ok.data(), 0, static_cast<int>(ok.size()));
  hbirl::observations_t back;
  EXPECT_EQ(back.decode(ok.data(), 0, static_cast<int>(ok.size())), static_cast<int>(ok.size()));
  EXPECT_EQ(back.eta, good.eta);
}

// Every resize in every generated decoder got its bound (a new lcm-gen might word them
// differently, and then bound_arrays.cmake would silently miss them).
TEST(LcmTypes, EveryGeneratedArrayIsBounded) {
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(HBIRL_LCMTYPES_DIR)) {
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    const std::string s = text.str();
    const auto count = [&s](const std::string& what) {
      long c = 0;
      for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++c;
      return c;
    };
    EXPECT_EQ(count(".resize(") + count(".assign("), count("// hbirl: bound_arrays.cmake")) << entry.path();
    EXPECT_EQ(count(".assign("), count("// hbirl: bound_arrays.cmake (strings)")) << entry.path();
    ++files;
  }
  EXPECT_GE(files, 12);
}

// Bytes malloc has handed out and not yet taken back (glibc's arenas and mmaps; under
// AddressSanitizer its own allocator serves them and this reads 0 -- there, an unbounded
// length is caught by the sanitizer refusing the multi-gigabyte request instead).
static long long allocated_now() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<long long>(m.uordblks + m.hblkhd);
}

// Every generated type, every position of a valid message overwritten with every hostile
// length (INT_MIN -- which crashed string decoders before bound_arrays.cmake bounded them
// too --, -1, 0, 2^20, 2^28, INT_MAX): the decode fails or stops within the bytes, and
// what it allocates stays a small multiple of the bytes received. docs/RELIABILITY.md.
TEST(LcmTypes, HostileLengthFieldsNeitherCrashNorBalloon) {
  const auto samples = hbirl::test::sample_messages();
  std::set<std::string> covered;
  long long decodes = 0;
  for (const auto& sample : samples) {
    covered.insert(sample.type.substr(sample.type.find('.') + 1));
    ASSERT_EQ(sample.decode(sample.bytes.data(), static_cast<int>(sample.bytes.size()), {}),
              static_cast<int>(sample.bytes.size()))
        << sample.type;
    for (size_t at = 8; at + 4 <= sample.bytes.size(); ++at) {  // after the 8-byte fingerprint
      for (const std::int32_t length : hbirl::test::hostile_lengths()) {
        const auto bytes = hbirl::test::with_int32_at(sample.bytes, at, length);
        const long long before = allocated_now();
        long long during = 0;
        const int used = sample.decode(bytes.data(), static_cast<int>(bytes.size()), [&] { during = allocated_now(); });
        EXPECT_LE(used, static_cast<int>(bytes.size())) << sample.type << " at byte " << at << " = " << length;
        EXPECT_LE(during - before, 64LL * static_cast<long long>(bytes.size()) + 4096)
            << sample.type << " at byte " << at << " = " << length << ": bytes allocated by one decode";
        ++decodes;
      }
    }
  }
  // A type without a sample would go untested: every generated header has one.
  for (const auto& entry : std::filesystem::directory_iterator(HBIRL_LCMTYPES_DIR)) {
    EXPECT_TRUE(covered.count(entry.path().stem().string())) << entry.path().stem() << " has no sample message";
  }
  EXPECT_GT(decodes, 5000);
}

// Typed messages round-trip between endpoints of one hub, in order, on the channels a
// subscription's regular expression matches (the whole name).
TEST(MemoryBus, DeliversTypedMessagesInOrder) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus a(hub), b(hub);
  Counters out = quiet_counters(), in = quiet_counters();
  std::vector<std::int64_t> seen;
  subscribe(b, Channel<hbirl::observations_t>{"OBS.*"}, in, [&](const hbirl::observations_t& m, const Message& raw) {
    EXPECT_EQ(raw.channel.substr(0, 3), "OBS");
    EXPECT_EQ(m.eta.size(), static_cast<size_t>(m.n));
    seen.push_back(m.seq);
  });
  for (int s = 1; s <= 5; ++s)
    EXPECT_TRUE(
        publish(a, s % 2 ? channels::kObservations : Channel<hbirl::observations_t>{"OBS_B"}, observations(s, s), out));
  EXPECT_TRUE(
      publish(a, Channel<hbirl::observations_t>{"XOBSERVATIONS"}, observations(9, 1), out));  // not a whole-name match
  EXPECT_EQ(b.handle(0), 5);
  EXPECT_EQ(seen, (std::vector<std::int64_t>{1, 2, 3, 4, 5}));
  EXPECT_EQ(in.messages_in, 5);
  EXPECT_EQ(out.messages_out, 6);
  EXPECT_EQ(b.handle(0), 0);  // nothing left: times out at once
}

// Garbage, another type, a truncated message and a message its handler rejects are each
// counted once and dropped; the good messages around them still arrive.
// A channel carries its type: publishing another type on it does not compile.
template <class C, class M>
concept Publishable = requires(Bus& bus, const C& channel, const M& message, Counters& counters) {
  publish(bus, channel, message, counters);
};
static_assert(Publishable<Channel<hbirl::observations_t>, hbirl::observations_t>);
static_assert(!Publishable<Channel<hbirl::observations_t>, hbirl::service_status_t>);
static_assert(!Publishable<decltype(channels::kStatus), hbirl::reward_t>);
static_assert(!Publishable<std::string, hbirl::reward_t>);  // no untyped channel names either

// Every reader validates a message by its type before its handler sees it (messages.hpp):
// an eta that is not a distribution never reaches the handler, whichever reader subscribes.
TEST(TypedSubscribe, ValidatesByTypeBeforeTheHandler) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub);
  Counters c = quiet_counters(), out = quiet_counters();
  int handled = 0;
  subscribe(bus, channels::kObservations, c, [&](const hbirl::observations_t&, const Message&) { ++handled; });
  hbirl::observations_t bad = observations(1, 2);
  bad.eta[1] = {2.0, 0.0};
  publish(bus, channels::kObservations, bad, out);
  bad = observations(2, 2);
  bad.symbol[0] = 22;  // outside the 22-symbol alphabet
  publish(bus, channels::kObservations, bad, out);
  publish(bus, channels::kObservations, observations(3, 2), out);
  bus.handle(0);
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(c.bad_messages, 2);
  EXPECT_NE(c.last_problem.find("observations.symbol[0]"), std::string::npos) << c.last_problem;
}

TEST(MemoryBus, BadMessagesAreCountedNotFatal) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub);
  Counters c = quiet_counters();
  int good = 0;
  subscribe(bus, channels::kObservations, c, [&](const hbirl::observations_t& m, const Message&) {
    if (m.num_sources < 1) throw InputError("num_sources", "must be at least 1");
    ++good;
  });
  Counters out = quiet_counters();
  publish(bus, channels::kObservations, observations(1, 3), out);
  const char garbage[] = "definitely not an LCM message";
  bus.publish("OBSERVATIONS", garbage, sizeof garbage);
  hbirl::service_status_t status{};  // a valid message of the wrong type
  status.service = "sampler";
  publish(bus, Channel<hbirl::service_status_t>{"OBSERVATIONS"}, status, out);  // another type on the channel
  const std::vector<std::uint8_t> whole = encode(observations(2, 3));
  bus.publish("OBSERVATIONS", whole.data(), static_cast<int>(whole.size()) - 5);  // truncated
  hbirl::observations_t bad = observations(3, 1);
  bad.num_sources = 0;
  bad.eta = {{}};
  publish(bus, channels::kObservations, bad, out);
  bus.publish("OBSERVATIONS", nullptr, 0);  // empty
  publish(bus, channels::kObservations, observations(4, 2), out);
  EXPECT_EQ(bus.handle(0), 7);
  EXPECT_EQ(good, 2);
  EXPECT_EQ(c.messages_in, 2);
  EXPECT_EQ(c.bad_messages, 5);
  EXPECT_NE(c.last_problem.find("OBSERVATIONS"), std::string::npos);
}

// A watched subscription (a sensor's data) says once, after kAllRefusedAfter refusals with
// none accepted, that it refused them all and why the first was refused; a counted one
// never does, and neither does a watched one that accepted a message first.
TEST(TypedSubscribe, AWatchedChannelSaysWhenItRefusedEveryMessage) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub);
  Counters watched = quiet_counters(), counted = quiet_counters(), after_one = quiet_counters(), out = quiet_counters();
  const auto refuse_all = [](const hbirl::observations_t& m, const Message&) {
    if (m.seq > 1) throw InputError("observations.domain", "'sensed' is not the domain learned on ('vacuum')");
  };
  subscribe(bus, channels::kObservations, watched, refuse_all, 0, Refusals::kWatched);
  subscribe(bus, channels::kObservations, counted, refuse_all);
  for (int s = 2; s <= kAllRefusedAfter; ++s) publish(bus, channels::kObservations, observations(s, 1), out);
  bus.handle(0);
  EXPECT_EQ(watched.all_refused_report, "");  // not yet: one short
  for (int s = 1; s <= 11; ++s) publish(bus, channels::kObservations, observations(100 + s, 1), out);
  bus.handle(0);
  EXPECT_EQ(watched.all_refused_report, std::string(kAllRefusedMarker) +
                                            "OBSERVATIONS: the first 10, none accepted; the first: OBSERVATIONS: " +
                                            "observations.domain: 'sensed' is not the domain learned on ('vacuum')");
  EXPECT_EQ(watched.bad_messages, 20);
  EXPECT_EQ(counted.bad_messages, 20);
  EXPECT_EQ(counted.all_refused_report, "");

  // Garbage counts toward it as well (decoding is the first refusal); a message signed for
  // another run (a shared bus) does not: it is not this sensor's.
  MemoryBus garbage_bus(std::make_shared<MemoryHub>());
  Counters garbled = quiet_counters(), signed_elsewhere = quiet_counters();
  subscribe(garbage_bus, channels::kObservations, garbled, refuse_all, 0, Refusals::kWatched);
  const char garbage[] = "definitely not an LCM message";
  for (int k = 0; k < kAllRefusedAfter; ++k) garbage_bus.publish("OBSERVATIONS", garbage, sizeof garbage);
  garbage_bus.handle(0);
  EXPECT_NE(garbled.all_refused_report.find("OBSERVATIONS: the first 10, none accepted"), std::string::npos)
      << garbled.all_refused_report;
  MemoryBus signed_bus(std::make_shared<MemoryHub>());
  subscribe(signed_bus, channels::kObservations, signed_elsewhere, refuse_all, 0, Refusals::kWatched);
  std::vector<std::uint8_t> other_run = encode(observations(5, 1));
  other_run.resize(other_run.size() + kTagBytes + kRunBytes, 0x5a);  // a tag and a run identity, then the marker
  for (const char c : std::string("hbk2")) other_run.push_back(static_cast<std::uint8_t>(c));
  for (int k = 0; k < 2 * kAllRefusedAfter; ++k)
    signed_bus.publish("OBSERVATIONS", other_run.data(), static_cast<int>(other_run.size()));
  signed_bus.handle(0);
  EXPECT_EQ(signed_elsewhere.signed_unread, 2 * kAllRefusedAfter);
  EXPECT_EQ(signed_elsewhere.all_refused_report, "");

  // A subscription that accepted one message first never says it.
  MemoryBus other(std::make_shared<MemoryHub>());
  subscribe(other, channels::kObservations, after_one, refuse_all, 0, Refusals::kWatched);
  publish(other, channels::kObservations, observations(1, 1), out);  // seq 1: accepted
  for (int s = 2; s <= 20; ++s) publish(other, channels::kObservations, observations(s, 1), out);
  other.handle(0);
  EXPECT_EQ(after_one.messages_in, 1);
  EXPECT_EQ(after_one.all_refused_report, "");
}

// A full subscription queue drops its oldest message (LCM's rule), and the hub counts it.
TEST(MemoryBus, QueueCapacityDropsTheOldest) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub);
  Counters c = quiet_counters(), out = quiet_counters();
  std::vector<std::int64_t> seen;
  subscribe(
      bus, channels::kObservations, c, [&](const hbirl::observations_t& m, const Message&) { seen.push_back(m.seq); },
      3);
  for (int s = 1; s <= 5; ++s) publish(bus, channels::kObservations, observations(s, 1), out);
  EXPECT_EQ(bus.handle(0), 3);
  EXPECT_EQ(seen, (std::vector<std::int64_t>{3, 4, 5}));
  EXPECT_EQ(hub->dropped(), 2);
}

// handle() waits for a message from another thread; a disconnected endpoint ends.
TEST(MemoryBus, WaitsAcrossThreadsAndEnds) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus a(hub), b(hub);
  Counters c = quiet_counters(), out = quiet_counters();
  int got = 0;
  subscribe(b, channels::kObservations, c, [&](const hbirl::observations_t&, const Message&) { ++got; });
  std::thread sender([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    publish(a, channels::kObservations, observations(1, 1), out);
  });
  int handled = 0;
  for (int i = 0; i < 200 && handled == 0; ++i) handled = b.handle(50);
  sender.join();
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(got, 1);
  b.disconnect();
  EXPECT_EQ(b.handle(10), -1);
  publish(a, channels::kObservations, observations(2, 1), out);  // no one to deliver to: fine
}

TEST(SequenceTracker, CountsSkippedNumbers) {
  SequenceTracker t;
  EXPECT_EQ(t.see(5), 0);
  EXPECT_EQ(t.see(6), 0);
  EXPECT_EQ(t.see(9), 2);
  EXPECT_EQ(t.see(9), 0);  // a duplicate is not a gap
  EXPECT_EQ(t.see(1), 0);  // the publisher restarted
  EXPECT_EQ(t.see(2), 0);
}

// LCM's own in-process provider exercises LcmBus without any network.
TEST(LcmBus, RoundTripOverMemq) {
  LcmBus bus("memq://");
  Counters c = quiet_counters(), out = quiet_counters();
  std::vector<std::int64_t> seen;
  subscribe(bus, channels::kObservations, c,
            [&](const hbirl::observations_t& m, const Message&) { seen.push_back(m.seq); });
  publish(bus, channels::kObservations, observations(7, 2), out);
  const char garbage[] = "noise";
  bus.publish("OBSERVATIONS", garbage, sizeof garbage);
  publish(bus, channels::kObservations, observations(8, 2), out);
  int handled = 0;
  for (int i = 0; i < 10 && handled < 3; ++i) handled += std::max(0, bus.handle(100));
  EXPECT_EQ(seen, (std::vector<std::int64_t>{7, 8}));
  EXPECT_EQ(c.bad_messages, 1);
}

// Subscriptions end with their owner (Subscriptions): after it, no handler runs, on
// every kind of bus; the other subscriptions carry on.
TEST(Bus, SubscriptionsEndWithTheirOwner) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("hbirl_unsub_" + std::to_string(::getpid()) + ".lcmlog");
  {
    lcm::LogFile log(path.string(), "w");
    for (int seq = 1; seq <= 2; ++seq) {
      const auto bytes = encode(observations(seq, 1));
      lcm::LogEvent e;
      e.timestamp = seq;
      e.channel = "OBSERVATIONS";
      e.datalen = static_cast<std::int32_t>(bytes.size());
      e.data = const_cast<std::uint8_t*>(bytes.data());
      log.writeEvent(&e);
    }
  }
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus memory(hub), sender(hub);
  LcmBus lcm("memq://");
  LogBus log(path.string());
  for (Bus* bus : std::vector<Bus*>{&memory, &lcm, &log}) {
    Counters c = quiet_counters(), out = quiet_counters();
    int kept = 0, ended = 0;
    subscribe(*bus, channels::kObservations, c, [&](const hbirl::observations_t&, const Message&) { ++kept; });
    {
      Subscriptions owner;
      owner.add(*bus, subscribe(*bus, Channel<hbirl::observations_t>{"OBS.*"}, c,
                                [&](const hbirl::observations_t&, const Message&) { ++ended; }));
      Bus& to = bus == &memory ? sender : *bus;
      publish(to, channels::kObservations, observations(1, 1), out);
      for (int i = 0; i < 5 && kept < 1; ++i) bus->handle(50);
    }
    Bus& to = bus == &memory ? sender : *bus;
    publish(to, channels::kObservations, observations(2, 1), out);
    for (int i = 0; i < 5 && kept < 2; ++i) bus->handle(50);
    EXPECT_EQ(kept, 2) << bus->url();
    EXPECT_EQ(ended, 1) << bus->url();
  }
  std::filesystem::remove(path);
}

TEST(LcmBus, BadUrlIsAClearError) {
  try {
    LcmBus bus("nosuchprovider://x");
    FAIL() << "opened a bus on a bad URL";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bus"), std::string::npos) << e.what();
  }
}

// A recorded log replays event by event, in order, skipping channels nobody wants, and
// ends; what a replaying service publishes can go to a log of its own.
// Following a log as it is written (the dashboard on a recording): at its end handle()
// waits and returns 0, an event written in two parts is read once it is whole, and
// nothing is skipped or read twice.
TEST(LogBus, FollowsALogAsItGrows) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hbirl_follow_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string one = (dir / "one.lcmlog").string(), path = (dir / "growing.lcmlog").string();
  const auto event_bytes = [&](std::int64_t seq) {  // one event as lcm-logger writes it
    {
      lcm::LogFile log(one, "w");
      const std::vector<std::uint8_t> bytes = encode(observations(seq, 2));
      lcm::LogEvent e;
      e.timestamp = seq;
      e.channel = "OBSERVATIONS";
      e.datalen = static_cast<int32_t>(bytes.size());
      e.data = const_cast<std::uint8_t*>(bytes.data());
      log.writeEvent(&e);
    }
    std::ifstream in(one, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  std::ofstream writer(path, std::ios::binary);
  writer << event_bytes(1) << std::flush;
  LogBus bus(path);
  bus.follow(true);
  Counters c = quiet_counters();
  std::vector<std::int64_t> seen;
  subscribe(bus, channels::kObservations, c,
            [&](const hbirl::observations_t& m, const Message&) { seen.push_back(m.seq); });
  EXPECT_EQ(bus.handle(0), 1);
  EXPECT_EQ(bus.handle(30), 0);  // the end, for now
  const std::string second = event_bytes(2);
  writer << second.substr(0, 30) << std::flush;  // half written
  EXPECT_EQ(bus.handle(30), 0);
  writer << second.substr(30) << event_bytes(3) << std::flush;
  EXPECT_EQ(bus.handle(30), 1);
  EXPECT_EQ(bus.handle(30), 1);
  EXPECT_EQ(bus.handle(0), 0);
  EXPECT_EQ(seen, (std::vector<std::int64_t>{1, 2, 3}));
  EXPECT_EQ(c.bad_messages, 0);
  std::filesystem::remove_all(dir);
}

// lcm-logger's event as bytes, its header stating what the caller says (a hostile file).
std::string raw_event(const std::string& channel, const std::string& data, std::int64_t channel_len,
                      std::int64_t data_len, std::uint32_t sync = 0xEDA1DA01) {
  std::string out;
  const auto be = [&out](std::uint64_t v, int bytes) {
    for (int k = bytes - 1; k >= 0; --k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFF));
  };
  be(sync, 4);
  be(7, 8);     // event number
  be(1000, 8);  // time
  be(static_cast<std::uint32_t>(channel_len), 4);
  be(static_cast<std::uint32_t>(data_len), 4);
  return out + channel + data;
}

std::string good_event(std::int64_t seq) {
  const std::vector<std::uint8_t> bytes = encode(observations(seq, 2));
  return raw_event("OBSERVATIONS", std::string(bytes.begin(), bytes.end()), 12,
                   static_cast<std::int64_t>(bytes.size()));
}

// A recording is hostile input too. After a good event, an event whose header states a data
// length LCM's reader would allocate and write through (2^31 - 1: SIGSEGV in every reader,
// from a 54-byte file), or a length below zero, an empty or overlong channel name, or no sync
// word: reading a finished recording stops with one InputError naming --log and the byte;
// following one skips to the next event and reads on. An event the file ends inside is the
// end of the recording.
TEST(LogBus, DamagedRecordingsAreRefusedNamingTheByte) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hbirl_damaged_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "damaged.lcmlog").string();
  const std::string first = good_event(1);
  const std::vector<std::pair<std::string, std::string>> damage = {
      {raw_event("OBSERVATIONS", std::string(14, 'x'), 12, 0x7FFFFFFF), "2147483647 bytes of data"},
      {raw_event("OBSERVATIONS", std::string(10, 'x'), 12, 0x7FFFFFF0), "2147483632 bytes of data"},
      {raw_event("OBSERVATIONS", "", 12, -1), "-1 bytes of data"},
      {raw_event("", "abc", 0, 3), "channel name of 0 bytes"},
      {raw_event(std::string(300, 'C'), "", 300, 0), "channel name of 300 bytes"},
      {raw_event("OBSERVATIONS", "", 0x7FFFFFFF, 0), "channel name of 2147483647 bytes"},
      {raw_event("OBSERVATIONS", "abc", 12, 3, 0x12345678), "no sync word"},
  };
  ASSERT_EQ(damage.front().first.size(), 54u);  // as the report's recording: one event, 54 bytes
  for (const auto& [bad, says] : damage) {
    { std::ofstream(path, std::ios::binary) << first << bad << good_event(2); }
    LogBus bus(path);
    Counters c = quiet_counters();
    std::vector<std::int64_t> seen;
    subscribe(bus, channels::kObservations, c,
              [&](const hbirl::observations_t& m, const Message&) { seen.push_back(m.seq); });
    EXPECT_EQ(bus.handle(0), 1);
    try {
      bus.handle(0);
      ADD_FAILURE() << "read past: " << says;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "--log");
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("byte " + std::to_string(first.size())), std::string::npos) << e.what();
    }
    // Following it (the dashboard): the damage is skipped, the next event read.
    LogBus following(path);
    following.follow(true);
    seen.clear();
    subscribe(following, channels::kObservations, c,
              [&](const hbirl::observations_t& m, const Message&) { seen.push_back(m.seq); });
    for (int k = 0; k < 4; ++k) following.handle(0);
    EXPECT_EQ(seen, (std::vector<std::int64_t>{1, 2})) << says;
    EXPECT_GE(following.damaged(), 1) << says;
  }
  // Cut short in its last event (data stated, not all there): the end, not damage.
  { std::ofstream(path, std::ios::binary) << first << good_event(2).substr(0, 40); }
  LogBus cut(path);
  Counters c = quiet_counters();
  int seen = 0;
  subscribe(cut, channels::kObservations, c, [&](const hbirl::observations_t&, const Message&) { ++seen; });
  EXPECT_EQ(cut.handle(0), 1);
  EXPECT_EQ(cut.handle(0), -1);
  EXPECT_EQ(seen, 1);
  // Not a regular file: refused before it is opened for reading (a FIFO would block).
  const std::string fifo = (dir / "fifo.lcmlog").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(LogBus{fifo}, InputError);
  std::filesystem::remove_all(dir);
}

TEST(LogBus, ReplaysARecordedLogDeterministically) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hbirl_logbus_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "run.lcmlog").string(), out_path = (dir / "out.lcmlog").string();
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    for (int s = 1; s <= 4; ++s) {
      const std::vector<std::uint8_t> bytes = encode(observations(s, s));
      lcm::LogEvent e;
      e.timestamp = 100 * s;
      e.channel = s == 3 ? "CAMERA" : "OBSERVATIONS";
      e.datalen = static_cast<int32_t>(bytes.size());
      e.data = const_cast<std::uint8_t*>(bytes.data());
      ASSERT_EQ(log.writeEvent(&e), 0);
    }
  }
  std::unique_ptr<Bus> bus = open_bus("log:" + path + "?out=" + out_path);
  Counters c = quiet_counters(), out = quiet_counters();
  std::vector<std::int64_t> seen, stamps;
  subscribe(*bus, channels::kObservations, c, [&](const hbirl::observations_t& m, const Message& raw) {
    seen.push_back(m.seq);
    stamps.push_back(raw.recv_utime);
    publish(*bus, Channel<hbirl::observations_t>{"ECHO"}, m, out);
  });
  int handled = 0;
  while (bus->handle(0) > 0) ++handled;
  EXPECT_EQ(handled, 3);
  EXPECT_EQ(seen, (std::vector<std::int64_t>{1, 2, 4}));
  EXPECT_EQ(stamps, (std::vector<std::int64_t>{100, 200, 400}));
  EXPECT_EQ(bus->handle(0), -1);
  bus.reset();
  lcm::LogFile echoed(out_path, "r");
  int n = 0;
  while (const lcm::LogEvent* e = echoed.readNextEvent()) {
    EXPECT_EQ(e->channel, "ECHO");
    ++n;
  }
  EXPECT_EQ(n, 3);
  EXPECT_THROW(open_bus("log:" + (dir / "missing.lcmlog").string()), InputError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hbirl::services
