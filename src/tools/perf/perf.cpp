#include "tools/perf/perf.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>

#include "io/json_writer.hpp"
#include "transport/seq_counter.hpp"
#ifdef RVC_HAVE_ZENOH
#include "transport/zenoh/rvc_zenoh.h"
#include "transport/zenoh/zenoh_endpoint.hpp"
#include "transport/zenoh/zenoh_session.hpp"
#endif
#ifdef RVC_HAVE_DDS
#include <dds/dds.h>
#include <unistd.h>

#include "transport/dds/dds_endpoint.hpp"
#endif

namespace rvc::perf {
namespace {

using Clock = std::chrono::steady_clock;
using transport::Frame;

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}
Clock::time_point at_ns(int64_t ns) { return Clock::time_point(std::chrono::nanoseconds(ns)); }
int64_t secs_ns(double s) { return static_cast<int64_t>(s * 1e9); }
std::chrono::milliseconds secs_ms(double s) { return std::chrono::milliseconds(static_cast<int64_t>(s * 1000)); }

enum Exit : int { kOk = 0, kNoPeer = 2, kLost = 4 };

bool stop_now(const PerfOptions& o) { return o.should_stop && o.should_stop(); }

// The rate as the summaries show it: messages/s, or "max".
void add_rate(io::JsonObject& js, double hz) {
  if (hz <= 0) js.add("rate", "max");
  else js.add("rate", hz);
}

// ---------------------------------------------------------------- transport

#ifdef RVC_HAVE_ZENOH
// The session rvc would open for these flags. --best-effort adds a Zenoh QoS
// overwrite for publishers under NAME/** (congestion control Drop): the C ABI
// declares every publisher with Block, and Zenoh applies configured
// overwrites last. The links stay TCP, so "best effort" means "dropped under
// congestion instead of blocking the publisher".
std::shared_ptr<transport::ZenohSession> open_zenoh(const PerfOptions& o) {
  const transport::ZenohOptions& z = o.transports.zenoh;
  if (!o.best_effort) return transport::ZenohSession::open(z);
  std::vector<const char*> connect, listen;
  for (const auto& e : z.connect) connect.push_back(e.c_str());
  for (const auto& e : z.listen) listen.push_back(e.c_str());
  const bool have_file = !z.config_file.empty();
  rvc_zenoh_config_opts c{};
  c.base_file = have_file ? z.config_file.c_str() : nullptr;
  c.mode = (!have_file || z.mode_explicit) ? z.mode.c_str() : nullptr;
  c.connect = connect.data();
  c.n_connect = connect.size();
  c.listen = listen.data();
  c.n_listen = listen.size();
  c.multicast_scouting = z.multicast_scouting;
  rvc_zenoh_config* cfg = nullptr;
  auto fail = [](const std::string& what) {
    throw transport::ZenohError("zenoh: " + what + ": " + rvc_zenoh_last_error());
  };
  if (rvc_zenoh_config_build(&c, &cfg) < 0) fail("building config");
  std::unique_ptr<rvc_zenoh_config, void (*)(rvc_zenoh_config*)> guard(cfg, rvc_zenoh_config_free);
  std::string overwrite = "[{key_exprs: [\"" + o.name + "/**\"], config: {congestion_control: \"drop\"}}]";
  if (rvc_zenoh_config_insert_json5(cfg, "qos/publication", overwrite.c_str()) < 0) fail("setting qos/publication");
  char* json = rvc_zenoh_config_get_json(cfg, "");
  if (!json) fail("reading config");
  std::string text = json;
  rvc_zenoh_string_free(json);
  return transport::ZenohSession::open_json5(text.c_str());
}
#endif

// Opens writers (Sinks) and readers (Sources) of one transport. Zenoh: one
// session for the process (pub and sub of --inproc share it, so delivery is
// session-local). DDS: rvc's shared participant, payload type rvc Frame
// (uint64 seq + string data) so every sample carries its sequence number.
class Transport {
 public:
  explicit Transport(const PerfOptions& o) : o_(o) {
    if (o.transport == "zenoh") {
#ifdef RVC_HAVE_ZENOH
      zenoh_ = open_zenoh(o);
      return;
#else
      throw std::invalid_argument("this rvc was built without the zenoh transport");
#endif
    }
    if (o.transport == "dds") {
#ifdef RVC_HAVE_DDS
      dds_ = o.transports.dds;
      dds_.type = "frame";
      if (o.best_effort) dds_.qos = "best-effort";
      if (o.write_batch) dds_.write_batch = true;  // else as the transport flags (rvc perf pub: on)
      return;
#else
      throw std::invalid_argument("this rvc was built without the dds transport");
#endif
    }
    throw std::invalid_argument("--transport must be zenoh or dds, not '" + o.transport + "'");
  }
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  std::unique_ptr<transport::Sink> writer(const std::string& name) {
#ifdef RVC_HAVE_ZENOH
    if (zenoh_) return std::make_unique<transport::ZenohSink>(zenoh_, name, o_.transports.zenoh.express);
#endif
#ifdef RVC_HAVE_DDS
    return std::make_unique<transport::DdsSink>(name, dds_);
#else
    throw std::logic_error("no transport");
#endif
  }

