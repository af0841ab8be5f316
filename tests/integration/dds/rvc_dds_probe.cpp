// Test driver for the dds: transport, used by the pytest interop tests until
// the rvc monitor/replay subcommands exist.
//   rvc_dds_probe config [DDS options]        print the generated CycloneDDS XML
//   rvc_dds_probe pub TOPIC [DDS options]     publish stdin lines (seq 1..N) + end-of-stream
//   rvc_dds_probe sub TOPIC [DDS options]     print frames as JSON lines until end-of-stream
// sub prints "READY" once subscribed, one {"seq","eos","payload_hex"} line per
// frame and finally {"counters":{...}} from SeqCounters. Exit codes: 0 ok,
// 1 usage/option error, 2 timed out (sub: no end-of-stream; pub: no reader).
#include <CLI/CLI.hpp>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <set>
#include <string>

#include "cli/transport_flags.hpp"
#include "transport/dds/dds_endpoint.hpp"
#include "transport/seq_counter.hpp"

using namespace rvc::transport;
using namespace rvc::cli;  // add_*_options: the transports' flags

namespace {

std::string hex(std::string_view s) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(s.size() * 2);
  for (unsigned char c : s) {
    out += digits[c >> 4];
    out += digits[c & 15];
  }
  return out;
}

int run_pub(const std::string& topic, const DdsOptions& opts, size_t wait_matched, int timeout_ms, bool eos,
            const std::set<uint64_t>& skip) {
  DdsSink sink(topic, opts);
  if (wait_matched > 0 && !sink.wait_matched(wait_matched, std::chrono::milliseconds(timeout_ms))) {
    std::fprintf(stderr, "rvc_dds_probe: no reader matched '%s' within %d ms\n", sink.dds_topic().c_str(), timeout_ms);
    return 2;
  }
  uint64_t seq = 0;
  std::string line;
  while (std::getline(std::cin, line)) {
    ++seq;
    if (skip.count(seq)) continue;  // simulate a message lost before DDS
    sink.put(line, seq);
  }
  if (eos) sink.put_eos(seq);
  sink.flush();
  std::printf("{\"written\":%llu,\"last_seq\":%llu}\n", static_cast<unsigned long long>(sink.written()),
              static_cast<unsigned long long>(seq));
  return 0;
}

int run_sub(const std::string& topic, const DdsOptions& opts, uint64_t max_frames, int timeout_ms) {
  DdsSource source(topic, opts);
  std::mutex mu;
  std::condition_variable cv;
  SeqCounters counters;
  uint64_t frames = 0;
  bool done = false;
  std::printf("READY %s\n", source.dds_topic().c_str());
  std::fflush(stdout);
  source.start([&](const Frame& f) {
    std::lock_guard lock(mu);
    if (done) return;
    if (f.eos) {
      counters.on_eos(f.seq);
      done = true;
    } else {
      counters.on_seq(f.seq);
      if (max_frames && ++frames >= max_frames) done = true;
    }
    std::printf("{\"seq\":%llu,\"eos\":%s,\"payload_hex\":\"%s\"}\n", static_cast<unsigned long long>(f.seq),
                f.eos ? "true" : "false", hex(f.payload).c_str());
    std::fflush(stdout);
    if (done) cv.notify_all();
  });
  bool finished;
  {
    std::unique_lock lock(mu);
    finished = cv.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return done; });
  }
  source.stop();
  std::printf("{\"counters\":{\"received\":%llu,\"gaps\":%llu,\"duplicates\":%llu,\"last_seq\":%llu}}\n",
              static_cast<unsigned long long>(counters.received), static_cast<unsigned long long>(counters.gaps),
              static_cast<unsigned long long>(counters.duplicates), static_cast<unsigned long long>(counters.last_seq));
  std::fflush(stdout);
  if (!finished) std::fprintf(stderr, "rvc_dds_probe: no end-of-stream within %d ms\n", timeout_ms);
  return finished ? 0 : 2;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rvc dds transport probe (tests only)"};
  app.require_subcommand(1);
  app.fallthrough();  // DDS options may follow the subcommand
  DdsOptions opts;
  add_dds_options(app, opts);
  std::string topic;
  int timeout_ms = 60000;
  size_t wait_matched = 1;
  bool no_eos = false;
  std::set<uint64_t> skip;
  uint64_t max_frames = 0;
  std::string out_file;

  auto* config = app.add_subcommand("config", "Print the generated CycloneDDS configuration");
  config->add_option("-o,--output", out_file, "Write to this file instead of stdout");
  auto* pub = app.add_subcommand("pub", "Publish stdin lines, then the end-of-stream marker");
  pub->add_option("topic", topic)->required();
  pub->add_option("--wait-matched", wait_matched, "Readers to wait for before publishing")->capture_default_str();
  pub->add_option("--timeout-ms", timeout_ms, "How long to wait for them")->capture_default_str();
  pub->add_flag("--no-eos", no_eos, "Do not publish the end-of-stream marker");
  pub->add_option("--skip", skip, "Sequence numbers to leave out (simulated upstream loss)");
  auto* sub = app.add_subcommand("sub", "Print received frames until the end-of-stream marker");
  sub->add_option("topic", topic)->required();
  sub->add_option("--max", max_frames, "Stop after this many data frames");
  sub->add_option("--timeout-ms", timeout_ms, "Give up after this long")->capture_default_str();

  try {
    app.parse(argc, argv);
    if (*config) {
      rvc::transport::dds::validate(opts);
      std::string xml = rvc::transport::dds::generated_config_xml(opts);
      if (out_file.empty()) {
        std::fputs(xml.c_str(), stdout);
      } else {
        FILE* f = std::fopen(out_file.c_str(), "w");
        if (!f || std::fputs(xml.c_str(), f) < 0 || std::fclose(f) != 0) {
          std::fprintf(stderr, "rvc_dds_probe: cannot write %s\n", out_file.c_str());
          return 1;
        }
      }
      return 0;
    }
    if (*pub) return run_pub(topic, opts, wait_matched, timeout_ms, !no_eos, skip);
    return run_sub(topic, opts, max_frames, timeout_ms);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rvc_dds_probe: %s\n", e.what());
    return 1;
  }
}
