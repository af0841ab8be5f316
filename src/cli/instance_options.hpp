// --instances-by FIELD, --instance-expiry S, --max-instances N: one monitor
// instance per key value (runtime/instances_feed.hpp), for rvc check and
// rvc monitor alike.
#pragma once

#include <CLI/CLI.hpp>

#include "cli/option_ranges.hpp"
#include "cli/option_rules.hpp"

#include <cstdio>
#include <string>

#include "runtime/instances_feed.hpp"

namespace rvc::cli {

struct InstanceFlags {
  std::string by;
  double expiry = 0;
  size_t max_instances = 100000;

  bool given() const { return !by.empty(); }
  void add_to(CLI::App& app) {
    app.add_option("--instances-by", by,
                   "One monitor instance per value of this field (a path: id, vehicle.id); each verdict carries "
                   "\"instance\":{\"FIELD\":VALUE} (docs/semantics.md, \"Parametric instances\")")
        ->check(field_name());
    app.add_option("--instance-expiry", expiry,
                   "With --instances-by: remove an instance whose last message is more than SECONDS (stream time; "
                   "messages for a trace without times) before the message being routed; its key then starts afresh")
        ->check(above_up_to(0, kMaxExpiry, "seconds (or messages)"));
    app.add_option("--max-instances", max_instances,
                   "With --instances-by: the most live instances (default 100000); messages of further keys are "
                   "dropped (\"instance_limit\", exit 3)")
        ->check(in_range(1, kMaxInstances, "instances"));
  }
  // The options, or false (usage error printed): an empty part of the path,
  // or --instance-expiry/--max-instances without --instances-by.
  bool options(runtime::InstanceOptions& out) const {
    if (by.empty()) {
      if (expiry > 0 || max_instances != 100000) {
        std::fprintf(stderr, "rvc: --instance-expiry and --max-instances go with --instances-by FIELD\n");
        return false;
      }
      return true;
    }
    out.key_path.clear();
    for (size_t start = 0;;) {
      const size_t dot = by.find('.', start);
      out.key_path.push_back(by.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
      if (out.key_path.back().empty()) {
        std::fprintf(stderr, "rvc: --instances-by '%s': an empty field name (write a field path like vehicle.id)\n",
                     by.c_str());
        return false;
      }
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    out.expiry = expiry;
    out.max_instances = max_instances;
    return true;
  }
};

}  // namespace rvc::cli
