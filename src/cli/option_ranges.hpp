// Bounds for numeric options, checked when the command line is parsed: a value
// outside them is a usage error (exit 2) naming the option and the range, not
// a run that never reads (--queue 0), allocates gigabytes (--witness 1e8) or
// holds a whole stream (--max-delay 1e308). NaN is refused too: CLI11's own
// Range and NonNegativeNumber compare with < and > and so let it through.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <string>

namespace rvc::cli {

// The documented limits (docs/cli.md, "Numeric options").
inline constexpr double kMaxSeconds = 86400 * 7;    // timeouts, intervals: a week
inline constexpr double kMaxDelaySeconds = 3600;   // --max-delay: an hour of stamps held back
inline constexpr double kAdaptiveDelayLimit = 60;  // merge: how far the wait adapts to the lateness seen
inline constexpr double kMaxMergeHeld = 1000000;   // merge: messages held while waiting for an input
inline constexpr double kMaxQueue = 1 << 24;        // --queue: frames between transport and engine
inline constexpr double kMaxSyncQueue = 1 << 20;    // --sync-queue: messages kept per input
inline constexpr double kMaxWitness = 10000;        // --witness: messages stored with a violation
inline constexpr double kMaxDataValues = 10000000;  // --max-data-values
inline constexpr double kMaxMessageSize = 1 << 30;  // --max-message-size: 1 GiB

// A number in [lo, hi]; `what` describes the unit in the message ("seconds").
inline CLI::Validator in_range(double lo, double hi, const std::string& what = "") {
  auto fmt = [](double v) {
    std::string s = std::to_string(v);
    s.erase(s.find_last_not_of('0') + 1);
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
  };
  const std::string range = fmt(lo) + " to " + fmt(hi) + (what.empty() ? "" : " " + what);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v)) return "'" + text + "' is not a number (allowed: " + range + ")";
        if (!(v >= lo && v <= hi)) return "'" + text + "' is out of range (allowed: " + range + ")";
        return {};
      },
      "in " + range);
}

}  // namespace rvc::cli
