// rvc replay: publish a JSON-lines trace, one message per line, with
// sequence numbers and an end-of-stream marker, at a fixed rate or as fast as
// the (reliable) transport accepts. Waits for subscribers first, so nothing
// sent before discovery completes is lost.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <vector>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "cli/transport_flags.hpp"
#include "cli/signals.hpp"
#include "io/cdr_codec.hpp"
#include "io/json_writer.hpp"
#include "cli/type_options.hpp"
#include "msg/type_registry.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

struct ReplayCommand {
  transport::TransportOptions transports;
  std::string file;
  std::string to;
  std::string rate = "max";
  size_t wait_subscribers = 1;
  double wait_timeout = 10;
  bool no_eos = false;
  bool progress = true;
  size_t batch = 1;          // messages (lines) per published sample
  std::string latency_from;  // verdict endpoint of a monitor run with --all: measure publish -> verdict
  TypeOptions typed;         // --type: each line is a message of this ROS 2 type, published as CDR
  bool big_endian = false;

  static double wall_now() {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  }

  int run() {
    double hz = 0;
    if (rate != "max") {
      try {
        hz = std::stod(rate);
      } catch (...) {
        hz = -1;
      }
      if (!(hz > 0)) {
        std::fprintf(stderr, "rvc: --rate must be a positive number of messages per second or 'max', not '%s'\n",
                     rate.c_str());
        return kUsage;
      }
    }
    if (typed.given()) {
      if (!TypeOptions::typed_scheme(to) || transport::scheme_of(to) == "rmw_zenoh") {
        std::fprintf(stderr, "rvc: --type publishes typed samples to dds: or zenoh: endpoints (rmw_zenoh: outputs "
                             "carry JSON as std_msgs/String); for CDR in a file use `rvc msg encode`\n");
        return kUsage;
      }
      if (batch > 1) {
        std::fprintf(stderr, "rvc: --type publishes one message per sample: --batch cannot be used with it\n");
        return kUsage;
      }
    }
    const msg::MessageType* ros_type = typed.resolve(transports);
    std::FILE* in = file == "-" ? stdin : std::fopen(file.c_str(), "r");
    if (!in) {
      std::fprintf(stderr, "rvc: cannot open '%s'\n", file.c_str());
      return kUsage;
    }
    // Closed on every way out (no subscriber, a sink that throws).
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> in_owner(in != stdin ? in : nullptr, &std::fclose);
    long total_bytes = 0;
    if (in != stdin && std::fseek(in, 0, SEEK_END) == 0) {
      total_bytes = std::ftell(in);
      std::rewind(in);
    }
    // DDS: one UDP packet per sample cost ~5 us of CPU each and bounded the
    // replay at ~0.18 M samples/s; packed (CycloneDDS WriteBatch, flushed
    // before every pause and at the end) ~0.9 M/s. A --dds-config file decides.
#ifdef RVC_HAVE_DDS
    if (!transports.dds.write_batch && transports.dds.config_file.empty()) transports.dds.write_batch = true;
#endif
    auto sink = transport::open_sink(to, transports);
    install_stop_signals();
    // Latency: with `rvc monitor --all`, verdict k answers message k. We note
    // when each message left and when its verdict came back.
    std::vector<std::chrono::steady_clock::time_point> sent_at;
    std::vector<double> latency_us;
    std::mutex latency_mutex;
    std::atomic<uint64_t> verdicts_back{0};
    std::unique_ptr<transport::Source> echo;
    if (!latency_from.empty()) {
      sent_at.reserve(1 << 20);
      // The handler only notes a time: DDS may call it on its receive thread
      // (one thread wake-up less per verdict than a waitset thread).
      transport::TransportOptions echo_opts = transports;
#ifdef RVC_HAVE_DDS
      echo_opts.dds.deliver_on_receive_thread = true;
#endif
      echo = transport::open_source(latency_from, echo_opts);
      echo->start([&](const transport::Frame& f) {
        if (f.eos) return;
        auto now = std::chrono::steady_clock::now();
        uint64_t k = ++verdicts_back;
        std::lock_guard<std::mutex> lock(latency_mutex);
        if (k <= sent_at.size())
          latency_us.push_back(std::chrono::duration<double, std::micro>(now - sent_at[k - 1]).count());
      });
    }
    if (wait_subscribers > 0) {
      std::fprintf(stderr, "rvc replay: waiting for %zu subscriber%s on %s ...\n", wait_subscribers,
                   wait_subscribers == 1 ? "" : "s", to.c_str());
      if (!sink->wait_matched(wait_subscribers, std::chrono::milliseconds(static_cast<long>(wait_timeout * 1000)))) {
        std::fprintf(stderr, "rvc: no subscriber matched on %s within %.1f s (--wait-timeout; --wait-subscribers 0 to not wait)\n",
                     to.c_str(), wait_timeout);
        if (!sink->discovery().empty()) std::fprintf(stderr, "rvc: this publisher: %s\n", sink->discovery().c_str());
        return kIncomplete;
      }
    }
    const bool show = progress && isatty(2);
    // Freed on every way out: a sink that cannot write throws (exit 5).
    char* line = nullptr;
    size_t cap = 0;
    struct FreeLine {
      char*& p;
      ~FreeLine() { std::free(p); }
    } free_line{line};  // getline may move the buffer: free whatever it holds last
    ssize_t n;
    uint64_t seq = 0;
    long bytes = 0;
    auto t0 = std::chrono::steady_clock::now();
    const double started_at = wall_now();
    auto next_progress = t0;
    uint64_t events = 0, samples = 0, rejected = 0, line_no = 0;
    std::string cdr, cdr_error;
    io::CdrWriteOptions cdr_options;
    cdr_options.big_endian = big_endian;
    std::string pending;  // --batch: lines waiting to go out as one sample
    size_t pending_lines = 0;
    auto send = [&](std::string_view payload) {
      ++samples;
      if (echo) {
        std::lock_guard<std::mutex> lock(latency_mutex);
        sent_at.push_back(std::chrono::steady_clock::now());
      }
      sink->put(payload, samples);
    };
    bool interrupted = false;
    while (!(interrupted = stop_requested()) && (n = ::getline(&line, &cap, in)) >= 0) {
      bytes += n;
      ++line_no;
      size_t len = static_cast<size_t>(n);
      while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) --len;
      if (len == 0) continue;
      if (ros_type && !io::json_to_cdr(*ros_type, std::string_view(line, len), cdr, cdr_error, cdr_options)) {
        if (++rejected <= 100)
          std::fprintf(stderr, "rvc: line %llu: not a %s: %s (message skipped)\n",
                       static_cast<unsigned long long>(line_no), ros_type->full_name().c_str(), cdr_error.c_str());
        continue;
      }
      seq = events + 1;  // this message's number: counted as sent once it is sent
      // Wait for this message's slot in short steps, so that a stop signal
      // during the wait is seen before the message is sent.
      if (hz > 0) {
        const auto due = t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                  std::chrono::duration<double>(static_cast<double>(seq - 1) / hz));
        // What write batching holds goes out before a pause, not with the next message.
        if (std::chrono::steady_clock::now() < due) sink->idle();
        while (!stop_requested() && std::chrono::steady_clock::now() < due)
          std::this_thread::sleep_until(std::min(due, std::chrono::steady_clock::now() + std::chrono::milliseconds(20)));
        if (stop_requested()) {
          interrupted = true;
          break;
        }
      }
      ++events;
      if (ros_type) {
        send(cdr);
      } else if (batch <= 1) {
        send(std::string_view(line, len));
      } else {
        pending.append(line, len);
        pending.push_back('\n');
        if (++pending_lines == batch) {
          send(pending);
          pending.clear();
          pending_lines = 0;
        }
      }
      if (show && (seq & 1023) == 0) {
        auto now = std::chrono::steady_clock::now();
        if (now >= next_progress) {
          next_progress = now + std::chrono::milliseconds(200);
          double s = std::chrono::duration<double>(now - t0).count();
          if (total_bytes > 0)
            std::fprintf(stderr, "\r  %5.1f%%  %llu messages  %.0f msg/s   ", 100.0 * bytes / total_bytes,
                         static_cast<unsigned long long>(seq), seq / s);
          else
            std::fprintf(stderr, "\r  %llu messages  %.0f msg/s   ", static_cast<unsigned long long>(seq), seq / s);
        }
      }
    }
    if (!pending.empty()) send(pending);
    in_owner.reset();
    seq = samples;  // sequence numbers count samples
    if (!no_eos) sink->put_eos(samples);
    sink->flush();
    double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (show) std::fprintf(stderr, "\r%60s\r", "");
    std::fprintf(stderr, "rvc replay: sent %llu messages in %llu samples in %.3f s (%.0f msg/s) to %s\n",
                 static_cast<unsigned long long>(events), static_cast<unsigned long long>(samples), s,
                 s > 0 ? events / s : 0.0, to.c_str());
    std::optional<io::JsonObject> latency;
    size_t verdicts_back_n = 0;
    if (echo) {
      auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      while (verdicts_back < seq && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      echo->stop();
      std::lock_guard<std::mutex> lock(latency_mutex);
      std::sort(latency_us.begin(), latency_us.end());
      auto pct = [&](double q) {
        return latency_us.empty() ? 0.0 : latency_us[std::min(latency_us.size() - 1, static_cast<size_t>(q * latency_us.size()))];
      };
      latency = io::JsonObject()
                    .add("p50", pct(0.5))
                    .add("p90", pct(0.9))
                    .add("p99", pct(0.99))
                    .add("max", latency_us.empty() ? 0.0 : latency_us.back());
      verdicts_back_n = latency_us.size();
    }
    io::JsonObject summary;
    summary.add("sent", events)
        .add("samples", samples);
    if (ros_type) summary.add("rejected", rejected);
    summary
        .add_fixed("seconds", s, 6)
        .add_fixed("msgs_per_s", s > 0 ? events / s : 0.0, 1)
        .add_fixed("started_at", started_at, 6);
    if (latency) summary.add("verdicts_back", verdicts_back_n).add("latency_us", *latency);
    // The summary must not mix with the data when the data goes to stdout.
    std::FILE* out = transport::scheme_of(to) == "file" && (to == "-" || to == "file:-" || to == "file:/dev/stdout")
                         ? stderr
                         : stdout;
    std::fprintf(out, "%s\n", summary.str().c_str());
    if (rejected > 0) {
      std::fprintf(stderr, "rvc replay: %llu line%s could not be converted to %s and %s not sent\n",
                   static_cast<unsigned long long>(rejected), rejected == 1 ? "" : "s", ros_type->full_name().c_str(),
                   rejected == 1 ? "was" : "were");
    }
    if (interrupted) {
      std::fprintf(stderr, "rvc replay: stopped by a signal after %llu of the input's messages: incomplete\n",
                   static_cast<unsigned long long>(events));
      return kIncomplete;
    }
    return rejected > 0 ? kBadInput : kOk;
  }
};

}  // namespace

