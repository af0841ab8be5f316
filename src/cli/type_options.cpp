#include "cli/type_options.hpp"

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
#ifdef RVC_HAVE_DDS
  transports.dds.ros_type = t;
#else
  (void)transports;
#endif
  return t;
}

bool TypeOptions::typed_scheme(const std::string& uri) {
  const std::string scheme = transport::scheme_of(uri);
  return scheme == "dds" || scheme == "zenoh";
}

}  // namespace rvc::cli
