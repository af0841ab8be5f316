// Maps endpoint URIs to transports. The only place that knows them all.
#include <sys/stat.h>

#include <stdexcept>

#include "transport/file_endpoint.hpp"
#include "transport/mcap/mcap_sink.hpp"
#include "transport/transport_options.hpp"
#ifdef RVC_HAVE_ZENOH
#include "transport/zenoh/rvc_zenoh.h"
#include "transport/zenoh/rmw_zenoh_endpoint.hpp"
#include "transport/zenoh/zenoh_endpoint.hpp"
#endif
#include "transport/zenoh/rmw_zenoh_format.hpp"
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
  // bag:PATH and mcap:PATH both name a ROS 2 bag of any storage (MCAP,
  // sqlite3, a bag folder: transport/rosbag2), told apart by content.
  if (scheme == "bag") scheme = "mcap";
  if (scheme == "file" || scheme == "zenoh" || scheme == "dds" || scheme == "mcap" || scheme == "rmw_zenoh") {
    if (rest.empty()) throw std::invalid_argument("endpoint '" + uri + "' names no " +
                                                  (scheme == "file" || scheme == "mcap"     ? "path"
                                                   : scheme == "dds" || scheme == "rmw_zenoh" ? "topic"
                                                                                              : "key expression"));
    return {scheme, rest};
  }
  if (scheme.size() == 1) return {"file", uri};  // not a scheme: a Windows-like path "C:..."
  throw std::invalid_argument("unknown endpoint scheme '" + scheme + ":' in '" + uri +
                              "' (use file:PATH, -, zenoh:KEYEXPR, dds:TOPIC, rmw_zenoh:TOPIC or, as an input, bag:BAG)");
}

[[noreturn, maybe_unused]] void not_built(const std::string& scheme) {
  throw std::invalid_argument("this rvc was built without the " + scheme + " transport (" +
                              (scheme == "zenoh" ? "RVC_WITH_ZENOH" : "RVC_WITH_DDS") + "=OFF)");
}

}  // namespace

std::string scheme_of(const std::string& uri) { return parse(uri).scheme; }

bool endpoints_overlap(const std::string& a, const std::string& b) {
  Parsed pa = parse(a), pb = parse(b);
  // An rmw_zenoh topic is a Zenoh key: <domain>/<topic>/<type>/<hash>, any type.
  for (Parsed* p : {&pa, &pb})
    if (p->scheme == "rmw_zenoh") *p = {"zenoh", rmw_zenoh::data_keyexpr(rmw_zenoh::domain_id_from_env(), p->rest)};
  // A bag is a file: writing verdicts over it is reading back one's output.
  for (Parsed* p : {&pa, &pb})
    if (p->scheme == "mcap") {
      p->scheme = "file";
      if (const size_t q = p->rest.rfind("?inputs="); q != std::string::npos) p->rest.resize(q);  // an output's option
    }
  if (pa.scheme != pb.scheme) return false;
  if (pa.scheme == "file") {
    if (pa.rest == "-" || pb.rest == "-") return false;  // stdin and stdout are different streams
    struct stat sa, sb;
    if (::stat(pa.rest.c_str(), &sa) != 0 || ::stat(pb.rest.c_str(), &sb) != 0) return pa.rest == pb.rest;
    return S_ISREG(sa.st_mode) && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  }
  if (pa.scheme == "dds") {
    // ROS 2 names: "/a/b" and "a/b" are the same topic (rt/a/b).
    auto strip = [](const std::string& t) { return t.front() == '/' ? t.substr(1) : t; };
    return strip(pa.rest) == strip(pb.rest);
  }
#ifdef RVC_HAVE_ZENOH
  int rc = rvc_zenoh_keyexpr_intersects(pa.rest.c_str(), pb.rest.c_str());
  if (rc < 0) throw std::invalid_argument(std::string("zenoh: ") + rvc_zenoh_last_error());
  return rc == 1;
#else
  return pa.rest == pb.rest;
#endif
}

bool reads_back(const std::string& input, const std::string& output) {
  if (endpoints_overlap(input, output)) return true;
  const Parsed in = parse(input), out = parse(output);
  if (in.scheme != "file" || in.rest != "-" || out.scheme != "file" || out.rest == "-") return false;
  struct stat si, so;
  if (::fstat(0, &si) != 0 || ::stat(out.rest.c_str(), &so) != 0) return false;
  return S_ISREG(si.st_mode) && si.st_dev == so.st_dev && si.st_ino == so.st_ino;
}

std::unique_ptr<Source> open_source(const std::string& uri, const TransportOptions& options) {
  Parsed p = parse(uri);
  if (p.scheme == "mcap")  // read whole by the runtime (runtime/check_bag.hpp), not as a stream
    throw std::invalid_argument("'" + uri + "': bags are read by rvc check and rvc monitor --input, not here");
  if (p.scheme == "file") return std::make_unique<FileSource>(p.rest);
  if (p.scheme == "rmw_zenoh") {
#ifdef RVC_HAVE_ZENOH
    return make_rmw_zenoh_source(p.rest, options.zenoh, options.rmw_zenoh);
#else
    not_built("zenoh");
#endif
  }
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
  // mcap:PATH as an output: verdicts in an MCAP file (bag:PATH names only inputs).
  if (p.scheme == "mcap") {
    if (uri.rfind("bag:", 0) == 0)
      throw std::invalid_argument("'" + uri + "': rvc reads bags (bag:), it writes verdicts to mcap:PATH");
    return std::make_unique<mcap::McapSink>(p.rest);
  }
  if (p.scheme == "file") return std::make_unique<FileSink>(p.rest);
  if (p.scheme == "rmw_zenoh") {
#ifdef RVC_HAVE_ZENOH
    return make_rmw_zenoh_sink(p.rest, options.zenoh, options.rmw_zenoh);
#else
    not_built("zenoh");
#endif
  }
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
