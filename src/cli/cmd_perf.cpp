// rvc perf pub|sub|ping|pong: throughput and latency of the Zenoh and DDS
// transports (src/tools/perf, docs/perf.md). Other DDS programs (ddsperf)
// join the same pinned network with the XML of `rvc dds-config`.
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "cli/transport_flags.hpp"
#include "cli/signals.hpp"
#include "tools/perf/perf.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

struct PerfRole {
  perf::PerfOptions opts;
  std::string size = "64";
  std::string rate = "max";
};

struct PerfCommand {
  std::map<std::string, PerfRole> roles;
  std::map<std::string, CLI::App*> apps;

  int run(CLI::App* perf) {
    for (auto& [name, app] : apps) {
      if (!perf->got_subcommand(app)) continue;
      PerfRole& r = roles[name];
      r.opts.size = perf::parse_size(r.size);
      r.opts.rate = perf::parse_rate(r.rate);
      if (r.opts.duration < 0 || r.opts.timeout <= 0 || r.opts.idle_timeout <= 0)
        throw std::invalid_argument("--duration must be >= 0, --timeout and --idle-timeout > 0");
      if (r.opts.write_batch && (r.opts.transport != "dds" || r.opts.rate > 0))
        throw std::invalid_argument("--write-batch needs --transport dds and --rate max");
      if ((name == "pub" || name == "ping") && r.opts.duration <= 0)
        throw std::invalid_argument("rvc perf " + name + ": --duration must be > 0");
      // A DDS publisher at --rate max packs samples into packets, as ddsperf
      // does (--no-dds-write-batch: one packet per sample; --dds-config decides for itself).
#ifdef RVC_HAVE_DDS
      auto& dds = r.opts.transports.dds;
      if (name == "pub" && r.opts.rate <= 0 && !dds.write_batch && dds.config_file.empty()) dds.write_batch = true;
#endif
      install_stop_signals();
      r.opts.should_stop = [] { return stop_requested(); };
      if (name == "pub") return perf::run_pub(r.opts);
      if (name == "sub") return perf::run_sub(r.opts);
      if (name == "ping") return perf::run_ping(r.opts);
      return perf::run_pong(r.opts);
    }
    std::fprintf(stderr, "rvc perf: give a mode: pub, sub, ping or pong (rvc perf --help)\n");
    return kUsage;
  }
};

void add_role(PerfCommand& cmd, CLI::App& perf, const std::string& name, const std::string& description) {
  PerfRole& r = cmd.roles[name];
  const bool sender = name == "pub" || name == "ping";
  r.opts.duration = sender ? 5 : 0;
  CLI::App* s = perf.add_subcommand(name, description);
  cmd.apps[name] = s;
  s->add_option("--transport,-t", r.opts.transport, "zenoh or dds")
      ->check(CLI::IsMember({"zenoh", "dds"}))
      ->capture_default_str();
  s->add_option("--key,--topic", r.opts.name,
                "Zenoh key / DDS topic (ping/pong use NAME/ping and NAME/pong)")
      ->capture_default_str();
  s->add_flag("--best-effort", r.opts.best_effort,
              "Zenoh: congestion control Drop instead of Block; DDS: best-effort instead of reliable");
  if (name != "sub" && name != "pong") {
    s->add_option("--size", r.size, "Payload bytes per message (suffixes k, M = KiB, MiB)")->capture_default_str();
    s->add_option("--rate", r.rate, name == "ping" ? "Pings per second, or max (next ping when the pong is back)"
                                                   : "Messages per second, or max")
        ->capture_default_str();
    s->add_option("--duration", r.opts.duration, "Seconds to send for")
        ->check(above_up_to(0, kMaxSeconds, "seconds"))
        ->capture_default_str();
    s->add_flag("--inproc", r.opts.inproc,
                name == "ping" ? "Answer the pings in this process (same session/participant)"
                               : "Subscribe in this process (same session/participant) and report its counts");
  } else {
    s->add_option("--duration", r.opts.duration,
                  "Stop this many seconds after the first message (default 0: at the end-of-stream marker)")
        ->check(in_range(0, kMaxSeconds, "seconds"))
        ->capture_default_str();
    s->add_option("--idle-timeout", r.opts.idle_timeout, "Stop when nothing arrived for this many seconds")
        ->check(above_up_to(0, kMaxSeconds, "seconds"))
        ->capture_default_str();
  }
  if (name == "pub")
    s->add_flag("--write-batch", r.opts.write_batch,
                "DDS at max rate: CycloneDDS write batching (several samples per packet, as ddsperf does); the default, "
                "kept for scripts (--no-dds-write-batch turns it off)");
  if (name == "ping")
    s->add_option("--warmup", r.opts.warmup, "Round trips sent in the first S seconds are not counted")
        ->check(in_range(0, kMaxSeconds, "seconds"))
        ->capture_default_str();
  if (name == "sub" || name == "pub")
    s->add_option("--warmup", r.opts.warmup,
                  name == "sub" ? "msgs_per_s leaves out the first S seconds after the first message"
                                : "With --inproc: msgs_per_s leaves out the first S seconds")
        ->check(in_range(0, kMaxSeconds, "seconds"))
        ->capture_default_str();
  s->add_option("--timeout", r.opts.timeout, "Seconds to wait for a peer (match or first message)")
      ->check(above_up_to(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  s->add_option("--report-interval", r.opts.report_interval, "Progress line period on stderr (0 = none)")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  add_transport_options(*s, r.opts.transports);
}

}  // namespace

Runner register_perf(CLI::App& app) {
  auto cmd = std::make_shared<PerfCommand>();
  CLI::App* perf = app.add_subcommand(
      "perf", "Measure transport throughput (pub/sub) and latency (ping/pong); one JSON summary line on stdout");
  perf->require_subcommand(1);
  add_role(*cmd, *perf, "pub", "Publish fixed-size messages carrying sequence numbers");
  add_role(*cmd, *perf, "sub", "Count messages/s, Mbit/s and lost messages (by sequence number)");
  add_role(*cmd, *perf, "ping", "Send pings, report one-way latency = round trip / 2");
  add_role(*cmd, *perf, "pong", "Answer pings");
  return [cmd, perf] { return cmd->run(perf); };
}

}  // namespace rvc::cli
