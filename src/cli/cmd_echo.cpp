// rvc echo: print what arrives on an endpoint as JSON lines, the `ros2 topic
// echo` of rvc. With --type, samples are ROS 2 CDR (a dds: topic of that type,
// or a zenoh: key as zenoh-bridge-ros2dds forwards it) decoded from the
// message definition; without, payloads are printed as they are (rvc's JSON
// strings). Ends after --count messages, at the end-of-stream marker, after
// --idle-timeout seconds without a message, or on SIGINT/SIGTERM.
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "cli/option_rules.hpp"
#include "cli/signals.hpp"
#include "cli/transport_flags.hpp"
#include "io/cdr_codec.hpp"
#include "cli/type_options.hpp"
#include "msg/type_registry.hpp"
#include "runtime/check_bag.hpp"
#include "transport/frame_queue.hpp"
#include "transport/rosbag2/bag_reader.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

struct EchoCommand {
  transport::TransportOptions transports;
  std::string input;
  TypeOptions typed;  // --type, --msg-path
  uint64_t count = 0;        // 0: no limit
  double idle_timeout = 0;   // 0: none
  std::vector<std::string> fields;  // --field: only these paths of a typed sample
  std::string topic;                // --topic: of a bag

  // --field a.b.c: each part a field of the message the previous one names.
  static bool select(const msg::MessageType& type, const std::string& path, io::CdrSelection& selection) {
    std::vector<std::string> parts;
    size_t start = 0;
    for (size_t dot; (dot = path.find('.', start)) != std::string::npos; start = dot + 1)
      parts.push_back(path.substr(start, dot - start));
    parts.push_back(path.substr(start));
    const msg::MessageType* holder = &type;
    for (const auto& part : parts) {
      const msg::Field* found = nullptr;
      if (holder)
        for (const auto& f : holder->fields)
          if (f.name == part) found = &f;
      if (!found) {
        std::string names;
        if (holder)
          for (const auto& f : holder->fields) names += (names.empty() ? "" : ", ") + f.name;
        std::fprintf(stderr, "rvc: --field %s: no field '%s' in %s%s%s\n", path.c_str(), part.c_str(),
                     holder ? holder->full_name().c_str() : "a field that is no message",
                     holder ? "; its fields: " : "", names.c_str());
        return false;
      }
      holder = found->type.prim == msg::Prim::Message && found->type.array == msg::ArrayKind::None
                   ? found->type.message
                   : nullptr;
    }
    selection.add(parts);
    return true;
  }

  // The bag a bag:/mcap: URI, a .mcap/.db3 file or a bag folder names; "" for other inputs.
  std::string bag_path() const {
    const std::string scheme = transport::scheme_of(input);
    if (scheme == "mcap") return input.substr(input.find(':') + 1);
    if (scheme != "file" || input == "-") return "";
    const std::string path = input.rfind("file:", 0) == 0 ? input.substr(5) : input;
    return transport::is_bag(path) ? path : "";
  }

  // Writes one line to stdout; false (after saying so) when stdout fails.
  static bool put_line(std::string_view line) {
    if (std::fwrite(line.data(), 1, line.size(), stdout) == line.size() && std::fputc('\n', stdout) != EOF) return true;
    std::fprintf(stderr, "rvc: cannot write to stdout: %s\n", std::strerror(errno));
    return false;
  }

