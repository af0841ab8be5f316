// In-process tests of the dds: transport over loopback: option parsing, topic
// naming, the end-of-stream marker, the generated configuration, pub->sub
// payload/sequence accounting, and that the participant's sockets stay on
// loopback. Each test uses its own domain id (40..51) and a per-process topic
// so that parallel runs do not interfere. Timeouts below are hang guards only.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <unistd.h>

#include <atomic>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli/transport_flags.hpp"
#include "transport/dds/dds_endpoint.hpp"
#include "transport/seq_counter.hpp"

using namespace rvc::transport;
using namespace rvc::cli;  // add_*_options: the transports' flags
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

constexpr auto kHang = 60s;  // hang guard, never a performance bound

std::string unique_topic(const std::string& name) {
  return "/rvc_test/" + name + "_" + std::to_string(::getpid());
}

DdsOptions opts_for(int domain) {
  DdsOptions o;
  o.domain = domain;
  return o;
}

// Collects frames delivered by a source, with the project's loss counters.
struct Collector {
  std::mutex mu;
  std::condition_variable cv;
  std::vector<std::string> payloads;
  std::vector<uint64_t> seqs;
  SeqCounters counters;
  int eos = 0;
  uint64_t eos_seq = 0;

  FrameHandler handler() {
    return [this](const Frame& f) {
      std::lock_guard lock(mu);
      if (f.eos) {
        ++eos;
        eos_seq = f.seq;
        counters.on_eos(f.seq);
      } else {
        payloads.emplace_back(f.payload);
        seqs.push_back(f.seq);
        counters.on_seq(f.seq);
      }
      cv.notify_all();
    };
  }
  bool wait_eos() {
    std::unique_lock lock(mu);
    return cv.wait_for(lock, kHang, [&] { return eos > 0; });
  }
  bool wait_payloads(size_t n) {
    std::unique_lock lock(mu);
    return cv.wait_for(lock, kHang, [&] { return payloads.size() >= n; });
  }
};

// ------------------------------------------------------------------ QoS

TEST(DdsQos, DefaultsAreReliableKeepAllVolatile) {
  auto q = dds::parse_qos("reliable");
  EXPECT_TRUE(q.reliable);
  EXPECT_EQ(q.keep_last, 0);
  EXPECT_FALSE(q.transient_local);
  EXPECT_EQ(q.max_blocking, 30s);
  EXPECT_TRUE(dds::parse_qos("").reliable);
}

TEST(DdsQos, Overrides) {
  auto q = dds::parse_qos(" Best-Effort , keep-last=10,transient_local,max-blocking=250ms");
  EXPECT_FALSE(q.reliable);
  EXPECT_EQ(q.keep_last, 10);
  EXPECT_TRUE(q.transient_local);
  EXPECT_EQ(q.max_blocking, 250ms);
  EXPECT_EQ(dds::parse_qos("max-blocking=2m").max_blocking, 120s);
  EXPECT_LT(dds::parse_qos("max-blocking=inf").max_blocking.count(), 0);
  EXPECT_EQ(dds::parse_qos("keep-last=4,keep-last=4").keep_last, 4);  // repeating is not contradicting
}

TEST(DdsQos, Ros2Profiles) {
  auto d = dds::parse_qos("ros2-default");  // rmw_qos_profile_default
  EXPECT_TRUE(d.reliable);
  EXPECT_EQ(d.keep_last, 10);
  EXPECT_FALSE(d.transient_local);
  auto s = dds::parse_qos("Sensor-Data, max-blocking=1s");  // rmw_qos_profile_sensor_data, plus an item
  EXPECT_FALSE(s.reliable);
  EXPECT_EQ(s.keep_last, 5);
  EXPECT_EQ(s.max_blocking, 1s);
}

void expect_qos_error(const std::string& text, const std::string& fragment) {
  try {
    dds::parse_qos(text);
    ADD_FAILURE() << "'" << text << "' was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--qos"), std::string::npos) << e.what();
  }
}

