// Several named inputs and how they are synchronized, as `rvc monitor` and
// `rvc sync` take them:
//   --input gear=dds:/vehicle/status/gear_status --type autoware_auto_vehicle_msgs/msg/GearReport
//   --input steer=zenoh:vehicle/status/steering_status --type ...   (a --type applies to the --input before it)
//   --stamp gear=header.stamp | --stamp steer=arrival
//   --sync approximate|exact|latest|merge (+ --sync-queue, --max-interval, --age-penalty, --lower-bound,
//   --max-delay, --late, --pivot, --dead-after)
#pragma once

#include <CLI/CLI.hpp>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "cli/type_options.hpp"
#include "runtime/synced_pipeline.hpp"
#include "transport/endpoint.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {

struct SyncFlags {
  std::vector<std::string> stamps;        // NAME=PATH|arrival
  std::string policy = "merge";
  size_t queue_size = 10;
  double max_interval = std::numeric_limits<double>::infinity();
  double age_penalty = 0.1;
  std::vector<std::string> lower_bounds;  // NAME=SECONDS
  double max_delay = 0;
  std::string late = "drop";  // merge: drop|process late messages
  std::string pivot;
  double dead_after = 5;

  void add_to(CLI::App& app);

  // "gear=dds:/x" -> name "gear", uri "dds:/x"; false if `text` is a plain URI.
  static bool split_named(const std::string& text, std::string& name, std::string& uri);
  // Whether these --input values ask for named inputs (any NAME=URI).
  static bool named(const std::vector<std::string>& inputs);

  // The named inputs with their types (each --type applies to the --input
  // before it, or names its input: --type gear=pkg/msg/T) and stamps, and
  // for each the transport options to open it with (its DDS type).
  // Throws std::invalid_argument / msg::MsgError with the reason.
  std::vector<runtime::SyncInput> resolve(const std::vector<std::string>& inputs, const CLI::App& app,
                                          const CLI::Option* input_option, TypeOptions& typed,
                                          const transport::TransportOptions& transports,
                                          std::vector<transport::TransportOptions>& per_input) const;
  runtime::SyncOptions options(const std::vector<runtime::SyncInput>& inputs) const;

  // The inputs' sources, opened in order (input i = sources[i]), and their
  // names joined for the counters ("gear,steer").
  struct Sources {
    std::vector<std::unique_ptr<transport::Source>> owned;
    std::vector<transport::Source*> list;
  };
  static Sources open_sources(const std::vector<runtime::SyncInput>& inputs,
                              const std::vector<transport::TransportOptions>& per_input);
  static std::string joined_names(const std::vector<runtime::SyncInput>& inputs);
  // --stamp NAME=PATH onto the inputs; throws std::invalid_argument for an unknown NAME.
  void apply_stamps(std::vector<runtime::SyncInput>& inputs) const;
};

}  // namespace rvc::cli