  // counting_only: the handler only counts (sub, in-process sub), so a DDS
  // reader may run it on CycloneDDS's receive thread. Pong and ping handlers
  // write samples, which may wait for acknowledgements that only that thread
  // can process: they keep the reader's own thread.
  std::unique_ptr<transport::Source> reader(const std::string& name, bool counting_only = false) {
#ifdef RVC_HAVE_ZENOH
    if (zenoh_) return std::make_unique<transport::ZenohSource>(zenoh_, name);
#endif
#ifdef RVC_HAVE_DDS
    transport::DdsOptions d = dds_;
    d.deliver_on_receive_thread = counting_only;
    return std::make_unique<transport::DdsSource>(name, d);
#else
    throw std::logic_error("no transport");
#endif
  }

  // DDS readers know when a writer matched; Zenoh subscribers cannot tell.
  bool reader_matched(transport::Source& s, std::chrono::milliseconds timeout) {
#ifdef RVC_HAVE_DDS
    if (auto* d = dynamic_cast<transport::DdsSource*>(&s)) return d->wait_matched(1, timeout);
#endif
    return true;
  }

  std::string uri(const std::string& name) const { return o_.transport + ":" + name; }

 private:
  const PerfOptions& o_;
#ifdef RVC_HAVE_ZENOH
  std::shared_ptr<transport::ZenohSession> zenoh_;
#endif
#ifdef RVC_HAVE_DDS
  transport::DdsOptions dds_;
#endif
};

// ------------------------------------------------------------- throughput

// Counts what a subscriber receives. on_frame runs on one transport thread
// at a time (ZenohSource serialises, DdsSource has one waitset thread); the
// atomics let the main thread print progress without locking per message.
struct SubCounter {
  transport::SeqCounters c;  // transport thread only
  int64_t warmup_ns = 0;     // msgs_per_s counts from first message + warmup
  bool warm = false;         // transport thread only
  std::atomic<int64_t> warm_ns{0};
  std::atomic<uint64_t> warm_received{0}, warm_bytes{0};
  std::atomic<uint64_t> received{0}, gaps{0}, bytes{0};
  std::atomic<int64_t> first_ns{0}, last_ns{0};
  std::mutex mu;
  std::condition_variable cv;
  bool eos = false;  // under mu
  uint64_t eos_seq = 0;

  void on_frame(const Frame& f) {
    if (f.eos) {
      c.on_eos(f.seq);
      gaps.store(c.gaps, std::memory_order_relaxed);
      {
        std::lock_guard lock(mu);
        eos = true;
        eos_seq = f.seq;
      }
      cv.notify_all();
      return;
    }
    const int64_t t = now_ns();
    if (c.received == 0) first_ns.store(t, std::memory_order_relaxed);
    if (!warm && t - first_ns.load(std::memory_order_relaxed) >= warmup_ns) {
      warm = true;  // the steady-state window starts with this message
      warm_ns.store(t, std::memory_order_relaxed);
      warm_received.store(c.received, std::memory_order_relaxed);
      warm_bytes.store(bytes.load(std::memory_order_relaxed), std::memory_order_relaxed);
    }
    last_ns.store(t, std::memory_order_relaxed);
    c.on_seq(f.seq);
    bytes.store(bytes.load(std::memory_order_relaxed) + f.payload.size(), std::memory_order_relaxed);
    gaps.store(c.gaps, std::memory_order_relaxed);
    received.store(c.received, std::memory_order_release);
  }

