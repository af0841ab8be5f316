// Options of every transport compiled in: plain structs. Their command-line
// flags are registered by src/cli/transport_flags.hpp, so that `rvc
// monitor`, `rvc replay` and `rvc perf` take the same flags.
#pragma once

#include <memory>
#include <string>

#include "transport/endpoint.hpp"
#ifdef RVC_HAVE_ZENOH
#include "transport/zenoh/zenoh_options.hpp"
#endif
#ifdef RVC_HAVE_DDS
#include "transport/dds/dds_options.hpp"
#endif

namespace rvc::transport {

struct TransportOptions {
#ifdef RVC_HAVE_ZENOH
  ZenohOptions zenoh;
  RmwZenohOptions rmw_zenoh;
#endif
#ifdef RVC_HAVE_DDS
  DdsOptions dds;
#endif
};

// Endpoint URIs: file:PATH | PATH | - | zenoh:KEYEXPR | dds:TOPIC | rmw_zenoh:TOPIC.
// Throw std::invalid_argument naming the problem (unknown scheme, a transport
// not compiled in, an empty key expression).
std::unique_ptr<Source> open_source(const std::string& uri, const TransportOptions& options);
std::unique_ptr<Sink> open_sink(const std::string& uri, const TransportOptions& options);

// "zenoh", "dds", "rmw_zenoh", "mcap" or "file".
std::string scheme_of(const std::string& uri);

// Whether what is published on endpoint `b` would be received on endpoint
// `a` (or the other way round): intersecting Zenoh key expressions, the same
// DDS topic, the same file. A monitor or bridge reading its own output would
// feed itself without end. Throws std::invalid_argument for a bad URI.
bool endpoints_overlap(const std::string& a, const std::string& b);

// Whether writing to `output` would change what `input` reads: the two
// overlap, or the input is stdin ("-") redirected from the very file the
// output names (`rvc check - -o t.jsonl < t.jsonl`: compared by device and
// inode, so hard links and symlinks count too). Opening the output would
// truncate the input before it is read. Throws as endpoints_overlap.
bool reads_back(const std::string& input, const std::string& output);

}  // namespace rvc::transport
