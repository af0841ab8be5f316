// Synchronization policies: which messages of N independently arriving
// inputs form one event for the monitors (issue 12).
//
// A policy sees only (input, stamp, token) per message; the caller keeps the
// messages themselves (decoded field values, JSON text), keyed by token, and
// frees one when the policy releases it. So a policy never copies payloads,
// and the same policy serves `rvc monitor` (in process) and `rvc sync` (its
// own participant).
//
//   approximate  message_filters' ApproximateTime algorithm, for any N
//   exact        sets of messages with equal stamps (ExactTime)
//   latest       zero-order hold: a set each time the pivot input (by default
//                the fastest so far) delivers, once every input has data
//   merge        every message is an event at its stamp, released in stamp
//                order behind a watermark; messages behind it are late
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace rvc::sync {

enum class PolicyKind { Approximate, Exact, Latest, Merge };

// "approximate" | "exact" | "latest" | "merge"; throws std::invalid_argument.
PolicyKind policy_from_string(const std::string& name);
const char* to_string(PolicyKind kind);

// Why a message leaves a policy. Everything added is released exactly once,
// at the latest by finish().
enum class Release : uint8_t {
  Used,        // it was a member of at least one set
  Unmatched,   // approximate/exact: no future set can hold it (a set past it went out, or a better candidate came)
  Overflow,    // approximate/exact: its input's queue exceeded queue_size; the oldest went
  Interval,    // approximate: every set holding it would span more than max_interval
  Replaced,    // latest: a newer message of its input came before a set used it;
               // exact/merge: another message of its input with the same stamp came
  Late,        // merge, exact: its stamp is not after the last set already out (approximate: earlier than
               // its own input's previous message); any policy: a stamp that is not a finite number
  Unfinished,  // finish(): still waiting for a set when the stream ended
};
inline constexpr size_t kReleaseKinds = 7;
const char* to_string(Release why);

struct Member {
  uint32_t input = 0;  // 0 .. inputs-1
  double stamp = 0;    // seconds
  uint64_t token = 0;  // the caller's handle; opaque to the policy
};

class Handler {
 public:
  virtual ~Handler() = default;
  // One event, members sorted by input. approximate/exact/latest: one member
  // per input (latest may hand out a held message again). merge: the
  // messages at one stamp, at most one per input. Sets come out in strictly
  // increasing set_stamp (approximate: the newest member's stamp; exact, merge:
  // the common stamp; latest: the pivot message's stamp), except that latest
  // follows the pivot input's own order, and approximate's may repeat when an input repeats a stamp.
  // The handler must not call back into the policy.
  virtual void on_set(const Member* members, size_t count, double set_stamp) = 0;
  // The policy will not hand this message out again; the caller may free it.
  virtual void on_release(const Member& message, Release why) = 0;
};

struct PolicyOptions {
  size_t inputs = 0;
  // approximate, exact: messages (exact: pending stamps) kept per input, as
  // message_filters' queue_size. Overflow drops the oldest.
  size_t queue_size = 10;
  // approximate: a set spanning more than this (newest - oldest stamp) is
  // never formed. Default: no limit.
  double max_interval = std::numeric_limits<double>::infinity();
  // approximate: message_filters' age penalty (default 0.1).
  double age_penalty = 0.1;
  // approximate: per input, the least time between two of its messages
  // (seconds; empty or 0: unknown). Lets a set out sooner.
  std::vector<double> inter_message_lower_bound;
  // merge: a message is released once a message stamped more than the delay
  // after it has arrived (or by advance()/finish()). The delay starts at
  // max_delay; with adaptive_limit > 0 it grows to twice the largest lateness
  // seen (how far behind the newest stamp a message arrived), at most to
  // adaptive_limit: ordinary jitter stops making messages late after the
  // first, and each further late message at least doubles the delay.
  double max_delay = 0;
  double adaptive_limit = 0;
  // merge: a late message (at or before the last set out) is not dropped but
  // released as a set of its own, stamped just after that set (the least
  // double above it): checked as the next event, since the events after its
  // own stamp have been checked already.
  bool process_late = false;
  // merge: also wait for every input: a stamp goes out only once each input
  // not excluded (exclude(): silent, ended) has delivered a later one. Each
  // input is in stamp order itself, so publishers that start or run apart do
  // not make each other's messages late. max_held bounds what this may hold:
  // past it the earliest goes out regardless.
  bool wait_for_inputs = false;
  size_t max_held = std::numeric_limits<size_t>::max();
  // latest: the input whose messages make sets; -1: the fastest so far
  // (smallest mean interval between its stamps; ties: the lower input).
  int pivot = -1;
};

class Policy {
 public:
  virtual ~Policy() = default;
  // One message, in arrival order. May call the handler (sets, releases)
  // before it returns.
  virtual void add(const Member& message) = 0;
  // merge: the watermark moves to at least `stamp` - max_delay even without
  // new messages (a caller whose stamps follow a clock calls this while idle).
  // Others: no effect.
  virtual void advance(double stamp) { (void)stamp; }
  // merge with wait_for_inputs: stop (or start again) waiting for an input,
  // e.g. one that has gone silent or has ended. Others: no effect.
  virtual void exclude(uint32_t input, bool excluded) {
    (void)input;
    (void)excluded;
  }
  // End of stream: merge releases what it holds as sets in stamp order; the
  // others release what they hold as Unfinished (latest: Used if a set used it).
  // The policy is then empty, as new, and may take another stream.
  virtual void finish() = 0;
  // Messages held now (the bound on memory: flat in stream length).
  virtual size_t held() const = 0;
};

std::unique_ptr<Policy> make_policy(PolicyKind kind, const PolicyOptions& options, Handler& handler);

}  // namespace rvc::sync
