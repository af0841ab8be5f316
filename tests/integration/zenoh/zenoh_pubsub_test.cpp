// Pub -> sub through the C++ wrappers and the transport seam, in one
// process, over loopback only. Waits are bounded by generous timeouts that
// only guard against hangs; nothing asserts on elapsed time.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <condition_variable>
#include <atomic>
#include <mutex>
#include <random>
#include <thread>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/transport_flags.hpp"
#include "transport/seq_counter.hpp"
#include "transport/zenoh/seq_attachment.hpp"
#include "transport/zenoh/zenoh_endpoint.hpp"

using namespace rvc::transport;
using namespace rvc::cli;  // add_*_options: the transports' flags
using namespace std::chrono_literals;

namespace {

constexpr auto kHangGuard = 60s;

// A free TCP port on 127.0.0.1, drawn at random from 20000-29999: below the
// kernel's ephemeral range, so outgoing connections cannot grab it between
// this check and its use, and parallel test runs rarely pick the same one.
int free_port() {
  static std::mt19937 rng(std::random_device{}());
  std::uniform_int_distribution<int> dist(20000, 29999);
  for (int attempt = 0; attempt < 200; ++attempt) {
    const int port = dist(rng);
    int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<uint16_t>(port));
    const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    ::close(fd);
    if (ok) return port;
  }
  return -1;
}

std::string ep(int port) { return "tcp/127.0.0.1:" + std::to_string(port); }

struct Received {
  std::string payload;
  uint64_t seq;
  bool eos;
};

// Collects frames from a Source; wait_for() blocks until a predicate holds.
struct Collector {
  std::mutex mu;
  std::condition_variable cv;
  std::vector<Received> frames;

  FrameHandler handler() {
    return [this](const Frame& f) {
      std::lock_guard lock(mu);
      frames.push_back({std::string(f.payload), f.seq, f.eos});
      cv.notify_all();
    };
  }
  bool wait_count(size_t n) {
    std::unique_lock lock(mu);
    return cv.wait_for(lock, kHangGuard, [&] { return frames.size() >= n; });
  }
  bool wait_eos() {
    std::unique_lock lock(mu);
    return cv.wait_for(lock, kHangGuard,
                       [&] { return !frames.empty() && frames.back().eos; });
  }
};

ZenohOptions listener_opts(int port) {
  ZenohOptions o;
  o.listen = {ep(port)};
  return o;
}

ZenohOptions connector_opts(int port) {
  ZenohOptions o;
  o.connect = {ep(port)};
  o.listen = {"tcp/127.0.0.1:0"};
  return o;
}

std::string binary_payload(size_t i, size_t len) {
  std::string s(len, '\0');
  for (size_t k = 0; k < len; ++k) s[k] = static_cast<char>((i * 131 + k * 7) & 0xff);
  return s;
}

}  // namespace

TEST(SeqAttachment, RoundTripAndLenientDecode) {
  auto a = encode_seq_attachment(0x0102030405060708ULL, true, 0x1122334455667788ULL);
  ASSERT_EQ(a.size(), 17u);
  EXPECT_EQ(a[9], 0x88);  // publisher id, little-endian
  EXPECT_EQ(a[16], 0x11);
  EXPECT_EQ(decode_seq_attachment(a.data(), a.size()).publisher, 0x1122334455667788ULL);
  EXPECT_EQ(decode_seq_attachment(a.data(), 9).publisher, 0u);  // the 9-byte form: unknown publisher
  EXPECT_EQ(a[0], 0x08);  // little-endian
  EXPECT_EQ(a[7], 0x01);
  EXPECT_EQ(a[8], kSeqFlagEos);
  auto d = decode_seq_attachment(a.data(), a.size());
  EXPECT_EQ(d.seq, 0x0102030405060708ULL);
  EXPECT_TRUE(d.eos);
  // Eight bytes: seq only. Fewer: unknown. Longer: extra bytes ignored.
  d = decode_seq_attachment(a.data(), 8);
  EXPECT_EQ(d.seq, 0x0102030405060708ULL);
  EXPECT_FALSE(d.eos);
  EXPECT_EQ(decode_seq_attachment(a.data(), 7).seq, 0u);
  EXPECT_EQ(decode_seq_attachment(nullptr, 0).seq, 0u);
  uint8_t longer[12] = {5, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff};
  d = decode_seq_attachment(longer, sizeof longer);
  EXPECT_EQ(d.seq, 5u);
  EXPECT_FALSE(d.eos);
}

