// rvc hz: a ready-made health check of N topics, what one reaches for instead
// of `ros2 topic hz` plus Autoware's topic_state_monitor. Per topic, over the
// last window_size arrivals: rate, inter-arrival jitter (std dev, min, max),
// silence since the last message and stamp latency (arrival - stamp); the
// topic_state_monitor state (runtime/topic_rate.hpp) from warn_rate,
// error_rate, timeout, window_size (cli/hz_config.hpp: flags and/or YAML).
//
// Output: a table every --period (--json: one object per topic per period),
// and with --diagnostics a diagnostic_msgs/DiagnosticArray (one status per
// topic) every period and at once whenever a topic's state changes. A topic
// that goes silent turns Timeout on a timer: the loop sleeps until the
// earliest timeout deadline, not until the next message.
//
// Time: arrivals are taken on the transport thread (steady clock for rate,
// jitter and silence; system clock for latency against ROS stamps). With
// --time-source stamps the messages' own time field is the clock instead
// (offline files, deterministic tests): reports fall on period boundaries of
// that time and "now" is the latest time read.
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/hz_arrivals.hpp"
#include "cli/hz_config.hpp"
#include "cli/hz_report.hpp"
#include "cli/option_ranges.hpp"
#include "cli/option_rules.hpp"
#include "cli/signals.hpp"
#include "cli/transport_flags.hpp"
#include "cli/type_options.hpp"
#include "io/cdr_decoder.hpp"
#include "io/diagnostics.hpp"
#include "io/json_writer.hpp"
#include "msg/type_registry.hpp"
#include "runtime/time_field_reader.hpp"
#include "runtime/topic_rate.hpp"
#include "transport/rosbag2/bag_reader.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

std::string number_text(double v) {
  if (!std::isfinite(v)) return v > 0 ? "inf" : "nan";
  char buf[64];
  auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, p);
}

struct HzTopic {
  HzTopicConfig config;
  const msg::MessageType* type = nullptr;
  std::unique_ptr<runtime::TimeFieldReader> arrival_field;  // --time-source stamps
  std::unique_ptr<runtime::TimeFieldReader> stamp_field;    // latency; null: none
  bool stamp_required = false;  // named explicitly: a message without it is rejected
  runtime::TopicRate stats;
  std::unique_ptr<transport::Source> source;
  uint64_t rejected = 0;
  bool ended = false;  // end-of-stream marker (files, rvc publishers)
  runtime::TopicState reported = runtime::TopicState::NotReceived;  // state last published

  explicit HzTopic(HzTopicConfig c) : config(std::move(c)), stats(config.thresholds) {}
  uint64_t received() const { return stats.received() + rejected; }
};

struct HzCommand {
  transport::TransportOptions transports;
  std::vector<std::string> inputs;
  std::string config_path;
  TypeOptions typed;
  std::string stamp_field;  // --stamp-field: for every topic without its own
  std::string time_source = "receive";
  std::string time_field = "time";
  HzFlagOverrides flags;
  double period = 1.0;
  bool json = false;
  std::vector<std::string> diagnostics;
  uint64_t count = 0;
  double duration = 0, idle_timeout = 0;

  std::vector<std::unique_ptr<HzTopic>> topics;
  std::vector<std::unique_ptr<transport::Sink>> diag_sinks;
  std::vector<bool> diag_is_file;  // files get the JSON form (a line), networks CDR
  bool stamps_mode() const { return time_source == "stamps"; }
  bool header_printed = false;
  uint64_t diag_published = 0;

