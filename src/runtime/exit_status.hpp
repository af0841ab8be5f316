// Exit statuses shared by every subcommand (documented in docs/cli.md), and
// how one run's outcome maps onto them.
#pragma once

namespace rvc::runtime {

enum ExitCode : int {
  kOk = 0,          // every property held
  kViolated = 1,    // some property was violated
  kUsage = 2,       // bad arguments, bad spec, unreadable files: before anything ran
  kBadInput = 3,    // messages were rejected (malformed, wrong time order, strict mode) or dropped as late
  kLost = 4,        // messages were lost or duplicated in transit (rvc monitor)
  kRuntime = 5,     // a runtime failure: an output could not be written, a read or transport error
  kIncomplete = 6,  // the stream did not end properly: nothing received, or no end-of-stream marker
                    // before --idle-timeout / a stop signal (with --exit-on-eos)
};

// What happened in one run. When several apply, exit_code() picks the first
// of: violated (1), runtime failure (5), lost (4), incomplete (6), rejected
// (3) — a violation is the answer users wait for; losing verdicts or
// messages outranks an incomplete stream, which outranks rejected input.
struct Outcome {
  bool violated = false;
  bool runtime_failure = false;
  bool lost = false;
  bool incomplete = false;
  bool rejected = false;
  bool dropped = false;  // messages the synchronizer dropped as late: skipped, not checked (exit 3)

  int exit_code() const {
    if (violated) return kViolated;
    if (runtime_failure) return kRuntime;
    if (lost) return kLost;
    if (incomplete) return kIncomplete;
    if (rejected || dropped) return kBadInput;
    return kOk;
  }
};

}  // namespace rvc::runtime
