// Command-line flags of the transports (CLI11), kept out of src/transport so
// the transports stay plain C++ with option structs: --mode/--connect/--listen/
// --(no-)multicast-scouting/--zenoh-config/--express for zenoh:, --domain/
// --partition/--qos/--dds-type/--dds-interface/--dds-peer/--dds-config/
// --dds-trace/--dds-write-batch/--no-ros2-names for dds:.
#pragma once

#include <CLI/CLI.hpp>

#include "transport/transport_options.hpp"

namespace rvc::cli {

// Every transport compiled in, each in its own help group.
void add_transport_options(CLI::App& app, transport::TransportOptions& options);
#ifdef RVC_HAVE_ZENOH
void add_zenoh_options(CLI::App& app, transport::ZenohOptions& options);
#endif
#ifdef RVC_HAVE_DDS
void add_dds_options(CLI::App& app, transport::DdsOptions& options);
#endif

}  // namespace rvc::cli