  // The topics with their types and stamp readers; false after printing why.
  bool prepare() {
    for (const auto& p : typed.msg_paths) typed.registry.add_search_path(p);
    for (auto& config : hz_topics(config_path, inputs, flags)) {
      if (!readable_as_lines(config.uri)) return false;
      auto t = std::make_unique<HzTopic>(config);
      const std::string type_name = config.type.empty() ? typed.type : config.type;
      if (!type_name.empty()) {
        if (!TypeOptions::typed_scheme(config.uri)) {
          std::fprintf(stderr, "rvc: %s: a type (%s) applies to dds: and zenoh: topics; files hold JSON lines\n",
                       config.uri.c_str(), type_name.c_str());
          return false;
        }
        t->type = &typed.registry.resolve(type_name);
      }
      const std::string stamp = config.stamp_field.empty() ? stamp_field : config.stamp_field;
      if (stamps_mode()) {
        const std::string arrival =
            t->type ? io::CdrDecoder::default_time_field(*t->type, time_field) : time_field;
        t->arrival_field = field_reader(*t, arrival, "--time-field");
        if (!t->arrival_field) return false;
      }
      if (stamp == "none") {
        // no latency
      } else if (!stamp.empty()) {
        t->stamp_field = field_reader(*t, stamp, "stamp field");
        if (!t->stamp_field) return false;
        t->stamp_required = true;
      } else if (!stamps_mode()) {
        // Automatic: a typed topic's header.stamp (or stamp) if its type has
        // one; JSON's "time" where a message carries it.
        if (t->type) {
          const std::string guess = io::CdrDecoder::default_time_field(*t->type, "time");
          try {
            t->stamp_field = std::make_unique<runtime::TimeFieldReader>(guess, t->type);
          } catch (const msg::MsgError&) {  // no stamp in this type: no latency
          }
        } else {
          t->stamp_field = std::make_unique<runtime::TimeFieldReader>("time", nullptr);
        }
      }
      topics.push_back(std::move(t));
    }
    return true;
  }

  // A file input is JSON lines (or any text lines): a bag or another binary
  // file is refused by what its first bytes are, as rvc check and rvc echo
  // do, not counted as "lines" of bytes (a bag gave "received 3353, OK").
  static bool readable_as_lines(const std::string& uri) {
    if (transport::scheme_of(uri) != "file" || uri == "-") return true;
    const std::string path = uri.rfind("file:", 0) == 0 ? uri.substr(5) : uri;
    if (path == "-") return true;
    if (transport::is_bag(path)) {
      const std::string what = transport::binary_signature(path);
      std::fprintf(stderr,
                   "rvc hz: '%s' is a ROS 2 bag%s: rvc hz watches live topics and files of JSON lines; a bag's "
                   "topics, counts and rates: rvc bag info; its timing properties: rvc check (docs/bags.md)\n",
                   path.c_str(), what.empty() ? " folder" : (" (" + what + ")").c_str());
      return false;
    }
    if (const std::string what = transport::binary_signature(path); !what.empty()) {
      std::fprintf(stderr, "rvc hz: '%s' is %s, not JSON lines\n", path.c_str(), what.c_str());
      return false;
    }
    return true;
  }

  std::unique_ptr<runtime::TimeFieldReader> field_reader(const HzTopic& t, const std::string& field, const char* what) {
    try {
      return std::make_unique<runtime::TimeFieldReader>(field, t.type);
    } catch (const msg::MsgError&) {
      // (The decoder's own words speak of dense time and --time-field.)
      std::string fields;
      for (const auto& f : t.type->fields) fields += (fields.empty() ? "" : ", ") + f.name;
      std::fprintf(stderr, "rvc: %s: %s '%s' is no number or builtin_interfaces/Time field of %s (its fields: %s)\n",
                   t.config.uri.c_str(), what, field.c_str(), t.type->full_name().c_str(), fields.c_str());
      return nullptr;
    }
  }

  bool open_diagnostics() {
    transport::TransportOptions diag_transports = transports;
#ifdef RVC_HAVE_DDS
    diag_transports.dds.ros_type = &typed.registry.resolve(std::string(io::kDiagnosticArrayType));
    diag_transports.dds.qos = "reliable";
#endif
    for (const auto& uri : diagnostics) {
      for (const auto& t : topics)
        if (transport::reads_back(t->config.uri, uri)) {
          std::fprintf(stderr, "rvc: --diagnostics %s would be read back by the input %s\n", uri.c_str(),
                       t->config.uri.c_str());
          return false;
        }
      diag_sinks.push_back(transport::open_sink(uri, diag_transports));
      diag_is_file.push_back(transport::scheme_of(uri) == "file");
    }
    return true;
  }

