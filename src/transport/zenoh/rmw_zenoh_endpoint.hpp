// rmw_zenoh: endpoints: ROS 2 topics of a system running rmw_zenoh_cpp, read
// and written over rvc's Zenoh session (formats: rmw_zenoh_format.hpp).
//   source  subscribes to <domain>/<topic>/<DDS type or *>/*: CDR payloads,
//           loss counted per publisher GID from rmw_zenoh's attachment
//   sink    publishes JSON text as std_msgs/msg/String with rmw_zenoh's
//           attachment and a node + publisher liveliness token, so `ros2
//           topic list/echo` on an rmw_zenoh system sees it
//   graph   the entities announced by liveliness tokens (rvc topics)
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "transport/endpoint.hpp"
#include "transport/zenoh/rmw_zenoh_format.hpp"
#include "transport/zenoh/zenoh_options.hpp"

namespace rvc::transport {

int rmw_zenoh_domain(const RmwZenohOptions& ropts);

std::unique_ptr<Source> make_rmw_zenoh_source(const std::string& topic, const ZenohOptions& opts,
                                              const RmwZenohOptions& ropts);
std::unique_ptr<Sink> make_rmw_zenoh_sink(const std::string& topic, const ZenohOptions& opts,
                                          const RmwZenohOptions& ropts);

// Every entity of the domain announced now. Peers are found by scouting or
// --connect after the session opens, so the query is repeated until it finds
// something (then once more, as answers trickle in) or `wait` runs out.
// Tokens of another layout are skipped (counted in *skipped when given).
std::vector<rmw_zenoh::Entity> rmw_zenoh_graph(const ZenohOptions& opts, int domain, std::chrono::milliseconds wait,
                                               std::size_t* skipped = nullptr);

// The ROS type (pkg/msg/Name) of `topic`'s publishers (or, with none, its
// subscriptions) in the graph. Throws std::invalid_argument naming what was
// found when there is no single type. `keep_session` (if given) holds the
// session open, so the endpoint opened next shares it instead of opening a
// second one (peers would meet it anew: samples put meanwhile could be missed).
std::string rmw_zenoh_topic_type(const std::string& topic, const ZenohOptions& opts, const RmwZenohOptions& ropts,
                                 std::chrono::milliseconds wait, std::shared_ptr<void>* keep_session = nullptr);

}  // namespace rvc::transport