TEST(DdsQos, ErrorsNameTheOffendingItem) {
  expect_qos_error("reliable,bogus", "unknown item 'bogus'");
  expect_qos_error("reliable,bogus", "expected reliable, best-effort");
  expect_qos_error("keep-last", "keep-last needs a depth");
  expect_qos_error("keep-last=0", "keep-last needs a depth");
  expect_qos_error("keep-last=x", "keep-last needs a depth");
  expect_qos_error("reliable,best-effort", "contradicts an earlier reliability item");
  expect_qos_error("volatile,transient-local", "contradicts an earlier durability item");
  expect_qos_error("keep-all,keep-last=3", "contradicts an earlier history item");
  expect_qos_error("max-blocking=10", "needs a unit");
  expect_qos_error("sensor-data,reliable", "in 'sensor-data,reliable'");  // the text as the user wrote it
  expect_qos_error("reliable,", "empty item");
  expect_qos_error("reliable=1", "unknown item 'reliable=1'");
}

// ------------------------------------------------------------ topic names

TEST(DdsNames, Ros2TopicsGetTheRtPrefix) {
  EXPECT_EQ(dds::dds_topic_name("/rv/verdicts", true), "rt/rv/verdicts");
  EXPECT_EQ(dds::dds_topic_name("rv/verdicts", true), "rt/rv/verdicts");
  EXPECT_EQ(dds::dds_topic_name("chatter", true), "rt/chatter");
  EXPECT_EQ(dds::dds_topic_name("/rv/verdicts", false), "/rv/verdicts");
  EXPECT_EQ(dds::dds_topic_name("PlainTopic", false), "PlainTopic");
  EXPECT_EQ(dds::dds_type_name("string"), "std_msgs::msg::dds_::String_");
  EXPECT_EQ(dds::dds_type_name("frame"), "rvc_msgs::msg::dds_::Frame_");
}

TEST(DdsNames, InvalidRos2NamesAreRejectedClearly) {
  for (const char* bad : {"", "/", "/a//b", "/a/", "/1abc", "/a/b-c", "/a b", "/a__b", "/~/x"}) {
    try {
      dds::dds_topic_name(bad, true);
      ADD_FAILURE() << "'" << bad << "' was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("not a valid ROS 2 topic name"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(dds::dds_topic_name("", false), std::invalid_argument);
  EXPECT_THROW(dds::dds_topic_name("a b", false), std::invalid_argument);
  EXPECT_THROW(dds::dds_type_name("json"), std::invalid_argument);
}

// ------------------------------------------------------ end-of-stream marker

TEST(DdsEos, RoundTripAndStrictParsing) {
  auto s = dds::format_eos({42, 40});
  EXPECT_EQ(s, std::string("\x04rvc-eos last=42 count=40"));
  auto m = dds::parse_eos(s);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->last_seq, 42u);
  EXPECT_EQ(m->count, 40u);
  auto m2 = dds::parse_eos("\x04rvc-eos last=7");
  ASSERT_TRUE(m2);
  EXPECT_EQ(m2->count, 7u);
  for (const char* not_eos : {"", "{}", "{\"rvc-eos\":1}", "rvc-eos last=1", "\x04rvc-eos", "\x04rvc-eos last=",
                              "\x04rvc-eos last=1 count=", "\x04rvc-eos last=1 extra=2", "\x04rvc-eos last=1x",
                              "\x04rvc-eos  last=1"})
    EXPECT_FALSE(dds::parse_eos(not_eos)) << "'" << not_eos << "' parsed as EOS";
}

// ------------------------------------------------------- generated config

TEST(DdsConfig, LoopbackConfigNamesOnlyLoAndUnicastPeers) {
  DdsOptions o;
  std::string x = dds::generated_config_xml(o);
  EXPECT_NE(x.find("<NetworkInterface name=\"lo\" multicast=\"false\"/>"), std::string::npos) << x;
  EXPECT_NE(x.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos) << x;
  EXPECT_NE(x.find("<Peer address=\"127.0.0.1\"/>"), std::string::npos) << x;
  EXPECT_NE(x.find("<ParticipantIndex>auto</ParticipantIndex>"), std::string::npos) << x;
  // Exactly one interface element, and it is lo.
  size_t n = 0;
  for (size_t p = x.find("<NetworkInterface"); p != std::string::npos; p = x.find("<NetworkInterface", p + 1)) ++n;
  EXPECT_EQ(n, 1u);
  // No address of any other interface of this host appears anywhere.
  ifaddrs* ifs = nullptr;
  ASSERT_EQ(getifaddrs(&ifs), 0);
  for (ifaddrs* i = ifs; i; i = i->ifa_next) {
    if (!i->ifa_addr || std::string(i->ifa_name) == "lo") continue;
    EXPECT_EQ(x.find(i->ifa_name), std::string::npos) << "config mentions " << i->ifa_name;
    if (i->ifa_addr->sa_family == AF_INET) {
      char buf[INET_ADDRSTRLEN];
      inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(i->ifa_addr)->sin_addr, buf, sizeof buf);
      EXPECT_EQ(x.find(buf), std::string::npos) << "config mentions " << buf;
    }
  }
  freeifaddrs(ifs);
  EXPECT_EQ(dds::effective_config(o), x);
}

