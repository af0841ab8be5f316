#include "cli/type_options.hpp"

#include <chrono>
#include <cstdio>
#include <stdexcept>

#ifdef RVC_HAVE_ZENOH
#include "transport/zenoh/rmw_zenoh_endpoint.hpp"
#endif

namespace rvc::cli {

void TypeOptions::add_to(CLI::App& app, const std::string& type_help) {
  type_option = app.add_option("--type", type, type_help)->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_option("--msg-path", msg_paths,
                 "Folder of .msg/.idl definitions for --type (a ROS 2 share/ tree or a plain folder), or one .idl file (repeatable)");
}

const msg::MessageType* TypeOptions::resolve(transport::TransportOptions& transports) {
  if (type.empty()) return nullptr;
  for (const auto& p : msg_paths) registry.add_search_path(p);
  const msg::MessageType* t = &registry.resolve(type);
#ifdef RVC_HAVE_ZENOH
  transports.rmw_zenoh.ros_type = type;  // subscribe to this type's key only
#endif
#ifdef RVC_HAVE_DDS
  transports.dds.ros_type = t;
#endif
  (void)transports;
  return t;
}

void TypeOptions::infer_from_graph(const std::string& uri, const transport::TransportOptions& transports) {
  if (!type.empty() || transport::scheme_of(uri) != "rmw_zenoh") return;
#ifdef RVC_HAVE_ZENOH
  const std::string topic = uri.substr(uri.find(':') + 1);
  type = transport::rmw_zenoh_topic_type(topic, transports.zenoh, transports.rmw_zenoh, std::chrono::seconds(3),
                                         &graph_session);
  std::fprintf(stderr, "rvc: %s: type %s (announced in the ROS 2 graph)\n", uri.c_str(), type.c_str());
#else
  (void)transports;
  throw std::invalid_argument("this rvc was built without the zenoh transport (RVC_WITH_ZENOH=OFF)");
#endif
}

bool TypeOptions::typed_scheme(const std::string& uri) {
  const std::string scheme = transport::scheme_of(uri);
  return scheme == "dds" || scheme == "zenoh" || scheme == "rmw_zenoh";
}

}  // namespace rvc::cli
