// --type and --msg-path, as every typed subcommand (monitor, echo, replay,
// bridge) takes them: the ROS 2 type of the samples, found in the given
// folders or the bundled definitions, and handed to the DDS transport so its
// topics carry that type.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

#include "msg/type_registry.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {

struct TypeOptions {
  std::string type;                    // pkg/msg/Name; empty: JSON payloads
  std::vector<std::string> msg_paths;  // --msg-path
  msg::TypeRegistry registry;          // owns the resolved type
  CLI::Option* type_option = nullptr;  // every --type given, in order (several inputs: one each)
  std::shared_ptr<void> graph_session;  // the session the graph was read with, kept for the input

  // `type_help` says what the type applies to in this subcommand.
  void add_to(CLI::App& app, const std::string& type_help);
  bool given() const { return !type.empty(); }
  // The type (null without --type); sets it as the DDS topics' type in
  // `transports`. Throws msg::MsgError for an unknown type or bad definition.
  const msg::MessageType* resolve(transport::TransportOptions& transports);
  // An rmw_zenoh: input without --type: the type its publishers announce in
  // the ROS 2 graph (liveliness tokens), printed to stderr. Does nothing for
  // other inputs or when --type was given. Throws std::invalid_argument when
  // the graph names no single type.
  void infer_from_graph(const std::string& uri, const transport::TransportOptions& transports);
  // Whether a typed endpoint can be `uri`: dds: and rmw_zenoh: topics, zenoh: keys.
  static bool typed_scheme(const std::string& uri);
};

}  // namespace rvc::cli