TEST(DdsConfig, NamedInterfaceAndPeersForContainers) {
  DdsOptions o;
  o.interface = "eth1";
  std::string x = dds::generated_config_xml(o);  // generated only; never started
  EXPECT_NE(x.find("<NetworkInterface name=\"eth1\"/>"), std::string::npos) << x;
  EXPECT_EQ(x.find("AllowMulticast"), std::string::npos) << x;
  o.peers = {"10.0.0.5", "a&b"};
  x = dds::generated_config_xml(o);
  EXPECT_NE(x.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos) << x;
  EXPECT_NE(x.find("<Peer address=\"10.0.0.5\"/>"), std::string::npos) << x;
  EXPECT_NE(x.find("<Peer address=\"a&amp;b\"/>"), std::string::npos) << x;
  o.interface = "10.0.0.2";
  EXPECT_NE(dds::generated_config_xml(o).find("<NetworkInterface address=\"10.0.0.2\""), std::string::npos);
}

TEST(DdsConfig, UserConfigFileIsReferencedNotGenerated) {
  DdsOptions o;
  o.config_file = "/nonexistent/rvc.xml";
  EXPECT_THROW(dds::effective_config(o), std::invalid_argument);
  auto path = fs::temp_directory_path() / ("rvc_dds_cfg_" + std::to_string(::getpid()) + ".xml");
  std::ofstream(path) << dds::generated_config_xml(DdsOptions{});
  o.config_file = path.string();
  EXPECT_EQ(dds::effective_config(o), "file://" + path.string());
  o.trace_file = "/tmp/x.log";
  EXPECT_THROW(dds::validate(o), std::invalid_argument);
  fs::remove(path);
}

// -------------------------------------------------------------------- CLI

TEST(DdsCli, OptionsParse) {
  CLI::App app;
  DdsOptions o;
  add_dds_options(app, o);
  app.parse("--domain 7 --partition p1 --qos best-effort,keep-last=5 --dds-type frame --dds-peer 127.0.0.2 "
            "--no-ros2-names",
            false);
  EXPECT_EQ(o.domain, 7);
  EXPECT_EQ(o.partition, "p1");
  EXPECT_EQ(o.qos, "best-effort,keep-last=5");
  EXPECT_EQ(o.type, "frame");
  EXPECT_FALSE(o.ros2);
  ASSERT_EQ(o.peers.size(), 1u);
  EXPECT_EQ(o.interface, "lo");
}