// Network safety: the embedded defaults must never leave loopback.
TEST(ZenohConfig, DefaultsStayOnLoopback) {
  ZenohOptions peer;
  EXPECT_EQ(zenoh_config_json(peer, "mode"), "\"peer\"");
  EXPECT_EQ(zenoh_config_json(peer, "listen/endpoints"), "[\"tcp/127.0.0.1:0\"]");
  // Multicast scouting on by default so one host needs no flags, but only on lo.
  EXPECT_EQ(zenoh_config_json(peer, "scouting/multicast/enabled"), "true");
  EXPECT_EQ(zenoh_config_json(peer, "scouting/multicast/interface"), "\"lo\"");

  ZenohOptions router;
  router.mode = "router";
  EXPECT_EQ(zenoh_config_json(router, "listen/endpoints"), "[\"tcp/127.0.0.1:7447\"]");
  EXPECT_EQ(zenoh_config_json(router, "scouting/multicast/interface"), "\"lo\"");

  ZenohOptions client;
  client.mode = "client";
  client.connect = {"tcp/127.0.0.1:7447"};
  EXPECT_EQ(zenoh_config_json(client, "listen/endpoints"), "[]");
  EXPECT_EQ(zenoh_config_json(client, "connect/endpoints"), "[\"tcp/127.0.0.1:7447\"]");

  ZenohOptions mc;
  mc.multicast_scouting = 1;
  EXPECT_EQ(zenoh_config_json(mc, "scouting/multicast/enabled"), "true");
  EXPECT_EQ(zenoh_config_json(mc, "scouting/multicast/interface"), "\"lo\"");
}