  // One arrival into its topic's statistics; false if the message is refused.
  bool accept(HzTopic& t, const Arrival& a, double arrival) {
    std::string error;
    std::optional<double> latency;
    double stamp = 0;
    if (t.stamp_field) {
      switch (t.stamp_field->read(a.payload, stamp, error)) {
        case runtime::TimeFieldReader::Result::Ok:
          latency = (stamps_mode() ? arrival : a.wall) - stamp;
          break;
        case runtime::TimeFieldReader::Result::Missing:
          if (t.stamp_required) return refuse(t, error);
          break;
        case runtime::TimeFieldReader::Result::Malformed:
          // A typed sample that does not decode is no message of the topic;
          // an untyped payload that is no JSON (plain text on a String
          // topic) still arrived: without a stamp asked for, it counts.
          if (t.stamp_required || t.type) return refuse(t, error);
          break;
      }
    }
    t.stats.add(arrival, latency);
    return true;
  }

  bool refuse(HzTopic& t, const std::string& why) {
    if (++t.rejected <= 20)
      std::fprintf(stderr, "rvc hz: %s: message %llu refused: %s\n", t.config.uri.c_str(),
                   static_cast<unsigned long long>(t.received()), why.c_str());
    return false;
  }

  // --- reports ---------------------------------------------------------------

  std::vector<HzRow> rows() const {
    std::vector<HzRow> out;
    for (const auto& t : topics) out.push_back(HzRow{&t->config.uri, &t->stats, t->rejected});
    return out;
  }

  void report(double now, bool final) {
    if (json) {
      print_hz_json(stdout, rows(), now, final);
    } else {
      print_hz_table(stdout, rows(), now, final, !header_printed || final);
      header_printed = true;
    }
  }

  std::vector<io::DiagStatus> statuses(double now) {
    std::vector<io::DiagStatus> out;
    for (const HzRow& row : rows()) out.push_back(hz_status(row, now));
    for (auto& t : topics) t->reported = t->stats.state(now);
    return out;
  }

  // `stamp`: the header's time (seconds since the epoch, or the stamps' clock).
  void publish(double now, double stamp) {
    if (diag_sinks.empty()) {
      for (auto& t : topics) t->reported = t->stats.state(now);
      return;
    }
    const auto list = statuses(now);
    std::string cdr, json_line;
    for (size_t i = 0; i < diag_sinks.size(); ++i) {
      if (diag_is_file[i]) {
        if (json_line.empty()) json_line = io::diagnostic_array_json(stamp, list);
        diag_sinks[i]->put(json_line, diag_published + 1);
      } else {
        if (cdr.empty()) cdr = io::diagnostic_array_cdr(stamp, list);
        diag_sinks[i]->put(cdr, diag_published + 1);
      }
      diag_sinks[i]->flush();
    }
    ++diag_published;
  }

  bool state_changed(double now) const {
    return std::any_of(topics.begin(), topics.end(),
                       [&](const auto& t) { return t->stats.state(now) != t->reported; });
  }

  // --- files in time order ---------------------------------------------------
  //
  // With --time-source stamps and only files, the files are read here, on
  // this thread, merged by their time field (a k-way merge): the same files
  // give the same reports, however the threads would have raced. A line
  // whose time cannot be read goes first (it is refused when processed).
  struct Head {
    bool have = false, ended = false;
    Arrival arrival;
  };
  std::vector<Head> heads;
  bool merged() const { return !heads.empty(); }

