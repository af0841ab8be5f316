// Maps endpoint URIs to transports. The only place that knows them all.
#include <stdexcept>

#include "transport/file_endpoint.hpp"
#include "transport/transport_options.hpp"
#ifdef RVC_HAVE_ZENOH
#include "transport/zenoh/zenoh_endpoint.hpp"
#endif
#ifdef RVC_HAVE_DDS
#include "transport/dds/dds_endpoint.hpp"
#endif

namespace rvc::transport {
namespace {

struct Parsed {
  std::string scheme, rest;
};

Parsed parse(const std::string& uri) {
  if (uri == "-") return {"file", "-"};
  auto colon = uri.find(':');
  if (colon == std::string::npos) return {"file", uri};  // a plain path
  std::string scheme = uri.substr(0, colon), rest = uri.substr(colon + 1);
  if (scheme == "file" || scheme == "zenoh" || scheme == "dds") {
    if (rest.empty()) throw std::invalid_argument("endpoint '" + uri + "' names no " +
                                                  (scheme == "file" ? "path" : scheme == "dds" ? "topic" : "key expression"));
    return {scheme, rest};
  }
  if (scheme.size() == 1) return {"file", uri};  // not a scheme: a Windows-like path "C:..."
  throw std::invalid_argument("unknown endpoint scheme '" + scheme + ":' in '" + uri +
                              "' (use file:PATH, -, zenoh:KEYEXPR or dds:TOPIC)");
}

[[noreturn]] void not_built(const std::string& scheme) {
  throw std::invalid_argument("this rvc was built without the " + scheme + " transport (" +
                              (scheme == "zenoh" ? "RVC_WITH_ZENOH" : "RVC_WITH_DDS") + "=OFF)");
}

}  // namespace

std::string scheme_of(const std::string& uri) { return parse(uri).scheme; }

void add_transport_options(CLI::App& app, TransportOptions& options) {
#ifdef RVC_HAVE_ZENOH
  add_zenoh_options(app, options.zenoh);
#endif
#ifdef RVC_HAVE_DDS
  add_dds_options(app, options.dds);
#endif
  (void)app;
  (void)options;
}

std::unique_ptr<Source> open_source(const std::string& uri, const TransportOptions& options) {
  Parsed p = parse(uri);
  if (p.scheme == "file") return std::make_unique<FileSource>(p.rest);
  if (p.scheme == "zenoh") {
#ifdef RVC_HAVE_ZENOH
    return make_zenoh_source(p.rest, options.zenoh);
#else
    not_built("zenoh");
#endif
  }
#ifdef RVC_HAVE_DDS
  return make_dds_source(p.rest, options.dds);
#else
  not_built("dds");
#endif
}

std::unique_ptr<Sink> open_sink(const std::string& uri, const TransportOptions& options) {
  Parsed p = parse(uri);
  if (p.scheme == "file") return std::make_unique<FileSink>(p.rest);
  if (p.scheme == "zenoh") {
#ifdef RVC_HAVE_ZENOH
    return make_zenoh_sink(p.rest, options.zenoh);
#else
    not_built("zenoh");
#endif
  }
#ifdef RVC_HAVE_DDS
  return make_dds_sink(p.rest, options.dds);
#else
  not_built("dds");
#endif
}

}  // namespace rvc::transport