TEST(ZenohConfig, ConfigFileThenFlags) {
  char path[] = "/tmp/rvc-zenoh-test-XXXXXX.json5";
  int fd = ::mkstemps(path, 6);
  ASSERT_GE(fd, 0);
  const std::string text =
      "{ mode: 'client', connect: { endpoints: ['tcp/127.0.0.1:1'] },"
      "  scouting: { multicast: { enabled: true } } }";
  ASSERT_EQ(::write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  ::close(fd);

  ZenohOptions o;
  o.config_file = path;
  EXPECT_EQ(zenoh_config_json(o, "mode"), "\"client\"");  // file's mode kept
  EXPECT_EQ(zenoh_config_json(o, "connect/endpoints"), "[\"tcp/127.0.0.1:1\"]");
  EXPECT_EQ(zenoh_config_json(o, "scouting/multicast/enabled"), "true");  // the file's setting kept
  o.multicast_scouting = 0;
  EXPECT_EQ(zenoh_config_json(o, "scouting/multicast/enabled"), "false");  // unless a flag says otherwise
  o.mode = "peer";
  o.mode_explicit = true;
  o.connect = {"tcp/127.0.0.1:2"};
  EXPECT_EQ(zenoh_config_json(o, "mode"), "\"peer\"");
  EXPECT_EQ(zenoh_config_json(o, "connect/endpoints"), "[\"tcp/127.0.0.1:2\"]");
  ::unlink(path);
}

TEST(ZenohConfig, ErrorsAreReported) {
  ZenohOptions bad;
  bad.mode = "broker";
  EXPECT_THROW(zenoh_config_json(bad), ZenohError);
  ZenohOptions bad_ep;
  bad_ep.listen = {"not-an-endpoint"};
  EXPECT_THROW(ZenohSession::open(bad_ep), ZenohError);
  auto s = ZenohSession::open(ZenohOptions{});
  try {
    ZenohPublisher p(s, "bad//key");
    FAIL() << "expected ZenohError";
  } catch (const ZenohError& e) {
    EXPECT_NE(std::string(e.what()).find("bad//key"), std::string::npos) << e.what();
  }
}

TEST(ZenohCli, RegistersFlags) {
  CLI::App app;
  ZenohOptions o;
  add_zenoh_options(app, o);
  std::vector<std::string> args = {"--listen",  "tcp/127.0.0.1:7000,tcp/127.0.0.1:7001",
                                   "--connect", "tcp/127.0.0.1:7447",
                                   "--mode",    "client",
                                   "--multicast-scouting", "--express"};
  std::vector<const char*> argv = {"t"};
  for (auto& a : args) argv.push_back(a.c_str());
  app.parse(static_cast<int>(argv.size()), argv.data());
  EXPECT_EQ(o.mode, "client");
  EXPECT_TRUE(o.mode_explicit);
  EXPECT_EQ(o.listen, (std::vector<std::string>{"tcp/127.0.0.1:7000", "tcp/127.0.0.1:7001"}));
  EXPECT_EQ(o.connect, (std::vector<std::string>{"tcp/127.0.0.1:7447"}));
  EXPECT_EQ(o.multicast_scouting, 1);
  EXPECT_TRUE(o.express);

  CLI::App app2;
  ZenohOptions o2;
  add_zenoh_options(app2, o2);
  const char* argv2[] = {"t", "--no-multicast-scouting"};
  app2.parse(2, argv2);
  EXPECT_EQ(o2.multicast_scouting, 0);
  EXPECT_FALSE(o2.mode_explicit);
  EXPECT_EQ(o2.mode, "peer");
  const char* argv3[] = {"t", "--mode", "broker"};
  CLI::App app3;
  ZenohOptions o3;
  add_zenoh_options(app3, o3);
  EXPECT_THROW(app3.parse(3, argv3), CLI::ValidationError);
}

// Two sessions (one listening, one connecting) over tcp/127.0.0.1.
TEST(ZenohTransport, PubSubAcrossSessions) {
  const int port = free_port();
  ASSERT_GT(port, 0);
  auto sub_session = ZenohSession::open(listener_opts(port));
  auto pub_session = ZenohSession::open(connector_opts(port));
  EXPECT_NE(sub_session->zid(), pub_session->zid());

  Collector got;
  ZenohSource source(sub_session, "rvc/test/across");
  source.start(got.handler());
  ZenohSink sink(pub_session, "rvc/test/across");
  ASSERT_TRUE(sink.wait_matched(1, kHangGuard));
  EXPECT_TRUE(sink.publisher().matching());

  constexpr size_t kN = 500;
  std::vector<std::string> sent;
  for (size_t i = 1; i <= kN; ++i) {
    sent.push_back(binary_payload(i, 1 + i % 300));  // includes NUL bytes
    sink.put(sent.back(), i);
  }
  sink.put_eos(kN);
  ASSERT_TRUE(got.wait_eos());

  std::lock_guard lock(got.mu);
  ASSERT_EQ(got.frames.size(), kN + 1);
  for (size_t i = 0; i < kN; ++i) {
    EXPECT_EQ(got.frames[i].seq, i + 1);
    EXPECT_FALSE(got.frames[i].eos);
    EXPECT_EQ(got.frames[i].payload, sent[i]) << "frame " << i;
  }
  EXPECT_TRUE(got.frames.back().eos);
  EXPECT_EQ(got.frames.back().seq, kN);
  EXPECT_TRUE(got.frames.back().payload.empty());
}

// Congestion control Block: a subscriber slower than its publisher pushes
// back on it instead of losing samples.
TEST(ZenohTransport, SlowSubscriberLosesNothing) {
  const int port = free_port();
  auto a = ZenohSession::open(listener_opts(port));
  auto b = ZenohSession::open(connector_opts(port));
  std::mutex mu;
  std::condition_variable cv;
  SeqCounters counters;
  bool eos = false;
  ZenohSource source(a, "rvc/test/slow");
  source.start([&](const Frame& f) {
    if (!f.eos) std::this_thread::sleep_for(20us);  // a slow monitor
    std::lock_guard lock(mu);
    if (f.eos) {
      counters.on_eos(f.seq);
      eos = true;
      cv.notify_all();
    } else {
      counters.on_seq(f.seq);
    }
  });
  ZenohSink sink(b, "rvc/test/slow");
  ASSERT_TRUE(sink.wait_matched(1, kHangGuard));
  constexpr uint64_t kN = 20000;
  const std::string payload(2048, 'p');  // ~40 MB: well past every queue
  for (uint64_t i = 1; i <= kN; ++i) sink.put(payload, i);
  sink.put_eos(kN);
  std::unique_lock lock(mu);
  ASSERT_TRUE(cv.wait_for(lock, kHangGuard, [&] { return eos; }));
  EXPECT_EQ(counters.received, kN);
  EXPECT_EQ(counters.gaps, 0u);
  EXPECT_EQ(counters.duplicates, 0u);
  EXPECT_EQ(counters.last_seq, kN);
}

// flush() is a barrier: when it returns, a slow subscriber in another session
// has taken every sample put before it, so the publisher may close its session
// at once. (Closing right after the last put lost samples still queued for a
// slow subscriber: Zenoh drains a closing link only with a timeout.)
TEST(ZenohTransport, FlushWaitsUntilEverySampleIsTaken) {
  const int port = free_port();
  auto a = ZenohSession::open(listener_opts(port));
  std::atomic<uint64_t> taken{0};
  ZenohSource source(a, "rvc/test/flush");
  source.start([&](const Frame& f) {
    if (f.eos) return;
    std::this_thread::sleep_for(200us);  // ~0.6 s for all of them
    taken.fetch_add(1);
  });
  constexpr uint64_t kN = 3000;
  {
    auto b = ZenohSession::open(connector_opts(port));
    ZenohSink sink(b, "rvc/test/flush");
    ASSERT_TRUE(sink.wait_matched(1, kHangGuard));
    ASSERT_TRUE(sink.publisher().wait_matched(1, kHangGuard));
    const std::string payload(4096, 'f');
    for (uint64_t i = 1; i <= kN; ++i) sink.put(payload, i);
    EXPECT_LT(taken.load(), kN) << "the subscriber was not slower than the publisher: the test proves nothing";
    auto confirmed = sink.publisher().flush(kHangGuard);
    ASSERT_TRUE(confirmed.has_value());
    EXPECT_EQ(*confirmed, 1u);
    EXPECT_EQ(taken.load(), kN);  // before the session closes
  }
  source.stop();
  EXPECT_EQ(taken.load(), kN);
}

// A flush with no rvc subscriber (nobody to answer) returns at once.
TEST(ZenohTransport, FlushWithoutRvcSubscribersReturns) {
  const int port = free_port();
  auto a = ZenohSession::open(listener_opts(port));
  auto b = ZenohSession::open(connector_opts(port));
  ZenohSubscriber plain(a, "rvc/test/flush_plain", [](const ZenohSample&) {}, /*announce=*/false);
  ZenohSink sink(b, "rvc/test/flush_plain");
  ASSERT_TRUE(sink.wait_matched(1, kHangGuard));
  sink.put("{}", 1);
  auto confirmed = sink.publisher().flush(kHangGuard);
  ASSERT_TRUE(confirmed.has_value());
  EXPECT_EQ(*confirmed, 0u);
}

// Samples from two remote sessions arrive on two links, hence possibly on
// two Zenoh threads; ZenohSource still never runs its handler twice at once.
TEST(ZenohTransport, HandlerCallsNeverOverlap) {
  const int port = free_port();
  auto a = ZenohSession::open(listener_opts(port));
  auto b = ZenohSession::open(connector_opts(port));
  auto c = ZenohSession::open(connector_opts(port));
  std::atomic<int> inflight{0}, overlaps{0}, total{0};
  ZenohSource source(a, "rvc/test/overlap/*");
  source.start([&](const Frame&) {
    if (inflight.fetch_add(1) != 0) ++overlaps;
    std::this_thread::sleep_for(50us);
    inflight.fetch_sub(1);
    ++total;
  });
  ZenohSink s1(b, "rvc/test/overlap/b"), s2(c, "rvc/test/overlap/c");
  ASSERT_TRUE(s1.wait_matched(1, kHangGuard));
  ASSERT_TRUE(s2.wait_matched(1, kHangGuard));
  constexpr int kN = 2000;
  std::thread t1([&] { for (int i = 1; i <= kN; ++i) s1.put("b", i); });
  std::thread t2([&] { for (int i = 1; i <= kN; ++i) s2.put("c", i); });
  t1.join();
  t2.join();
  for (int i = 0; i < 6000 && total.load() < 2 * kN; ++i) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(total.load(), 2 * kN);
  EXPECT_EQ(overlaps.load(), 0);
}

// Large payloads arrive fragmented and take the copying path.
TEST(ZenohTransport, LargePayloadsIntact) {
  const int port = free_port();
  auto a = ZenohSession::open(listener_opts(port));
  auto b = ZenohSession::open(connector_opts(port));
  Collector got;
  ZenohSource source(a, "rvc/test/large");
  source.start(got.handler());
  ZenohSink sink(b, "rvc/test/large");
  ASSERT_TRUE(sink.wait_matched(1, kHangGuard));
  const std::string big1 = binary_payload(1, 3 * 1024 * 1024 + 17);
  const std::string big2 = binary_payload(2, 200 * 1024);
  sink.put(big1, 1);
  sink.put(big2, 2);
  ASSERT_TRUE(got.wait_count(2));
  std::lock_guard lock(got.mu);
  EXPECT_EQ(got.frames[0].payload.size(), big1.size());
  EXPECT_TRUE(got.frames[0].payload == big1);
  EXPECT_TRUE(got.frames[1].payload == big2);
  EXPECT_EQ(got.frames[1].seq, 2u);
}

// A publisher that sends no attachment (e.g. plain Python) yields seq 0.
TEST(ZenohTransport, NoAttachmentMeansSeqZero) {
  auto s = ZenohSession::open(ZenohOptions{});  // local delivery in one session
  Collector got;
  ZenohSource source(s, "rvc/test/plain/**");
  source.start(got.handler());
  ZenohPublisher raw(s, "rvc/test/plain/x");
  ASSERT_TRUE(raw.wait_matched(1, kHangGuard));
  raw.put("{\"a\":1}");
  raw.put("short", std::string_view("\x07\x00\x00", 3));  // too short: unknown
  raw.put("", std::string_view());                        // empty attachment
  ASSERT_TRUE(got.wait_count(3));
  std::lock_guard lock(got.mu);
  EXPECT_EQ(got.frames[0].payload, "{\"a\":1}");
  for (auto& f : got.frames) {
    EXPECT_EQ(f.seq, 0u);
    EXPECT_FALSE(f.eos);
  }
}

// Matching counts announced subscribers; plain ones only flip the boolean.
TEST(ZenohTransport, MatchingCountsAnnouncedSubscribers) {
  const int port = free_port();
  auto a = ZenohSession::open(listener_opts(port));
  auto b = ZenohSession::open(connector_opts(port));
  ZenohPublisher pub(b, "rvc/test/count");
  EXPECT_FALSE(pub.matching());
  EXPECT_FALSE(pub.wait_matched(1, 0ms));

  {
    ZenohSubscriber plain(a, "rvc/test/count", [](const ZenohSample&) {}, false);
    ASSERT_TRUE(pub.wait_matched(1, kHangGuard));
    EXPECT_EQ(pub.announced_subscribers(), 0u);
  }
  ZenohSource s1(a, "rvc/test/*");
  ZenohSource s2(b, "rvc/**");
  ZenohSource other(a, "elsewhere/**");  // does not match: never counted
  s1.start([](const Frame&) {});
  s2.start([](const Frame&) {});
  other.start([](const Frame&) {});
  ASSERT_TRUE(pub.wait_matched(2, kHangGuard));
  EXPECT_EQ(pub.announced_subscribers(), 2u);
  EXPECT_FALSE(pub.wait_matched(3, 200ms));
  s1.stop();
  s2.stop();
  // Tokens go away with their subscribers.
  ZenohSource s3(a, "rvc/test/count");
  s3.start([](const Frame&) {});
  ASSERT_TRUE(pub.wait_matched(1, kHangGuard));
  for (int i = 0; i < 1000 && pub.announced_subscribers() != 1; ++i)
    std::this_thread::sleep_for(10ms);
  EXPECT_EQ(pub.announced_subscribers(), 1u);
}

// After stop() returns the handler never runs again, even mid-stream.
TEST(ZenohTransport, StopIsAFence) {
  auto s = ZenohSession::open(ZenohOptions{});
  std::atomic<bool> stopped{false};
  std::atomic<int> after_stop{0}, calls{0};
  ZenohSource source(s, "rvc/test/fence");
  source.start([&](const Frame&) {
    ++calls;
    // Linger so that stop() is likely to arrive while a call is in flight; a
    // call still running when stop() returned would see `stopped` here.
    std::this_thread::sleep_for(200us);
    if (stopped.load()) ++after_stop;
  });
  ZenohSink sink(s, "rvc/test/fence");
  ASSERT_TRUE(sink.wait_matched(1, kHangGuard));
  std::thread producer([&] {
    for (uint64_t i = 1; i <= 2000; ++i) sink.put("x", i);
  });
  while (calls.load() < 50) std::this_thread::yield();
  source.stop();
  stopped = true;
  producer.join();
  EXPECT_EQ(after_stop.load(), 0);
}

// The factories share one session per options, so two endpoints in one
// process with the same explicit --listen do not collide on the port.
TEST(ZenohTransport, FactoriesShareSession) {
  const int port = free_port();
  ZenohOptions o = listener_opts(port);
  Collector got;
  auto source = make_zenoh_source("rvc/test/shared", o);
  auto sink = make_zenoh_sink("rvc/test/shared", o);
  source->start(got.handler());
  ASSERT_TRUE(sink->wait_matched(1, kHangGuard));
  sink->put("hello", 1);
  sink->put_eos(1);
  ASSERT_TRUE(got.wait_eos());
  std::lock_guard lock(got.mu);
  ASSERT_EQ(got.frames.size(), 2u);
  EXPECT_EQ(got.frames[0].payload, "hello");
  EXPECT_EQ(got.frames[1].seq, 1u);
}

// Router in-process; a client publisher and a client subscriber meet there.
TEST(ZenohTransport, ThroughRouter) {
  const int port = free_port();
  ZenohOptions ro;
  ro.listen = {ep(port)};
  std::atomic<bool> stop{false};
  int rc = -1;
  std::thread router([&] { rc = run_zenoh_router(ro, stop); });
  // The router is up once a client can open (clients fail fast otherwise).
  ZenohOptions co;
  co.mode = "client";
  co.connect = {ep(port)};
  std::shared_ptr<ZenohSession> c1;
  for (int i = 0; i < 600 && !c1; ++i) {
    try {
      c1 = ZenohSession::open(co);
    } catch (const ZenohError&) {
      std::this_thread::sleep_for(50ms);
    }
  }
  ASSERT_TRUE(c1);
  auto c2 = ZenohSession::open(co);
  {
    Collector got;
    ZenohSource source(c1, "rvc/test/routed");
    source.start(got.handler());
    ZenohSink sink(c2, "rvc/test/routed");
    ASSERT_TRUE(sink.wait_matched(1, kHangGuard));
    for (uint64_t i = 1; i <= 100; ++i) sink.put(std::string("m").append(std::to_string(i)), i);
    sink.put_eos(100);
    ASSERT_TRUE(got.wait_eos());
    std::lock_guard lock(got.mu);
    ASSERT_EQ(got.frames.size(), 101u);
    EXPECT_EQ(got.frames[41].payload, "m42");
    EXPECT_EQ(got.frames[41].seq, 42u);
  }
  c1.reset();
  c2.reset();
  stop = true;
  router.join();
  EXPECT_EQ(rc, 0);
}