  // A bag's topic, in the bag's order: each message as `rvc echo` prints a
  // live sample of the type the bag records (same decoder, same JSON).
  int run_bag(const std::string& path) {
    if (typed.given()) {
      std::fprintf(stderr, "rvc: a bag names the type of each topic itself: drop --type\n");
      return kUsage;
    }
    for (const auto& dir : typed.msg_paths) typed.registry.add_search_path(dir);
    const runtime::BagInput in = runtime::select_bag_topic(path, topic, typed.registry);
    io::CdrSelection selection;
    if (!fields.empty() && !in.type) {
      std::fprintf(stderr, "rvc: --field selects fields of typed samples; topic %s carries JSON\n", in.topic.c_str());
      return kUsage;
    }
    for (const auto& f : fields)
      if (!select(*in.type, f, selection)) return kUsage;
    install_stop_signals();
    transport::BagReadOptions read;  // the default cap; the other topics' compressed messages stay so
    read.topics = {in.topic};
    auto reader = transport::open_bag(path, read);
    uint64_t printed = 0, rejected = 0;
    reader->on_skip([&](const std::string& why) {
      if (++rejected <= 100) std::fprintf(stderr, "rvc: bag '%s': %s\n", path.c_str(), why.c_str());
    });
    transport::BagMessage m;
    std::string json;
    try {
      while (!stop_requested() && (count == 0 || printed < count) && reader->next(m)) {
        if (m.topic != in.topic) continue;
        std::string_view line = m.data;
        if (in.type) {
          io::CdrError error;
          json.clear();
          if (!io::cdr_to_json(*in.type, m.data, json, error, fields.empty() ? nullptr : &selection)) {
            if (++rejected <= 100)
              std::fprintf(stderr, "rvc: message %llu: not a %s: %s (skipped)\n",
                           static_cast<unsigned long long>(m.index), in.type->full_name().c_str(),
                           error.to_string().c_str());
            continue;
          }
          line = json;
        }
        if (!put_line(line)) return kRuntime;
        ++printed;
      }
    } catch (const transport::BagError& e) {  // cut short: what came before was printed
      std::fprintf(stderr, "rvc: %s (the messages before it were printed)\n", e.what());
      ++rejected;
    }
    if (std::fflush(stdout) != 0) {
      std::fprintf(stderr, "rvc: cannot write to stdout: %s\n", std::strerror(errno));
      return kRuntime;
    }
    if (rejected > 0) {
      if (printed == 0) runtime::hint_bag_definition(in);
      std::fprintf(stderr, "rvc echo: %llu message%s of the bag could not be read or decoded\n",
                   static_cast<unsigned long long>(rejected), rejected == 1 ? "" : "s");
      return kBadInput;
    }
    return printed == 0 ? kIncomplete : kOk;
  }