  // The next arrival in time order into `out` (empty once every file ended).
  void pull_merged(std::vector<Arrival>& out) {
    out.clear();
    for (uint32_t i = 0; i < heads.size(); ++i) {
      Head& h = heads[i];
      while (!h.have && !h.ended && !stop_requested()) {
        transport::Frame f;
        const auto r = topics[i]->source->pull(f);
        if (r == transport::PullResult::End || (r == transport::PullResult::Frame && f.eos)) {
          h.ended = true;
        } else if (r == transport::PullResult::Frame) {
          h.arrival = Arrival{i, false, SteadyClock::now(), wall_seconds(), std::string(f.payload), std::nullopt};
          std::string error;
          double time = 0;
          if (topics[i]->arrival_field->read(h.arrival.payload, time, error) == runtime::TimeFieldReader::Result::Ok)
            h.arrival.time = time;
          h.have = true;
        }  // Wait: a pipe with nothing yet; ask again
      }
    }
    Head* first = nullptr;
    for (Head& h : heads)
      if (h.have && (!first || !h.arrival.time || (first->arrival.time && *h.arrival.time < *first->arrival.time))) {
        first = &h;
        if (!h.arrival.time) break;
      }
    if (first) {
      out.push_back(std::move(first->arrival));
      first->have = false;
      return;
    }
    for (uint32_t i = 0; i < heads.size(); ++i) topics[i]->ended = heads[i].ended;
  }

  // --- the loop --------------------------------------------------------------

  int run() {
    if (time_source != "receive" && time_source != "stamps") {
      std::fprintf(stderr, "rvc: --time-source must be receive or stamps, not '%s'\n", time_source.c_str());
      return kUsage;
    }
    if (!prepare() || !open_diagnostics()) return kUsage;
    for (auto& t : topics) {
      transport::TransportOptions per_input = transports;
#ifdef RVC_HAVE_DDS
      per_input.dds.ros_type = t->type;
#endif
      t->source = transport::open_source(t->config.uri, per_input);
    }
    install_stop_signals();
    ArrivalQueue queue(4096);
    if (stamps_mode() && std::all_of(topics.begin(), topics.end(), [](const auto& t) { return t->source->pullable(); }))
      heads.resize(topics.size());
    else
      for (uint32_t i = 0; i < topics.size(); ++i)
        topics[i]->source->start([&queue, i](const transport::Frame& f) { queue.push(i, f); });

    const auto start = SteadyClock::now();
    auto since_start = [&](SteadyClock::time_point p) { return std::chrono::duration<double>(p - start).count(); };
    auto to_point = [&](double s) {
      return start + std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(s));
    };
    const double kNever = std::numeric_limits<double>::infinity();
    double next_report = period;                            // receive: the steady clock's next report
    runtime::StampSchedule schedule(period);                // stamps: the messages' own
    double stamp_now = -kNever;                             // stamps: the latest time read
    double last_message = 0;                                // steady s, for --idle-timeout
    uint64_t total = 0;
    std::vector<Arrival> batch;
    bool finished = false;
    if (!stamps_mode()) publish(0, wall_seconds());  // every topic NotReceived: a monitor sees rvc hz is up