TEST(DdsCli, BadValuesAreRejectedWithTheReason) {
  auto parse_error = [](const std::string& args) -> std::string {
    CLI::App app;
    DdsOptions o;
    add_dds_options(app, o);
    try {
      app.parse(args, false);
    } catch (const CLI::ParseError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(parse_error("--qos reliable,keep-last=2"), "");
  EXPECT_NE(parse_error("--qos bogus,reliable").find("unknown item 'bogus'"), std::string::npos);
  EXPECT_NE(parse_error("--domain 999"), "");
  EXPECT_NE(parse_error("--dds-type json"), "");
  EXPECT_NE(parse_error("--dds-config /nonexistent/cyclone.xml"), "");
}

// ------------------------------------------------------- pub -> sub (lo)

TEST(DdsPubSub, PayloadBytesSeqAndEos) {
  const auto topic = unique_topic("bytes");
  DdsSource src(topic, opts_for(40));
  DdsSink sink(topic, opts_for(40));
  EXPECT_EQ(src.dds_topic(), "rt" + topic);
  Collector c;
  src.start(c.handler());
  ASSERT_TRUE(sink.wait_matched(1, kHang));
  ASSERT_TRUE(src.wait_matched(1, kHang));
  std::vector<std::string> sent = {R"({"t":1,"p":true})", "", "caf\xc3\xa9 \xe2\x9c\x93", std::string(100000, 'x'),
                                   "{\"esc\":\"\\n\\t\"}"};
  for (int i = 0; i < 2000; ++i) sent.push_back("{\"i\":" + std::to_string(i) + "}");
  for (size_t i = 0; i < sent.size(); ++i) sink.put(sent[i], i + 1);
  sink.put_eos(sent.size());
  sink.flush();
  EXPECT_EQ(sink.written(), sent.size());
  ASSERT_TRUE(c.wait_eos());
  std::lock_guard lock(c.mu);
  EXPECT_EQ(c.payloads, sent);
  for (size_t i = 0; i < c.seqs.size(); ++i) ASSERT_EQ(c.seqs[i], i + 1);
  EXPECT_EQ(c.eos, 1);
  EXPECT_EQ(c.eos_seq, sent.size());
  EXPECT_EQ(c.counters.received, sent.size());
  EXPECT_EQ(c.counters.gaps, 0u);
  EXPECT_EQ(c.counters.duplicates, 0u);
}

TEST(DdsPubSub, FrameTypeCarriesPublisherSeq) {
  const auto topic = unique_topic("frame");
  DdsOptions o = opts_for(41);
  o.type = "frame";
  DdsSource src(topic, o);
  DdsSink sink(topic, o);
  Collector c;
  src.start(c.handler());
  ASSERT_TRUE(sink.wait_matched(1, kHang));
  for (uint64_t s : {1, 2, 3, 5, 6, 9}) sink.put("{\"s\":" + std::to_string(s) + "}", s);  // 4, 7, 8 never sent
  sink.put_eos(10);                                                                         // 10 never sent either
  sink.flush();
  ASSERT_TRUE(c.wait_eos());
  std::lock_guard lock(c.mu);
  EXPECT_EQ(c.seqs, (std::vector<uint64_t>{1, 2, 3, 5, 6, 9}));
  EXPECT_EQ(c.eos_seq, 10u);
  EXPECT_EQ(c.counters.received, 6u);
  EXPECT_EQ(c.counters.gaps, 4u);
}

TEST(DdsPubSub, StringTypeLossShowsUpAsGapsAtEos) {
  // A late-joining keep-last=3 transient-local reader only gets the last two
  // data samples and the marker: the marker's count turns the rest into gaps.
  const auto topic = unique_topic("late");
  DdsOptions o = opts_for(42);
  o.qos = "reliable,keep-last=3,transient-local";
  DdsSink sink(topic, o);
  for (uint64_t s = 1; s <= 10; ++s) sink.put("{\"s\":" + std::to_string(s) + "}", s);
  sink.put_eos(10);
  DdsSource src(topic, o);
  Collector c;
  src.start(c.handler());
  ASSERT_TRUE(c.wait_eos());
  std::lock_guard lock(c.mu);
  EXPECT_EQ(c.payloads, (std::vector<std::string>{"{\"s\":9}", "{\"s\":10}"}));
  EXPECT_EQ(c.seqs, (std::vector<uint64_t>{1, 2}));  // arrival index: the String type has no seq field
  EXPECT_EQ(c.eos_seq, 10u);                          // the writer's count
  EXPECT_EQ(c.counters.received, 2u);
  EXPECT_EQ(c.counters.gaps, 8u);
}

// Delivery on CycloneDDS's thread (a data-available listener): samples written
// before start() and after it arrive once, in order, each writer's seq intact;
// nothing is delivered after stop() returns.
TEST(DdsPubSub, ReceiveThreadDeliveryKeepsOrderAndStopsAtStop) {
  const auto topic = unique_topic("listener");
  DdsOptions o = opts_for(50);
  o.type = "frame";
  o.deliver_on_receive_thread = true;
  DdsSource src(topic, o);
  DdsSink sink(topic, o);
  ASSERT_TRUE(sink.wait_matched(1, kHang));
  for (uint64_t s = 1; s <= 500; ++s) sink.put("{\"s\":" + std::to_string(s) + "}", s);  // before start
  Collector c;
  std::atomic<bool> stopped{false};
  std::atomic<int> after_stop{0};
  FrameHandler collect = c.handler();
  src.start([&](const Frame& f) {
    if (stopped.load()) after_stop.fetch_add(1);
    collect(f);
  });
  // No new sample raises a callback: start() itself must deliver these.
  ASSERT_TRUE(c.wait_payloads(500));
  std::thread second([&] {  // a second writer thread on the same topic
    DdsSink other(topic, o);
    for (uint64_t s = 1; s <= 300; ++s) other.put("{\"o\":" + std::to_string(s) + "}", 100000 + s);
    other.flush();
  });
  for (uint64_t s = 501; s <= 3000; ++s) sink.put("{\"s\":" + std::to_string(s) + "}", s);
  second.join();
  sink.put_eos(3000);
  ASSERT_TRUE(c.wait_eos());
  src.stop();
  stopped = true;
  for (uint64_t s = 3001; s <= 3100; ++s) sink.put("{\"s\":" + std::to_string(s) + "}", s);
  sink.flush();
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(after_stop.load(), 0);
  std::lock_guard lock(c.mu);
  std::vector<uint64_t> mine, other;
  for (uint64_t s : c.seqs) (s > 100000 ? other : mine).push_back(s);
  ASSERT_EQ(mine.size(), 3000u);
  ASSERT_EQ(other.size(), 300u);
  for (size_t i = 0; i < mine.size(); ++i) ASSERT_EQ(mine[i], i + 1) << "writer 1 out of order at " << i;
  for (size_t i = 0; i < other.size(); ++i) ASSERT_EQ(other[i], 100001 + i) << "writer 2 out of order at " << i;
}

// --dds-write-batch is domain configuration: the generated XML carries it, a
// user's --dds-config cannot be combined with it, and samples and the
// end-of-stream marker still arrive whole. (In one process CycloneDDS delivers
// locally and never batches; the participants tier checks two processes.)
TEST(DdsPubSub, WriteBatchingIsConfigurationAndLosesNothing) {
  const auto topic = unique_topic("batch");
  DdsOptions o = opts_for(51);
  o.write_batch = true;
  EXPECT_NE(dds::generated_config_xml(o).find("<Internal><WriteBatch>true</WriteBatch></Internal>"),
            std::string::npos);
  EXPECT_EQ(dds::generated_config_xml(opts_for(51)).find("WriteBatch"), std::string::npos);  // unset: off
  DdsOptions off = opts_for(51);
  off.write_batch = false;  // --no-dds-write-batch
  EXPECT_EQ(dds::generated_config_xml(off).find("WriteBatch"), std::string::npos);
  off.config_file = "/etc/hostname";
  EXPECT_NO_THROW(dds::validate(off));  // "off" asks nothing of a user's file
  DdsOptions with_file = o;
  with_file.config_file = "/etc/hostname";
  try {
    dds::validate(with_file);
    ADD_FAILURE() << "--dds-write-batch with --dds-config was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--dds-write-batch cannot be combined with --dds-config"), std::string::npos)
        << e.what();
  }
  DdsSource src(topic, o);
  DdsSink sink(topic, o);
  Collector c;
  src.start(c.handler());
  ASSERT_TRUE(sink.wait_matched(1, kHang));
  for (uint64_t s = 1; s <= 1000; ++s) sink.put("{\"s\":" + std::to_string(s) + "}", s);
  sink.put_eos(1000);
  ASSERT_TRUE(c.wait_eos());
  std::lock_guard lock(c.mu);
  EXPECT_EQ(c.payloads.size(), 1000u);
  EXPECT_EQ(c.counters.gaps, 0u);
}

