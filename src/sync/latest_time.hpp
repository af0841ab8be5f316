// LatestTime: zero-order hold. Each input holds its latest message; each time
// a message of the pivot input arrives and every input holds one, a set goes
// out with the latest message of every input, stamped with the pivot
// message's stamp. Like message_filters' LatestTime (ROS 2), but the rates come
// from the messages' stamps rather than their arrival times, so the result
// does not depend on the machine that replays a recording.
//
// The pivot is options.pivot, or (-1) the fastest input so far: the smallest
// mean interval between its own stamps, (newest - oldest stamp) / (messages - 1),
// ties to the lower input. An input needs two messages to have a rate; until
// some input has one, the pivot is the input with the most messages (ties:
// the lower input). Since a set needs every input to hold a message, that
// means input 0 in effect, and a set can go out on the very first round
// (message_filters waits for rates). The pivot is chosen after the arriving
// message has updated its input's rate.
//
// A held message replaced by a newer one of its input is released Used if a
// set included it, else Replaced. Stamps need not increase (arrival order
// decides what "latest" is); only a stamp that is not a finite number is Late.
#pragma once

#include <cstdint>
#include <vector>

#include "sync/policy.hpp"

namespace rvc::sync {

class LatestTime final : public Policy {
 public:
  // Throws std::invalid_argument on inputs == 0 or a pivot outside [-1, inputs).
  LatestTime(const PolicyOptions& options, Handler& handler);

  void add(const Member& message) override;
  void finish() override;
  size_t held() const override { return held_; }

 private:
  struct Input {
    bool has = false;   // holds a message
    bool used = false;  // the held message went out in a set
    Member held;
    uint64_t count = 0;  // messages so far
    double lo = 0, hi = 0;  // oldest and newest stamp so far (the rate's span)
  };
  // Whether input a is a better pivot than input b (both have a rate, or neither).
  bool faster(uint32_t a, uint32_t b) const;

  Handler& handler_;
  const uint32_t n_;
  const int fixed_pivot_;
  std::vector<Input> inputs_;
  uint32_t with_data_ = 0;  // inputs holding a message
  size_t held_ = 0;
  uint32_t pivot_ = 0;
  std::vector<Member> members_;
};

}  // namespace rvc::sync