  bool wait_eos_until(int64_t deadline_ns) {
    std::unique_lock lock(mu);
    return cv.wait_until(lock, at_ns(deadline_ns), [&] { return eos; });
  }
  bool has_eos() {
    std::lock_guard lock(mu);
    return eos;
  }
};

// Waits until the end of stream, an idle gap, --duration after the first
// message, the --timeout for the first message, or a stop signal; prints a
// progress line every report interval. Returns false if nothing arrived.
bool follow_subscription(const PerfOptions& o, SubCounter& s, const char* who) {
  const int64_t start = now_ns();
  int64_t next_report = start + secs_ns(o.report_interval > 0 ? o.report_interval : 1e6);
  int64_t last_t = start;
  uint64_t last_r = 0, last_b = 0;
  for (;;) {
    const int64_t wake = std::min(next_report, now_ns() + 100'000'000);
    if (s.wait_eos_until(wake)) return true;
    if (stop_now(o)) return s.received.load() > 0;
    const int64_t t = now_ns();
    const uint64_t r = s.received.load(std::memory_order_acquire);
    if (r == 0 && t - start > secs_ns(o.timeout)) {
      std::fprintf(stderr, "rvc perf %s: nothing received within %.1f s (--timeout)\n", who, o.timeout);
      return false;
    }
    if (r > 0 && t - s.last_ns.load() > secs_ns(o.idle_timeout)) {
      std::fprintf(stderr, "rvc perf %s: no message for %.1f s and no end of stream; stopping\n", who,
                   o.idle_timeout);
      return true;
    }
    if (o.duration > 0 && r > 0 && t - s.first_ns.load() > secs_ns(o.duration)) return true;
    if (o.report_interval > 0 && t >= next_report) {
      const uint64_t b = s.bytes.load(std::memory_order_relaxed);
      const double dt = (t - last_t) / 1e9;
      std::fprintf(stderr, "rvc perf %s: %7.2f s  %10.0f msg/s  %9.2f Mbit/s  received %llu  lost %llu\n", who,
                   (t - start) / 1e9, (r - last_r) / dt, (b - last_b) * 8 / dt / 1e6,
                   static_cast<unsigned long long>(r), static_cast<unsigned long long>(s.gaps.load()));
      last_t = t;
      last_r = r;
      last_b = b;
      next_report += secs_ns(o.report_interval);
      if (next_report <= t) next_report = t + secs_ns(o.report_interval);
    }
  }
}

// The subscriber's summary. msgs_per_s counts from the first message (plus
// --warmup seconds) to the last one, so discovery, the ramp-up and the wait
// for the end of stream do not dilute it; avg_msgs_per_s is first to last.
std::string sub_json(const PerfOptions& o, const char* role, SubCounter& s, uint64_t sent_by_pub) {
  const uint64_t received = s.c.received;
  const bool eos = s.has_eos();
  const uint64_t sent = sent_by_pub ? sent_by_pub : eos ? s.eos_seq : s.c.last_seq;
  const double span = (s.last_ns.load() - s.first_ns.load()) / 1e9;
  const double avg = received > 1 && span > 0 ? (received - 1) / span : 0;
  const double steady_span = (s.last_ns.load() - s.warm_ns.load()) / 1e9;
  const uint64_t steady_n = received - s.warm_received.load();
  // Too little after the warm-up (a short run): fall back to the whole run.
  const bool steady = s.warm && steady_n > 100 && steady_span > 0.2;
  const double mps = steady ? steady_n / steady_span : avg;
  const double avg_size = received ? static_cast<double>(s.bytes.load()) / received : static_cast<double>(o.size);
  const double mbps = mps * avg_size * 8 / 1e6;
  return io::JsonObject()
      .add("role", role)
      .add("transport", o.transport)
      .add_fixed("size", avg_size, 0)
      .add_fixed("msgs_per_s", mps, 1)
      .add_fixed("mbps", mbps, 3)
      .add("lost", s.c.gaps)
      .add("sent", sent)
      .add("received", received)
      .add("duplicates", s.c.duplicates)
      .add_fixed("seconds", span, 6)
      .add_fixed("avg_msgs_per_s", avg, 1)
      .add_fixed("steady_seconds", steady ? steady_span : span, 6)
      .add("reliable", !o.best_effort)
      .add("eos", eos)
      .str();
}

// Publishes for --duration at --rate (or as fast as the reliable transport
// accepts), then the end-of-stream marker. Returns the messages sent.
struct PubResult {
  uint64_t sent = 0;
  double seconds = 0;
};

PubResult publish(const PerfOptions& o, transport::Sink& sink, Transport& t) {
  const std::string payload(o.size, 'x');  // one buffer for the whole run (DDS strings cannot hold NUL)
  const int64_t t0 = now_ns();
  const int64_t deadline = t0 + secs_ns(o.duration);
  const double interval = o.rate > 0 ? 1e9 / o.rate : 0;
  int64_t next_report = t0 + secs_ns(o.report_interval > 0 ? o.report_interval : 1e6);
  uint64_t seq = 0, last_seq = 0;
  int64_t last_t = t0;
  for (;;) {
    int64_t t = now_ns();
    if (interval > 0) {
      const int64_t due = t0 + static_cast<int64_t>(seq * interval);
      if (due > t) {
        if (due >= deadline) break;
        sink.idle();  // what write batching holds goes out before the pause
        std::this_thread::sleep_until(at_ns(due));
        t = now_ns();
      }
    }
    if (t >= deadline || stop_now(o)) break;
    sink.put(payload, ++seq);
    if (o.report_interval > 0 && t >= next_report) {
      const double dt = (t - last_t) / 1e9;
      std::fprintf(stderr, "rvc perf pub: %7.2f s  %10.0f msg/s  %9.2f Mbit/s  sent %llu\n", (t - t0) / 1e9,
                   (seq - last_seq) / dt, (seq - last_seq) * o.size * 8 / dt / 1e6,
                   static_cast<unsigned long long>(seq));
      last_t = t;
      last_seq = seq;
      next_report += secs_ns(o.report_interval);
    }
  }
  const double seconds = (now_ns() - t0) / 1e9;
  sink.put_eos(seq);
  sink.flush();
  return {seq, seconds};
}

bool wait_writer_matched(const PerfOptions& o, transport::Sink& sink, const std::string& uri) {
  std::fprintf(stderr, "rvc perf: waiting for a subscriber on %s ...\n", uri.c_str());
  if (sink.wait_matched(1, secs_ms(o.timeout))) return true;
  std::fprintf(stderr, "rvc perf: no subscriber matched on %s within %.1f s (--timeout)\n", uri.c_str(), o.timeout);
  return false;
}

// ---------------------------------------------------------------- latency

constexpr std::size_t kRing = 1 << 16;  // send times of the last 65536 pings

struct PingState {
  const PerfOptions* o = nullptr;
  transport::Sink* sink = nullptr;
  std::string payload;
  std::unique_ptr<std::atomic<int64_t>[]> sent_ns{new std::atomic<int64_t>[kRing]};
  std::atomic<uint64_t> next_seq{0}, outstanding{0}, pongs{0}, last_pong{0};
  std::atomic<uint64_t> window_count{0}, window_sum_ns{0};
  std::atomic<bool> running{true};
  std::atomic<int64_t> record_from{0};
  std::vector<uint32_t> rtts;  // written by the transport thread only; read after stop()
  bool chain = false;          // max rate: the pong callback sends the next ping itself
  std::mutex mu;
  std::condition_variable cv;

