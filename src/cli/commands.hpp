// Each subcommand registers its options on the CLI11 app and returns the
// function that runs it (called only if that subcommand was chosen).
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

#include "runtime/exit_status.hpp"

namespace rvc::cli {

using Runner = std::function<int()>;

// Exit codes: src/runtime/exit_status.hpp (documented in docs/cli.md).
using runtime::kBadInput, runtime::kIncomplete, runtime::kLost, runtime::kOk, runtime::kRuntime, runtime::kUsage,
    runtime::kViolated;

Runner register_check(CLI::App& app);
Runner register_timescales(CLI::App& app);
Runner register_monitor(CLI::App& app);
Runner register_replay(CLI::App& app);
Runner register_router(CLI::App& app);      // only with the Zenoh transport
Runner register_topics(CLI::App& app);      // the ROS 2 graph of rmw_zenoh (Zenoh transport only)
Runner register_dds_config(CLI::App& app);  // only with the DDS transport
Runner register_perf(CLI::App& app);
Runner register_bridge(CLI::App& app);
Runner register_msg(CLI::App& app);         // ROS 2 message types, CDR <-> JSON
Runner register_calls(CLI::App& app);       // service events -> one line per call
Runner register_echo(CLI::App& app);        // print an endpoint's messages as JSON lines
Runner register_hz(CLI::App& app);          // rate/jitter/silence/latency health check, /diagnostics
Runner register_sync(CLI::App& app);        // several topics -> one stream of sets
Runner register_dashboard(CLI::App& app);   // web page over a results database
Runner register_bag(CLI::App& app);         // rvc bag info: what a ROS 2 bag holds

}  // namespace rvc::cli
