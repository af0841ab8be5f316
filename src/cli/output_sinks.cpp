#include "cli/output_sinks.hpp"

#include <chrono>
#include <cstdio>

#include "cli/commands.hpp"

namespace rvc::cli {

int open_outputs(const std::vector<std::string>& uris, const transport::TransportOptions& transports,
                 size_t wait_subscribers, double wait_timeout, const char* who,
                 std::vector<std::unique_ptr<transport::Sink>>& sinks) {
  for (const auto& uri : uris) sinks.push_back(transport::open_sink(uri, transports));
  for (size_t i = 0; i < sinks.size() && wait_subscribers > 0; ++i) {
    if (transport::scheme_of(uris[i]) == "file" || transport::scheme_of(uris[i]) == "mcap") continue;  // no subscribers
    std::fprintf(stderr, "rvc %s: waiting for %zu subscriber%s on %s ...\n", who, wait_subscribers,
                 wait_subscribers == 1 ? "" : "s", uris[i].c_str());
    if (!sinks[i]->wait_matched(wait_subscribers, std::chrono::milliseconds(static_cast<long>(wait_timeout * 1000)))) {
      std::fprintf(stderr, "rvc: no subscriber matched on %s within %.1f s (--wait-timeout)\n", uris[i].c_str(),
                   wait_timeout);
      if (!sinks[i]->discovery().empty())
        std::fprintf(stderr, "rvc: this publisher: %s\n", sinks[i]->discovery().c_str());
      return kIncomplete;
    }
  }
  return 0;
}

int refuse_input_copies(const std::vector<std::string>& outputs, const std::string& input) {
  for (const auto& uri : outputs)
    if (uri.rfind("mcap:", 0) == 0 && (uri.ends_with("?inputs=1") || uri.ends_with("?inputs=true"))) {
      std::fprintf(stderr,
                   "rvc: %s copies the messages of a ROS 2 bag (rvc check BAG, --input bag:BAG); the messages of %s "
                   "are not copied: drop ?inputs=1 (docs/mcap-output.md)\n",
                   uri.c_str(), input.c_str());
      return kUsage;
    }
  return 0;
}

}  // namespace rvc::cli