TEST(DdsPubSub, PartitionsSeparateTopics) {
  const auto topic = unique_topic("part");
  DdsOptions a = opts_for(43), b = opts_for(43);
  a.partition = "alpha";
  b.partition = "beta";
  DdsSource src_a(topic, a);
  DdsSink sink_b(topic, b);
  DdsSink sink_a(topic, a);
  EXPECT_TRUE(sink_a.wait_matched(1, kHang));
  EXPECT_FALSE(sink_b.wait_matched(1, 200ms));  // no reader in partition beta (either outcome is quick)
  Collector c;
  src_a.start(c.handler());
  sink_b.put("{\"from\":\"beta\"}", 1);
  sink_b.put_eos(1);
  sink_a.put("{\"from\":\"alpha\"}", 1);
  sink_a.put_eos(1);
  sink_a.flush();
  ASSERT_TRUE(c.wait_eos());
  std::lock_guard lock(c.mu);
  EXPECT_EQ(c.payloads, (std::vector<std::string>{"{\"from\":\"alpha\"}"}));
}

TEST(DdsPubSub, ReliableReaderDoesNotMatchBestEffortWriter) {
  const auto topic = unique_topic("rxo");
  DdsOptions be = opts_for(44);
  be.qos = "best-effort";
  DdsSource reliable_src(topic, opts_for(44));
  DdsSink best_effort_sink(topic, be);
  EXPECT_FALSE(best_effort_sink.wait_matched(1, 300ms));
  DdsSource best_effort_src(topic, be);
  EXPECT_TRUE(best_effort_sink.wait_matched(1, kHang));
}