    while (!finished && !stop_requested()) {
      // Sleep until the earliest thing that can happen without a message: a
      // report, a topic's timeout (strictly after its deadline, hence the
      // millisecond), the end of --duration or --idle-timeout; at most 100
      // ms, to notice a stop signal.
      double wake = since_start(SteadyClock::now()) + 0.1;
      if (!stamps_mode()) {
        wake = std::min(wake, next_report);
        for (const auto& t : topics)
          if (auto at = t->stats.timeout_at(); at && t->reported != runtime::TopicState::Timeout)
            wake = std::min(wake, *at + 0.001);
      }
      if (duration > 0) wake = std::min(wake, duration);
      if (idle_timeout > 0) wake = std::min(wake, last_message + idle_timeout);
      if (merged()) pull_merged(batch);
      else queue.pop_until(to_point(wake), batch);

      for (const Arrival& a : batch) {
        HzTopic& t = *topics[a.input];
        if (a.eos) {
          t.ended = true;
          continue;
        }
        last_message = since_start(a.steady);
        double arrival = last_message;
        if (stamps_mode()) {
          std::string error;
          double time = a.time.value_or(0);
          const auto r = a.time ? runtime::TimeFieldReader::Result::Ok : t.arrival_field->read(a.payload, time, error);
          if (r != runtime::TimeFieldReader::Result::Ok) {
            refuse(t, error);
            ++total;
            continue;
          }
          if (t.stats.any() && time < t.stats.last_arrival()) {
            refuse(t, "time " + number_text(time) + " is before the previous message's " +
                          number_text(t.stats.last_arrival()) + " (--time-source stamps needs them in order)");
            ++total;
            continue;
          }
          // Reports due before this message see the topics as they were then.
          const double last = stamp_now;  // the latest time read before this message
          const runtime::StampSchedule::Step& due = schedule.step(time);
          for (double boundary : due.reports) {
            stamp_now = std::max(stamp_now, boundary);
            report(boundary, false);
            publish(boundary, boundary);
          }
          if (due.skipped > 0)  // a jump (a simulator reset): one report and one line, not one per period
            std::fprintf(stderr,
                         "rvc hz: %s: the stamps jumped by %s s (from %s to %s): the reports of the %s periods "
                         "in between are skipped\n",
                         t.config.uri.c_str(), number_text(time - last).c_str(), number_text(last).c_str(),
                         number_text(time).c_str(), number_text(due.skipped).c_str());
          stamp_now = std::max(stamp_now, time);
          arrival = time;
        }
        accept(t, a, arrival);
        ++total;
        if (count > 0 && total >= count) {
          finished = true;
          break;
        }
      }

      const double now_steady = since_start(SteadyClock::now());
      const double now = stamps_mode() ? stamp_now : now_steady;
      if (!stamps_mode() && now_steady >= next_report) {
        report(now, false);
        publish(now, wall_seconds());
        next_report += period * std::max(1.0, std::floor((now_steady - next_report) / period) + 1);
      } else if (state_changed(now) && (!stamps_mode() || stamp_now > -kNever)) {
        publish(now, stamps_mode() ? stamp_now : wall_seconds());  // Timeout as it happens, not at the next report
      }
      if (std::all_of(topics.begin(), topics.end(), [](const auto& t) { return t->ended; })) finished = true;
      if (duration > 0 && now_steady >= duration) finished = true;
      if (idle_timeout > 0 && now_steady - last_message >= idle_timeout) finished = true;
    }
    // Close first: a transport thread blocked on a full queue (a file read
    // ahead of --count) returns at once, so stop() can join it.
    queue.close();
    for (auto& t : topics) t->source->stop();

    const double now = stamps_mode() ? (stamp_now > -kNever ? stamp_now : 0) : since_start(SteadyClock::now());
    report(now, true);
    if (stamps_mode() ? stamp_now > -kNever : true) publish(now, stamps_mode() ? now : wall_seconds());
    return finish(now, total);
  }

  // The final line per topic (received = checked + rejected) and the exit status.
  int finish(double now, uint64_t total) {
    runtime::Outcome outcome;
    for (const auto& t : topics) {
      const runtime::TopicState state = t->stats.state(now);
      std::fprintf(stderr, "rvc hz: %s: received %llu (checked %llu, rejected %llu), final state %s\n",
                   t->config.uri.c_str(), static_cast<unsigned long long>(t->received()),
                   static_cast<unsigned long long>(t->stats.received()),
                   static_cast<unsigned long long>(t->rejected), runtime::to_string(state));
      if (runtime::diag_level(state) == io::DiagLevel::Error) outcome.violated = true;
      if (t->rejected > 0) outcome.rejected = true;
      if (t->received() == 0) {
        const std::string why = t->source->diagnosis();
        if (!why.empty()) std::fprintf(stderr, "rvc hz: %s: %s\n", t->config.uri.c_str(), why.c_str());
      }
    }
    if (std::ferror(stdout)) {
      std::fprintf(stderr, "rvc hz: cannot write the reports to stdout\n");
      return kRuntime;
    }
    uint64_t checked = 0;
    for (const auto& t : topics) checked += t->stats.received();
    if (checked == 0) {  // as every rvc run that checked nothing: not a success
      std::fprintf(stderr, "rvc hz: %s\n", total == 0 ? "nothing was received" : "every message was refused");
      return kIncomplete;
    }
    return outcome.exit_code();
  }
};

}  // namespace

