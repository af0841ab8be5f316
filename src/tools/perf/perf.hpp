// rvc perf: throughput and latency of rvc's transports, measured through the
// same C++ classes rvc monitor/replay use (ZenohSink/ZenohSource over one
// Zenoh session, DdsSink/DdsSource on rvc's loopback-pinned participant).
//
//   pub/sub    fixed-size payloads carrying a sequence number; the subscriber
//              reports msg/s, Mbit/s and lost messages (by sequence number)
//   ping/pong  round trips at a set rate (or as fast as they come back);
//              ping reports one-way latency = RTT / 2 (mean, min, p50, p90,
//              p99, max), like ddsperf
//
// Every run ends with one JSON line on stdout; progress goes to stderr.
// Design notes, wire formats and the comparison with ddsperf: docs/perf.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "transport/transport_options.hpp"

namespace rvc::perf {

struct PerfOptions {
  std::string transport = "zenoh";  // zenoh | dds
  std::size_t size = 64;            // payload bytes per message
  double rate = 0;                  // messages (pings) per second; 0 = as fast as possible
  double duration = 5;              // seconds of publishing (pub, ping); sub/pong: 0 = until end of stream
  std::string name = "rvc_perf";    // key (Zenoh) / topic (DDS); ping/pong use NAME/ping and NAME/pong
  bool best_effort = false;         // Zenoh: congestion control Drop; DDS: best-effort reliability
  bool inproc = false;              // pub/ping: run the subscriber/pong in this process too
  // DDS pub at max rate: CycloneDDS Internal/WriteBatch (several samples per
  // packet, as ddsperf does). rvc perf pub --rate max has it on anyway
  // (transports.dds.write_batch, unless --no-dds-write-batch).
  bool write_batch = false;
  double timeout = 30;              // hang guard: waiting for a match or the first message
  double idle_timeout = 3;          // sub/pong: stop when nothing arrived for this long
  // ping: round trips sent in the first S seconds are not counted; sub (and
  // pub --inproc): msgs_per_s starts S seconds after the first message
  double warmup = 0;
  double report_interval = 1;       // progress line period on stderr (0 = none)
  transport::TransportOptions transports;
  std::function<bool()> should_stop;  // polled: true ends the run early (signals)
};

// Each returns a process exit code (0 ok, 2 no match / nothing received,
// 4 messages lost with reliable delivery) and prints the JSON summary.
int run_pub(const PerfOptions& o);
int run_sub(const PerfOptions& o);
int run_ping(const PerfOptions& o);
int run_pong(const PerfOptions& o);

// "max" -> 0; "10", "1k", "2.5kHz", "1e4" -> Hz. Throws std::invalid_argument.
double parse_rate(const std::string& text);
// "64", "1k"/"1KiB" (1024), "1M"/"1MiB" (1048576). Throws std::invalid_argument.
std::size_t parse_size(const std::string& text);

// Latency summary of round-trip times (nanoseconds): one-way = RTT / 2.
struct LatencyStats {
  std::size_t count = 0;
  double mean_us = 0, min_us = 0, p50_us = 0, p90_us = 0, p99_us = 0, max_us = 0;
};
// Sorts `rtt_ns` in place. Percentiles are nearest-rank (ceil(q * n)).
LatencyStats latency_stats(std::vector<uint32_t>& rtt_ns);

}  // namespace rvc::perf