TEST(DdsPubSub, SinkRejectsPayloadsItCannotCarry) {
  const auto topic = unique_topic("reject");
  DdsSink sink(topic, opts_for(45));
  EXPECT_THROW(sink.put(std::string("a\0b", 3), 1), std::invalid_argument);
  EXPECT_THROW(sink.put(dds::format_eos({1, 1}), 1), std::invalid_argument);
  EXPECT_EQ(sink.written(), 0u);
}

TEST(DdsEndpoints, ErrorsAreClear) {
  DdsOptions o = opts_for(46);
  o.qos = "keep-last=0";
  EXPECT_THROW(DdsSink("/x", o), std::invalid_argument);
  EXPECT_THROW(DdsSink("/bad name", opts_for(46)), std::invalid_argument);
  // A missing interface fails domain creation (peer forced to 127.0.0.1 so
  // that even a misbehaving fallback could only talk to loopback).
  DdsOptions missing = opts_for(47);
  missing.interface = "rvcnosuch0";
  missing.peers = {"127.0.0.1"};
  try {
    DdsSource s("/x", missing);
    ADD_FAILURE() << "missing interface accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot create domain 47"), std::string::npos) << e.what();
  }
  // One domain id, one configuration per process.
  DdsSource first("/x", opts_for(48));
  DdsOptions other = opts_for(48);
  other.peers = {"127.0.0.2"};
  EXPECT_THROW(DdsSink("/x", other), std::invalid_argument);
  DdsSink same("/x", opts_for(48));  // same configuration: shares the participant
  DdsSource src("/y", opts_for(48));
  src.start([](const Frame&) {});
  EXPECT_THROW(src.start([](const Frame&) {}), std::logic_error);
  src.stop();
  src.stop();  // idempotent
}

// ------------------------------------------------------ network safety

struct SockInfo {
  std::string table;
  std::string local_ip, remote_ip;
  unsigned local_port = 0, remote_port = 0;
};

std::string hex_ip(const std::string& h) {
  char buf[INET6_ADDRSTRLEN] = {};
  if (h.size() == 8) {
    in_addr a;
    a.s_addr = static_cast<uint32_t>(std::stoul(h, nullptr, 16));  // /proc prints the in-memory u32
    inet_ntop(AF_INET, &a, buf, sizeof buf);
  } else {
    in6_addr a;
    for (int w = 0; w < 4; ++w) {
      uint32_t v = static_cast<uint32_t>(std::stoul(h.substr(w * 8, 8), nullptr, 16));
      std::memcpy(&a.s6_addr[w * 4], &v, 4);
    }
    inet_ntop(AF_INET6, &a, buf, sizeof buf);
  }
  return buf;
}

std::set<std::string> my_socket_inodes() {
  std::set<std::string> out;
  for (auto& e : fs::directory_iterator("/proc/self/fd")) {
    std::error_code ec;
    auto t = fs::read_symlink(e.path(), ec).string();
    if (!ec && t.rfind("socket:[", 0) == 0) out.insert(t.substr(8, t.size() - 9));
  }
  return out;
}

std::vector<SockInfo> sockets_of(const std::set<std::string>& inodes) {
  std::vector<SockInfo> out;
  for (const char* table : {"udp", "udp6", "tcp", "tcp6"}) {
    std::ifstream in(std::string("/proc/self/net/") + table);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::istringstream ss(line);
      std::string sl, local, remote, st, txrx, trtm, retr, uid, timeout, inode;
      ss >> sl >> local >> remote >> st >> txrx >> trtm >> retr >> uid >> timeout >> inode;
      if (!inodes.count(inode)) continue;
      SockInfo s;
      s.table = table;
      auto colon = local.find(':');
      s.local_ip = hex_ip(local.substr(0, colon));
      s.local_port = std::stoul(local.substr(colon + 1), nullptr, 16);
      colon = remote.find(':');
      s.remote_ip = hex_ip(remote.substr(0, colon));
      s.remote_port = std::stoul(remote.substr(colon + 1), nullptr, 16);
      out.push_back(s);
    }
  }
  return out;
}

