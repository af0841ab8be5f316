// Each subcommand registers its options on the CLI11 app and returns the
// function that runs it (called only if that subcommand was chosen).
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace rvc::cli {

using Runner = std::function<int()>;

// Exit codes shared by all subcommands (documented in docs/cli.md).
enum ExitCode : int {
  kOk = 0,          // every property held
  kViolated = 1,    // some property was violated
  kUsage = 2,       // bad arguments, bad spec, unreadable files
  kBadInput = 3,    // messages were rejected (and no property was violated)
  kLost = 4,        // messages were lost or duplicated in transit (rvc monitor)
  kRuntime = 5,     // a runtime failure: an output could not be written, a read or transport error
  kIncomplete = 6,  // the stream did not end properly: nothing received, or no end-of-stream marker
                    // before --idle-timeout / a stop signal (with --exit-on-eos)
};
// When several apply, the first in this order wins: 2 (before anything runs),
// 1, 5, 4, 6, 3 — a violation is the answer users wait for; losing verdicts
// or messages outranks an incomplete stream, which outranks rejected input.

Runner register_check(CLI::App& app);
Runner register_timescales(CLI::App& app);
Runner register_monitor(CLI::App& app);
Runner register_replay(CLI::App& app);
Runner register_router(CLI::App& app);      // only with the Zenoh transport
Runner register_dds_config(CLI::App& app);  // only with the DDS transport
Runner register_perf(CLI::App& app);
Runner register_bridge(CLI::App& app);

}  // namespace rvc::cli