// Bounds of rvc hz's own numbers (docs/cli.md, "Numeric options").
constexpr double kMaxRateHz = 1e9;
constexpr double kMaxWindow = 10000000;

Runner register_hz(CLI::App& app) {
  auto cmd = std::make_shared<HzCommand>();
  CLI::App* sub = app.add_subcommand(
      "hz", "Watch topics' rate, jitter, silence and stamp latency; topic_state_monitor states, /diagnostics");
  sub->add_option("inputs", cmd->inputs, "Endpoints: dds:TOPIC, zenoh:KEYEXPR, file:PATH (several: one row each)");
  sub->add_option("--config", cmd->config_path,
                  "YAML file: topics with warn_rate, error_rate, timeout, window_size, type, stamp_field (docs/cli.md)")
      ->check(CLI::ExistingFile);
  cmd->typed.add_to(*sub, "Message type of the dds:/zenoh: samples: ROS 2 pkg/msg/Name (else JSON payloads)");
  sub->add_option("--warn-rate", cmd->flags.warn_rate, "WarnRate below this rate, Hz (default 0: off)")
      ->check(in_range(0, kMaxRateHz, "Hz"));
  sub->add_option("--error-rate", cmd->flags.error_rate, "ErrorRate below this rate, Hz (default 0: off)")
      ->check(in_range(0, kMaxRateHz, "Hz"));
  sub->add_option("--timeout", cmd->flags.timeout, "Timeout after this many seconds without a message (default 1; 0: off)")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->add_option("--window", cmd->flags.window_size, "Arrivals the rate and jitter are computed over (default 10)")
      ->check(in_range(2, kMaxWindow, "arrivals"));
  sub->add_option("--stamp-field", cmd->stamp_field,
                  "Latency = arrival - this field (a number of seconds or a Time); none: no latency (default: "
                  "header.stamp or stamp of a typed message, \"time\" of JSON where present)")
      ->check(field_name());
  sub->add_option("--time-source", cmd->time_source,
                  "receive: arrival on this host's clock (default); stamps: the messages' --time-field is the clock")
      ->check(CLI::IsMember({"receive", "stamps"}));
  sub->add_option("--time-field", cmd->time_field, "With --time-source stamps: the field read as arrival time (default time)")
      ->check(field_name());
  sub->add_option("--period", cmd->period, "Seconds between reports and /diagnostics (default 1)")
      ->check(in_range(0.01, 3600, "seconds"));
  sub->add_flag("--json", cmd->json, "One JSON object per topic per period instead of the table");
  sub->add_option("--diagnostics", cmd->diagnostics,
                  "Publish diagnostic_msgs/DiagnosticArray here, e.g. dds:/diagnostics, zenoh:diagnostics "
                  "(CDR), file:PATH (JSON lines); repeatable");
  sub->add_option("--count,-n", cmd->count, "Stop after this many messages in all")
      ->check(in_range(0, kMaxCount, "messages (0: no limit)"));
  sub->add_option("--duration", cmd->duration, "Stop after this many seconds")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->add_option("--idle-timeout", cmd->idle_timeout, "Stop after this many seconds without any message")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->footer("Exit status: 0 every topic ended OK or WarnRate, 1 some topic ended NotReceived, ErrorRate or Timeout, "
              "3 messages were refused, 5 stdout could not be written, 6 nothing was checked.");
  add_transport_options(*sub, cmd->transports);
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