bool is_loopback(const std::string& ip) { return ip.rfind("127.", 0) == 0 || ip == "::1"; }
bool is_wildcard(const std::string& ip) { return ip == "0.0.0.0" || ip == "::"; }

TEST(DdsNetwork, ParticipantStaysOnLoopback) {
  const int domain = 49;
  const auto before = my_socket_inodes();
  const auto trace = fs::temp_directory_path() / ("rvc_dds_trace_" + std::to_string(::getpid()) + ".log");
  DdsOptions o = opts_for(domain);
  o.trace_file = trace.string();
  {
    const auto topic = unique_topic("net");
    DdsSource src(topic, o);
    DdsSink sink(topic, o);
    Collector c;
    src.start(c.handler());
    ASSERT_TRUE(sink.wait_matched(1, kHang));
    sink.put("{\"net\":1}", 1);
    sink.put_eos(1);
    ASSERT_TRUE(c.wait_eos());

    std::set<std::string> mine;
    for (auto& i : my_socket_inodes())
      if (!before.count(i)) mine.insert(i);
    auto socks = sockets_of(mine);
    ASSERT_FALSE(socks.empty()) << "no DDS sockets found";
    // DDSI unicast ports of this domain: 7400 + 250 d + 10/11 + 2 i.
    const unsigned base = 7400 + 250 * domain;
    size_t bound_to_lo = 0;
    for (auto& s : socks) {
      SCOPED_TRACE(s.table + " " + s.local_ip + ":" + std::to_string(s.local_port));
      EXPECT_EQ(s.table.substr(0, 3), "udp") << "CycloneDDS opened a TCP socket";
      EXPECT_TRUE(is_loopback(s.local_ip) || is_wildcard(s.local_ip)) << "socket bound to a non-loopback address";
      EXPECT_TRUE(s.remote_port == 0 || is_loopback(s.remote_ip)) << "socket connected to " << s.remote_ip;
      if (is_loopback(s.local_ip)) ++bound_to_lo;
      if (is_wildcard(s.local_ip)) {
        // CycloneDDS 0.10 binds its unicast *receive* sockets to the wildcard
        // address (no BindUnicastToInterfaceAddress yet); only those may be.
        EXPECT_TRUE(s.local_port >= base + 10 && s.local_port <= base + 10 + 2 * 100 + 1)
            << "unexpected wildcard-bound socket";
      }
    }
    EXPECT_GE(bound_to_lo, 1u) << "no transmit socket bound to 127.0.0.1";
  }
  // Domain deleted: the trace is complete. Only lo was selected, and no
  // address of another interface was used for anything (the one line that
  // enumerates the host's interfaces excepted).
  std::ifstream in(trace);
  ASSERT_TRUE(in) << "no trace at " << trace;
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  auto has = [&](const std::string& s) {
    for (auto& l : lines)
      if (l.find(s) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("selected interfaces: lo ")) << "trace: " << trace;
  EXPECT_TRUE(has("ownip: udp/127.0.0.1"));
  EXPECT_TRUE(has("add_peer_addresses: add udp/127.0.0.1:"));
  ifaddrs* ifs = nullptr;
  ASSERT_EQ(getifaddrs(&ifs), 0);
  for (ifaddrs* i = ifs; i; i = i->ifa_next) {
    if (!i->ifa_addr || i->ifa_addr->sa_family != AF_INET || std::string(i->ifa_name) == "lo") continue;
    char buf[INET_ADDRSTRLEN];
    inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(i->ifa_addr)->sin_addr, buf, sizeof buf);
    for (auto& l : lines) {
      if (l.find(": interfaces: ") != std::string::npos) continue;
      EXPECT_EQ(l.find(std::string("/") + buf), std::string::npos) << "trace uses " << buf << ": " << l;
    }
  }
  freeifaddrs(ifs);
  fs::remove(trace);
}

}  // namespace