  int run() {
    if (const std::string bag = bag_path(); !bag.empty()) return run_bag(bag);
    if (transport::scheme_of(input) == "file" && input != "-")
      if (const std::string path = input.rfind("file:", 0) == 0 ? input.substr(5) : input;
          !transport::truncated_bag(path).empty()) {
        std::fprintf(stderr, "rvc: bag '%s' is %s\n", path.c_str(), transport::truncated_bag(path).c_str());
        return kUsage;
      }
    if (!topic.empty()) {
      std::fprintf(stderr, "rvc: --topic chooses a topic of a bag (bag:PATH, a .mcap or .db3 file, a bag folder)\n");
      return kUsage;
    }
    if (transport::scheme_of(input) == "file" && input != "-") {  // a file's lines are printed as they are
      const std::string path = input.rfind("file:", 0) == 0 ? input.substr(5) : input;
      if (const std::string what = transport::binary_signature(path); !what.empty()) {
        std::fprintf(stderr, "rvc: input '%s' is %s, not JSON lines\n", path.c_str(), what.c_str());
        return kUsage;
      }
    }
    if (typed.given() && !TypeOptions::typed_scheme(input)) {
      std::fprintf(stderr, "rvc: --type reads dds:, rmw_zenoh: or zenoh: inputs; for CDR in a file use `rvc msg decode`\n");
      return kUsage;
    }
    try {
      typed.infer_from_graph(input, transports);  // rmw_zenoh: without --type
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: %s\n", e.what());
      return kUsage;
    }
    const msg::MessageType* ros_type = typed.resolve(transports);
    io::CdrSelection selection;
    if (!fields.empty() && !ros_type) {
      std::fprintf(stderr, "rvc: --field selects fields of typed samples: give --type too\n");
      return kUsage;
    }
    for (const auto& path : fields)
      if (!select(*ros_type, path, selection)) return kUsage;
    transport::FrameQueue queue(1024);
    auto source = transport::open_source(input, transports);
    install_stop_signals();
    source->start([&](const transport::Frame& f) { queue.push(f); });

    std::vector<transport::OwnedFrame> batch;
    std::string json;
    uint64_t printed = 0, rejected = 0;
    bool eos = false, failed_write = false;
    auto last = std::chrono::steady_clock::now();
    while (!stop_requested() && !eos && (count == 0 || printed < count)) {
      size_t n = 0;
      if (!queue.pop_batch(batch, n, 100)) break;
      const auto now = std::chrono::steady_clock::now();
      if (n == 0) {
        if (idle_timeout > 0 && std::chrono::duration<double>(now - last).count() >= idle_timeout) break;
        continue;
      }
      last = now;
      for (size_t i = 0; i < n && (count == 0 || printed < count); ++i) {
        const auto& f = batch[i];
        if (f.eos) {
          eos = true;
          break;
        }
        std::string_view line = f.payload;
        if (ros_type) {
          io::CdrError error;
          json.clear();  // cdr_to_json appends
          if (!io::cdr_to_json(*ros_type, f.payload, json, error, fields.empty() ? nullptr : &selection)) {
            if (++rejected <= 100)
              std::fprintf(stderr, "rvc: sample %llu: not a %s: %s (skipped)\n", static_cast<unsigned long long>(f.seq),
                           ros_type->full_name().c_str(), error.to_string().c_str());
            continue;
          }
          line = json;
        }
        if (std::fwrite(line.data(), 1, line.size(), stdout) != line.size() || std::fputc('\n', stdout) == EOF) {
          failed_write = true;
          break;
        }
        ++printed;
      }
      if (failed_write || std::fflush(stdout) != 0) {
        std::fprintf(stderr, "rvc: cannot write to stdout: %s\n", std::strerror(errno));
        source->stop();
        queue.close();
        return kRuntime;
      }
    }
    source->stop();
    queue.close();
    if (rejected > 0) {
      std::fprintf(stderr, "rvc echo: %llu sample%s could not be decoded\n", static_cast<unsigned long long>(rejected),
                   rejected == 1 ? "" : "s");
      return kBadInput;
    }
    if (printed == 0) {
      const std::string why = source->diagnosis();  // a publisher with incompatible QoS, say
      if (!why.empty()) std::fprintf(stderr, "rvc: nothing was received on %s; %s\n", input.c_str(), why.c_str());
    }
    return printed == 0 ? kIncomplete : kOk;
  }
};

}  // namespace

Runner register_echo(CLI::App& app) {
  auto cmd = std::make_shared<EchoCommand>();
  CLI::App* sub = app.add_subcommand("echo", "Print the messages of an endpoint or a ROS 2 bag's topic as JSON lines (typed ROS 2 topics with --type)");
  sub->add_option("input", cmd->input, "Endpoint: dds:TOPIC, rmw_zenoh:TOPIC (type from the ROS 2 graph), zenoh:KEYEXPR, file:PATH, or a ROS 2 bag (bag:PATH, a .mcap or .db3 file, a bag folder)")->required();
  cmd->typed.add_to(*sub, "Message type of the samples: ROS 2 pkg/msg/Name (`rvc msg list`) or a DDS IDL name from --msg-path");
  sub->add_option("--field", cmd->fields,
                  "Print only this field of each typed sample, e.g. status.twist (repeatable; the rest is still "
                  "checked)")
      ->check(field_name());
  sub->add_option("--topic", cmd->topic, "The topic of a bag to print (needed when the bag holds several)");
  sub->add_option("--count,-n", cmd->count, "Stop after this many messages (default: no limit)")
      ->check(in_range(0, kMaxCount, "messages (0: no limit)"));
  sub->add_option("--idle-timeout", cmd->idle_timeout, "Stop after this many seconds without a message")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->footer("Exit status: 0 messages printed, 3 samples could not be decoded (or records of a bag were damaged), 5 stdout could not be written, "
              "6 nothing arrived.");
  add_transport_options(*sub, cmd->transports);
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
