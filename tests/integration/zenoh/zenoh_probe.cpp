// rvc_zenoh_probe: a test driver for the Python interop tests, exercising the
// same code paths the rvc subcommands use (make_zenoh_source/sink,
// run_zenoh_router, add_zenoh_options). To be replaced by `rvc monitor`,
// `rvc replay` and `rvc router` once those exist.
//
//   rvc_zenoh_probe sub    --key K [zenoh flags] [--max N] [--timeout S]
//       prints "READY <zid>" once subscribed, then one line per sample:
//       "DATA <seq> <hex payload>" or "EOS <seq>"; exits 0 after EOS (or N
//       data samples), 3 if --timeout seconds pass first.
//   rvc_zenoh_probe pub    --key K --count N [--prefix P] [--wait N]
//       [--no-seq] [--no-eos] [zenoh flags]
//       waits for N matching subscribers (prints "MATCHED"), publishes
//       P1..PN with seq 1..N, then EOS with seq N; prints "DONE". Exit 2 if
//       no subscriber shows up within --match-timeout seconds.
//   rvc_zenoh_probe router [zenoh flags]   until SIGINT/SIGTERM
#include <CLI/CLI.hpp>
#include <atomic>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <string>

#include "cli/transport_flags.hpp"
#include "transport/zenoh/zenoh_endpoint.hpp"

using namespace rvc::transport;
using namespace rvc::cli;  // add_*_options: the transports' flags

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

std::string hex(std::string_view s) {
  static const char* d = "0123456789abcdef";
  std::string out;
  out.reserve(s.size() * 2);
  for (unsigned char c : s) {
    out.push_back(d[c >> 4]);
    out.push_back(d[c & 15]);
  }
  return out;
}

int run_sub(const std::string& key, const ZenohOptions& zo, uint64_t max, double timeout_s) {
  std::mutex mu;
  std::condition_variable cv;
  uint64_t data = 0;
  bool done = false;
  auto source = make_zenoh_source(key, zo);
  source->start([&](const Frame& f) {
    std::lock_guard lock(mu);
    if (done) return;
    if (f.eos) {
      std::printf("EOS %llu\n", static_cast<unsigned long long>(f.seq));
      done = true;
    } else {
      std::printf("DATA %llu %s\n", static_cast<unsigned long long>(f.seq), hex(f.payload).c_str());
      done = max > 0 && ++data >= max;
    }
    std::fflush(stdout);
    if (done) cv.notify_all();
  });
  std::printf("READY %s\n", ZenohSession::shared(zo)->zid().c_str());
  std::fflush(stdout);
  std::unique_lock lock(mu);
  const bool ok = cv.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] { return done; });
  lock.unlock();
  source->stop();
  return ok ? 0 : 3;
}

int run_pub(const std::string& key, const ZenohOptions& zo, uint64_t count,
            const std::string& prefix, size_t wait_n, double match_timeout_s, bool no_seq,
            bool no_eos) {
  auto sink = make_zenoh_sink(key, zo);
  const auto timeout = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::duration<double>(match_timeout_s));
  if (!sink->wait_matched(wait_n, timeout)) {
    std::fprintf(stderr, "probe pub: no matching subscriber\n");
    return 2;
  }
  std::printf("MATCHED\n");
  std::fflush(stdout);
  auto* zsink = dynamic_cast<ZenohSink*>(sink.get());
  for (uint64_t i = 1; i <= count; ++i) {
    const std::string payload = prefix + std::to_string(i);
    if (no_seq)
      zsink->publisher().put(payload);  // plain sample, no attachment
    else
      sink->put(payload, i);
  }
  if (!no_eos) sink->put_eos(count);
  sink->flush();
  sink.reset();  // last user: closes the session, which flushes
  std::printf("DONE\n");
  std::fflush(stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rvc Zenoh test probe"};
  app.require_subcommand(1);
  ZenohOptions sub_o, pub_o, router_o;
  std::string sub_key, pub_key, prefix = "msg-";
  uint64_t max = 0, count = 10;
  double timeout_s = 60, match_timeout_s = 60;
  size_t wait_n = 1;
  bool no_seq = false, no_eos = false, verbose = false;
  app.add_flag("-v,--verbose", verbose, "Zenoh logs (RUST_LOG) to stderr");

  auto* sub = app.add_subcommand("sub", "subscribe and print samples");
  sub->add_option("--key", sub_key)->required();
  sub->add_option("--max", max, "exit after this many data samples");
  sub->add_option("--timeout", timeout_s, "give up after this many seconds");
  add_zenoh_options(*sub, sub_o);

  auto* pub = app.add_subcommand("pub", "publish numbered samples");
  pub->add_option("--key", pub_key)->required();
  pub->add_option("--count", count);
  pub->add_option("--prefix", prefix);
  pub->add_option("--wait", wait_n, "subscribers to wait for");
  pub->add_option("--match-timeout", match_timeout_s);
  pub->add_flag("--no-seq", no_seq, "send no attachment");
  pub->add_flag("--no-eos", no_eos, "send no end-of-stream marker");
  add_zenoh_options(*pub, pub_o);

  auto* router = app.add_subcommand("router", "run a Zenoh router");
  add_zenoh_options(*router, router_o);

  CLI11_PARSE(app, argc, argv);
  try {
    if (verbose) zenoh_init_logging("info");
    if (*sub) return run_sub(sub_key, sub_o, max, timeout_s);
    if (*pub) return run_pub(pub_key, pub_o, count, prefix, wait_n, match_timeout_s, no_seq, no_eos);
    // Only the router stops gracefully; pub/sub die on the default signals.
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    return run_zenoh_router(router_o, g_stop);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "probe: %s\n", e.what());
    return 1;
  }
}
