// How an rvc process joins a Zenoh network, as set on the command line.
// Without a config file rvc's defaults find each other on one host and keep
// everything on loopback: peers listen on tcp/127.0.0.1:0, routers on
// tcp/127.0.0.1:7447, and multicast scouting runs on the loopback interface
// only (224.0.0.224:7446 via lo). See docs/zenoh.md.
#pragma once

#include <string>
#include <vector>

namespace rvc::transport {

struct ZenohOptions {
  std::string mode = "peer";         // peer | client | router
  std::vector<std::string> connect;  // endpoints such as tcp/127.0.0.1:7447
  std::vector<std::string> listen;   // empty = default for the mode (see above)
  // -1: the default — on, confined to the loopback interface, without a
  // config file; the file's own setting with one. 1: on (lo). 0: off.
  int multicast_scouting = -1;
  std::string config_file;  // JSON5 Zenoh config; explicit flags override it
  // With a config file, its mode is kept unless --mode was given.
  bool mode_explicit = false;
  bool express = false;  // publishers: send each sample at once, no batching
};

// rmw_zenoh: endpoints (ROS 2 over rmw_zenoh_cpp, docs/zenoh.md): what the
// data key needs beyond the topic. Kept apart from ZenohOptions, which keys
// the shared sessions.
struct RmwZenohOptions {
  int domain = -1;       // -1: ROS_DOMAIN_ID (unset: 0)
  std::string ros_type;  // pkg/msg/Name from --type or the graph; empty: any type on the topic
};

}  // namespace rvc::transport