Runner register_replay(CLI::App& app) {
  auto cmd = std::make_shared<ReplayCommand>();
  CLI::App* sub = app.add_subcommand("replay", "Publish a JSON-lines trace to an endpoint, one message per line");
  sub->add_option("file", cmd->file, "Trace (JSON lines), or - for stdin")->required();
  sub->add_option("--to", cmd->to, "Endpoint: zenoh:KEYEXPR, dds:TOPIC, file:PATH")->required();
  sub->add_option("--rate", cmd->rate, "Messages per second, or max")->capture_default_str();
  sub->add_option("--wait-subscribers", cmd->wait_subscribers, "Subscribers to wait for before publishing")
      ->check(in_range(0, 100000))
      ->capture_default_str();
  sub->add_option("--wait-timeout", cmd->wait_timeout, "Seconds to wait for them")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  sub->add_flag("--no-eos", cmd->no_eos, "Do not send the end-of-stream marker");
  sub->add_option("--batch", cmd->batch,
                  "Messages per published sample (newline-separated; sequence numbers count samples)")
      ->capture_default_str()
      ->check(in_range(1, 1 << 20, "messages"));
  sub->add_flag("!--no-progress", cmd->progress, "No progress line on a terminal");
  sub->add_option("--latency-from", cmd->latency_from,
                  "Verdict endpoint of an `rvc monitor --all`: report publish-to-verdict latency percentiles");
  cmd->typed.add_to(*sub,
                  "ROS 2 message type of the lines, pkg/msg/Name: each line is converted to a CDR sample and published "
                  "typed (`rvc msg list`)");
  sub->add_flag("--big-endian", cmd->big_endian, "With --type: big-endian CDR (default: little endian)");
  add_transport_options(*sub, cmd->transports);
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