  void send() {
    const uint64_t seq = next_seq.fetch_add(1) + 1;
    sent_ns[seq & (kRing - 1)].store(now_ns(), std::memory_order_relaxed);
    outstanding.store(seq);
    sink->put(payload, seq);
  }

  void on_pong(const Frame& f) {
    if (f.eos || f.seq == 0 || f.seq > next_seq.load()) return;
    const int64_t t = now_ns();
    const int64_t sent = sent_ns[f.seq & (kRing - 1)].load(std::memory_order_relaxed);
    const int64_t rtt = t - sent;
    if (rtt > 0 && rtt < 4'000'000'000LL && sent >= record_from.load(std::memory_order_relaxed)) {
      rtts.push_back(static_cast<uint32_t>(rtt));
      window_count.fetch_add(1, std::memory_order_relaxed);
      window_sum_ns.fetch_add(static_cast<uint64_t>(rtt), std::memory_order_relaxed);
    }
    pongs.fetch_add(1, std::memory_order_relaxed);
    if (chain) {
      last_pong.store(f.seq);
      if (running.load() && f.seq == outstanding.load()) send();
      return;
    }
    {
      std::lock_guard lock(mu);
      last_pong.store(f.seq);
    }
    cv.notify_all();
  }

  // Waits until the pong of `seq` is back (or `deadline`).
  bool wait_pong(uint64_t seq, int64_t deadline) {
    std::unique_lock lock(mu);
    return cv.wait_until(lock, at_ns(deadline), [&] { return last_pong.load() >= seq; });
  }
};

void print_ping_progress(const PerfOptions& o, PingState& p, int64_t t0, int64_t t) {
  const uint64_t n = p.window_count.exchange(0);
  const uint64_t sum = p.window_sum_ns.exchange(0);
  std::fprintf(stderr, "rvc perf ping: %7.2f s  %8llu round trips  mean one-way %9.2f us\n", (t - t0) / 1e9,
               static_cast<unsigned long long>(n), n ? sum / 2.0 / n / 1e3 : 0.0);
  (void)o;
}

// Sends pings for --duration: at --rate, or (rate 0) one at a time, each as
// soon as the previous pong is back. Returns pings sent.
uint64_t run_pings(const PerfOptions& o, PingState& p) {
  const int64_t t0 = now_ns();
  const int64_t deadline = t0 + secs_ns(o.duration);
  p.record_from.store(t0 + secs_ns(o.warmup));
  const int64_t report = secs_ns(o.report_interval > 0 ? o.report_interval : 1e6);
  int64_t next_report = t0 + report;
  auto progress = [&](int64_t t) {
    if (o.report_interval > 0 && t >= next_report) {
      print_ping_progress(o, p, t0, t);
      next_report += report;
    }
  };
  if (o.rate > 0) {
    const double interval = 1e9 / o.rate;
    for (uint64_t k = 0;; ++k) {
      const int64_t due = t0 + static_cast<int64_t>(k * interval);
      if (due >= deadline || stop_now(o)) break;
      if (due > now_ns()) std::this_thread::sleep_until(at_ns(due));
      p.send();
      progress(now_ns());
    }
  } else if (p.chain) {
    // The pong callback keeps the ball rolling; this thread only restarts it
    // when a round trip got lost (best effort) and reports progress.
    p.send();
    uint64_t seen = 0;
    int64_t seen_at = now_ns();
    for (;;) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      const int64_t t = now_ns();
      if (t >= deadline || stop_now(o)) break;
      const uint64_t n = p.pongs.load();
      if (n != seen) {
        seen = n;
        seen_at = t;
      } else if (t - seen_at > 1'000'000'000) {
        p.send();  // lost ping or pong: start again
        seen_at = t;
      }
      progress(t);
    }
  } else {
    // In-process pong: the callback may run inside our own put(), so the
    // next ping is sent from here, never from the callback.
    for (;;) {
      const int64_t t = now_ns();
      if (t >= deadline || stop_now(o)) break;
      p.send();
      p.wait_pong(p.next_seq.load(), std::min(deadline, now_ns() + 1'000'000'000));
      progress(t);
    }
  }
  p.running.store(false);
  const uint64_t sent = p.next_seq.load();
  // Give the last pongs a moment (bounded) to come back.
  const int64_t grace = now_ns() + 1'000'000'000;
  while (p.last_pong.load() < sent && now_ns() < grace) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  return p.next_seq.load();
}

}  // namespace

double parse_rate(const std::string& text) {
  std::string t;
  for (char c : text) t += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (t == "max" || t == "inf" || t == "0") return 0;
  double mult = 1;
  auto strip = [&](std::string_view suffix, double m) {
    if (t.size() > suffix.size() && t.compare(t.size() - suffix.size(), suffix.size(), suffix) == 0) {
      t.resize(t.size() - suffix.size());
      mult = m;
      return true;
    }
    return false;
  };
  strip("khz", 1e3) || strip("hz", 1) || strip("k", 1e3);
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (t.empty() || end != t.c_str() + t.size() || !(v > 0) || !std::isfinite(v))
    throw std::invalid_argument("--rate must be a positive number of messages per second (10, 1k, 2.5kHz) or 'max', not '" +
                                text + "'");
  return v * mult;
}

std::size_t parse_size(const std::string& text) {
  std::string t;
  for (char c : text) t += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  double mult = 1;
  for (auto [suffix, m] : {std::pair<std::string_view, double>{"kib", 1024}, {"mib", 1048576}, {"kb", 1024},
                           {"mb", 1048576}, {"k", 1024}, {"m", 1048576}, {"b", 1}}) {
    if (t.size() > suffix.size() && t.compare(t.size() - suffix.size(), suffix.size(), suffix) == 0) {
      t.resize(t.size() - suffix.size());
      mult = m;
      break;
    }
  }
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  const double bytes = v * mult;
  if (t.empty() || end != t.c_str() + t.size() || !(bytes >= 1) || bytes > 256.0 * 1048576 ||
      bytes != std::floor(bytes))
    throw std::invalid_argument("--size must be a whole number of bytes from 1 to 256 MiB (64, 4k, 1MiB), not '" +
                                text + "'");
  return static_cast<std::size_t>(bytes);
}

LatencyStats latency_stats(std::vector<uint32_t>& rtt_ns) {
  LatencyStats s;
  s.count = rtt_ns.size();
  if (rtt_ns.empty()) return s;
  std::sort(rtt_ns.begin(), rtt_ns.end());
  const double n = static_cast<double>(rtt_ns.size());
  auto one_way_us = [](uint32_t rtt) { return rtt / 2.0 / 1e3; };
  auto pct = [&](double q) {
    auto rank = static_cast<std::size_t>(std::ceil(q * n));
    rank = std::clamp<std::size_t>(rank, 1, rtt_ns.size());
    return one_way_us(rtt_ns[rank - 1]);
  };
  double sum = 0;
  for (uint32_t v : rtt_ns) sum += v;
  s.mean_us = sum / n / 2.0 / 1e3;
  s.min_us = one_way_us(rtt_ns.front());
  s.p50_us = pct(0.50);
  s.p90_us = pct(0.90);
  s.p99_us = pct(0.99);
  s.max_us = one_way_us(rtt_ns.back());
  return s;
}

int run_sub(const PerfOptions& o) {
  Transport t(o);
  auto src = t.reader(o.name, /*counting_only=*/true);
  SubCounter s;
  s.warmup_ns = secs_ns(o.warmup);
  src->start([&s](const Frame& f) { s.on_frame(f); });
  std::fprintf(stderr, "rvc perf sub: ready on %s\n", t.uri(o.name).c_str());
  const bool got = follow_subscription(o, s, "sub");
  src->stop();
  std::printf("%s\n", sub_json(o, "sub", s, 0).c_str());
  std::fflush(stdout);
  if (!got) return kNoPeer;
  return (!o.best_effort && s.c.gaps > 0) ? kLost : kOk;
}

int run_pub(const PerfOptions& o) {
  Transport t(o);
  SubCounter s;
  s.warmup_ns = secs_ns(o.warmup);
  std::unique_ptr<transport::Source> local;
  if (o.inproc) {
    local = t.reader(o.name, /*counting_only=*/true);
    local->start([&s](const Frame& f) { s.on_frame(f); });
  }
  auto sink = t.writer(o.name);
  if (!wait_writer_matched(o, *sink, t.uri(o.name))) return kNoPeer;
  std::fprintf(stderr, "rvc perf pub: %zu-byte messages at %s for %.1f s on %s%s\n", o.size,
               o.rate > 0 ? (std::to_string(o.rate) + " Hz").c_str() : "max rate", o.duration, t.uri(o.name).c_str(),
               o.inproc ? " (subscriber in this process)" : "");
  const PubResult r = publish(o, *sink, t);
  if (o.inproc) {
    if (!s.wait_eos_until(now_ns() + secs_ns(o.timeout)))
      std::fprintf(stderr, "rvc perf pub: in-process subscriber saw no end of stream within %.1f s\n", o.timeout);
    local->stop();
    std::printf("%s\n", sub_json(o, "inproc", s, r.sent).c_str());
    std::fflush(stdout);
    return (!o.best_effort && s.c.gaps > 0) ? kLost : kOk;
  }
  const double mps = r.seconds > 0 ? r.sent / r.seconds : 0;
  io::JsonObject js;
  js.add("role", "pub").add("transport", o.transport).add("size", o.size);
  add_rate(js, o.rate);
  js.add_fixed("msgs_per_s", mps, 1)
      .add_fixed("mbps", mps * o.size * 8 / 1e6, 3)
      .add_raw("lost", "null")  // a publisher cannot know: see the subscriber's line
      .add("sent", r.sent)
      .add_raw("received", "null")
      .add_fixed("seconds", r.seconds, 6)
      .add("reliable", !o.best_effort);
  std::printf("%s\n", js.str().c_str());
  std::fflush(stdout);
  return kOk;
}

int run_pong(const PerfOptions& o) {
  Transport t(o);
  auto sink = t.writer(o.name + "/pong");
  auto src = t.reader(o.name + "/ping");
  SubCounter s;  // counts pings; its end of stream ends the pong
  transport::Sink* out = sink.get();
  src->start([&s, out](const Frame& f) {
    // The end of the pings ends the pongs too (so a bridge in between can
    // see both directions end).
    if (f.eos)
      out->put_eos(f.seq);
    else
      out->put(f.payload, f.seq);
    s.on_frame(f);
  });
  std::fprintf(stderr, "rvc perf pong: ready on %s, answering on %s\n", t.uri(o.name + "/ping").c_str(),
               t.uri(o.name + "/pong").c_str());
  PerfOptions quiet = o;
  quiet.report_interval = 0;
  const bool got = follow_subscription(quiet, s, "pong");
  src->stop();
  sink->flush();
  const uint64_t n = s.c.received;
  std::printf("%s\n", io::JsonObject()
                          .add("role", "pong")
                          .add("transport", o.transport)
                          .add_fixed("size", n ? static_cast<double>(s.bytes.load()) / n : static_cast<double>(o.size), 0)
                          .add("echoed", n)
                          .str()
                          .c_str());
  std::fflush(stdout);
  return got ? kOk : kNoPeer;
}

int run_ping(const PerfOptions& o) {
  Transport t(o);
  // In-process pong: same session/participant, created first.
  std::unique_ptr<transport::Sink> pong_sink;
  std::unique_ptr<transport::Source> pong_src;
  if (o.inproc) {
    pong_sink = t.writer(o.name + "/pong");
    pong_src = t.reader(o.name + "/ping");
    transport::Sink* out = pong_sink.get();
    pong_src->start([out](const Frame& f) {
      if (!f.eos) out->put(f.payload, f.seq);
    });
  }
  auto src = t.reader(o.name + "/pong");
  auto sink = t.writer(o.name + "/ping");
  PingState p;
  p.o = &o;
  p.sink = sink.get();
  p.payload.assign(o.size, 'x');
  p.chain = o.rate <= 0 && !o.inproc;
  p.rtts.reserve(o.rate > 0 ? static_cast<std::size_t>(std::min(o.rate * o.duration * 1.1 + 1024, 16e6))
                            : std::size_t{1} << 21);
  src->start([&p](const Frame& f) { p.on_pong(f); });
  if (!wait_writer_matched(o, *sink, t.uri(o.name + "/ping"))) return kNoPeer;
  if (!t.reader_matched(*src, secs_ms(o.timeout))) {
    std::fprintf(stderr, "rvc perf ping: no pong writer matched within %.1f s\n", o.timeout);
    return kNoPeer;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let both directions' routes settle
  std::fprintf(stderr, "rvc perf ping: %zu-byte pings at %s for %.1f s on %s\n", o.size,
               o.rate > 0 ? (std::to_string(o.rate) + " Hz").c_str() : "max rate", o.duration,
               t.uri(o.name + "/ping").c_str());
  const uint64_t sent = run_pings(o, p);
  sink->put_eos(sent);
  sink->flush();
  src->stop();
  if (pong_src) pong_src->stop();
  const uint64_t back = p.pongs.load();
  LatencyStats st = latency_stats(p.rtts);
  io::JsonObject js;
  js.add("role", "ping").add("transport", o.transport).add("size", o.size);
  add_rate(js, o.rate);
  js.add("count", st.count)
      .add("sent", sent)
      .add("lost", sent > back ? sent - back : 0)
      .add_fixed("mean_us", st.mean_us, 3)
      .add_fixed("min_us", st.min_us, 3)
      .add_fixed("p50_us", st.p50_us, 3)
      .add_fixed("p90_us", st.p90_us, 3)
      .add_fixed("p99_us", st.p99_us, 3)
      .add_fixed("max_us", st.max_us, 3)
      .add("reliable", !o.best_effort);
  std::printf("%s\n", js.str().c_str());
  std::fflush(stdout);
  if (back == 0) return kNoPeer;
  return kOk;
}

}  // namespace rvc::perf
