// Bounds for numeric options, checked when the command line is parsed: a value
// outside them is a usage error (exit 2) naming the option and the range, not
// a run that never reads (--queue 0), allocates gigabytes (--witness 1e8) or
// holds a whole stream (--max-delay 1e308). NaN is refused too: CLI11's own
// Range and NonNegativeNumber compare with < and > and so let it through.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
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

inline constexpr double kMaxCount = 9007199254740992;  // counts, seeds: 2^53 (exact as a double)
inline constexpr double kMaxInstances = 10000000;      // --max-instances
inline constexpr double kMaxExpiry = 1e9;              // --instance-expiry: seconds of stream time (or messages)
inline constexpr double kMaxDomain = 232;              // DDS domain ids

// Names the validator in_range() makes, followed by "lo hi" (%.17g) and, for
// a range open at lo, " above": how the rule over the whole command tree
// (option_rules.hpp) finds an option's range.
inline constexpr const char* kRangeValidator = "rvc-range ";

namespace detail {
inline std::string range_number(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::string s = std::to_string(v);
  s.erase(s.find_last_not_of('0') + 1);
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

inline CLI::Validator range_validator(double lo, double hi, bool above, const std::string& what) {
  const std::string range = (above ? "more than " + range_number(lo) + ", up to " : range_number(lo) + " to ") +
                            range_number(hi) + (what.empty() ? "" : " " + what);
  char name[96];
  std::snprintf(name, sizeof name, "%s%.17g %.17g%s", kRangeValidator, lo, hi, above ? " above" : "");
  CLI::Validator v(
      [lo, hi, above, range](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v)) return "'" + text + "' is not a number (allowed: " + range + ")";
        if (!((above ? v > lo : v >= lo) && v <= hi)) return "'" + text + "' is out of range (allowed: " + range + ")";
        return {};
      },
      "in " + range);
  v.name(name);
  return v;
}
}  // namespace detail

// A number in [lo, hi]; `what` describes the unit in the message ("seconds").
// Every numeric option of every subcommand takes one (checked by
// numeric_rule(), listed by the hidden `rvc --list-numeric`).
inline CLI::Validator in_range(double lo, double hi, const std::string& what = "") {
  return detail::range_validator(lo, hi, false, what);
}

// A number in (lo, hi]: more than lo (a timeout of 0 s would time out every call).
inline CLI::Validator above_up_to(double lo, double hi, const std::string& what = "") {
  return detail::range_validator(lo, hi, true, what);
}

}  // namespace rvc::cli
