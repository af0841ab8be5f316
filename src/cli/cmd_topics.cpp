// rvc topics: the topics of a running ROS 2 system on rmw_zenoh, from the
// liveliness tokens its nodes declare (the graph rmw_zenoh_cpp itself keeps):
// what `ros2 topic list` prints, with -t the types and with -v the publisher
// and subscription counts. ROS_DOMAIN_ID chooses the domain, as in ROS 2.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "cli/transport_flags.hpp"
#include "transport/zenoh/rmw_zenoh_endpoint.hpp"

namespace rvc::cli {
namespace {

struct TopicsCommand {
  transport::TransportOptions transports;
  std::string graph = "rmw_zenoh:";
  bool show_types = false, verbose = false;
  double wait = 2.0;  // seconds to wait for the graph's answers

  static std::string types_of(const transport::rmw_zenoh::TopicInfo& t) {
    std::string s;
    for (const auto& ty : t.types) s += (s.empty() ? "" : ", ") + ty;
    return "[" + s + "]";
  }

  int run() {
    if (graph != "rmw_zenoh:" && graph != "rmw_zenoh") {
      std::fprintf(stderr, "rvc topics: lists the ROS 2 graph of rmw_zenoh: (got '%s'; DDS topics: ros2 topic list)\n",
                   graph.c_str());
      return kUsage;
    }
    int domain = 0;
    std::vector<transport::rmw_zenoh::TopicInfo> topics;
    std::size_t skipped = 0;
    try {
      domain = transport::rmw_zenoh_domain(transports.rmw_zenoh);
      const auto entities = transport::rmw_zenoh_graph(
          transports.zenoh, domain, std::chrono::milliseconds(static_cast<long long>(wait * 1000)), &skipped);
      topics = transport::rmw_zenoh::graph_topics(entities);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc topics: %s\n", e.what());
      return kRuntime;
    }
    if (skipped > 0)
      std::fprintf(stderr, "rvc topics: %zu liveliness token%s under @ros2_lv/%d not in rmw_zenoh's layout (skipped)\n",
                   skipped, skipped == 1 ? "" : "s", domain);
    if (topics.empty()) {
      std::fprintf(stderr, "rvc topics: no ROS 2 topic announced on domain %d within %.1f s (is the system up, "
                           "ROS_DOMAIN_ID right, and rvc connected: --connect tcp/127.0.0.1:7447 for rmw_zenoh's router?)\n",
                   domain, wait);
      return kIncomplete;
    }
    if (verbose) {
      auto section = [&](const char* title, bool publishers) {
        std::printf("%s\n", title);
        for (const auto& t : topics) {
          const std::size_t n = publishers ? t.publishers : t.subscriptions;
          if (n == 0) continue;
          std::printf(" * %s %s %zu %s%s\n", t.topic.c_str(), types_of(t).c_str(), n,
                      publishers ? "publisher" : "subscriber", n == 1 ? "" : "s");
        }
        std::printf("\n");
      };
      section("Published topics:", true);
      section("Subscribed topics:", false);
    } else {
      for (const auto& t : topics)
        std::printf("%s%s%s\n", t.topic.c_str(), show_types ? " " : "", show_types ? types_of(t).c_str() : "");
    }
    return std::fflush(stdout) == 0 ? kOk : kRuntime;
  }
};

}  // namespace

Runner register_topics(CLI::App& app) {
  auto cmd = std::make_shared<TopicsCommand>();
  CLI::App* sub = app.add_subcommand("topics", "List the topics of a ROS 2 system on rmw_zenoh (its liveliness graph), "
                                               "like ros2 topic list");
  sub->add_option("graph", cmd->graph, "rmw_zenoh: (the default; the domain is ROS_DOMAIN_ID)");
  sub->add_flag("--show-types,-t", cmd->show_types, "Print each topic's type: /topic [pkg/msg/Name]");
  sub->add_flag("--verbose,-v", cmd->verbose, "Published and subscribed topics with their endpoint counts");
  sub->add_option("--wait", cmd->wait, "Seconds to wait for the graph's answers (default 2)")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->footer("Exit status: 0 topics listed, 5 Zenoh failed, 6 no topic announced within --wait.");
  add_zenoh_options(*sub, cmd->transports.zenoh);
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
