// Endpoints: every subcommand names its inputs and outputs with a URI
//   file:PATH | PATH | -   (JSON lines)
//   zenoh:KEYEXPR          (one JSON object per sample)
//   dds:TOPIC              (ROS 2 std_msgs/msg/String by default)
//   rmw_zenoh:TOPIC        (ROS 2 over rmw_zenoh_cpp: CDR samples, GIDs; zenoh/rmw_zenoh_endpoint.hpp)
// A Source delivers Frames to a handler; a Sink publishes payloads. Transport
// specifics (sessions, QoS, configs) stay behind these two interfaces.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "transport/frame.hpp"

namespace rvc::transport {

// What Source::pull found: a frame, nothing yet (a pipe that is quiet: ask
// again), or nothing more after the end-of-stream frame.
enum class PullResult { Frame, Wait, End };

class Source {
 public:
  virtual ~Source() = default;
  // Starts delivery; the handler runs on a transport thread (or the caller's
  // thread for files). Returns once subscribed, i.e. ready to receive.
  virtual void start(FrameHandler handler) = 0;
  // Stops delivery; no handler call is running or will run after it returns.
  virtual void stop() = 0;
  // Sources the caller can read on its own thread, one frame when it wants
  // it, instead of start() (files): several are then read in the order the
  // caller chooses, not raced by threads. The frame's payload stays valid
  // until the next pull. Waits at most about 100 ms for data.
  virtual bool pullable() const { return false; }
  virtual PullResult pull(Frame& frame) {
    (void)frame;
    return PullResult::End;
  }
  // The handler may block this source's thread and do the engine's work
  // there (rvc monitor's inline hand-off, LoopOptions::Handoff): true for
  // Zenoh, whose callbacks may block (backpressure, as a full queue does);
  // false for threads that must never block (CycloneDDS's receive thread
  // also carries the acknowledgements a verdict writer waits for).
  virtual bool handler_may_block() const { return false; }
  // What the transport knows about why messages may not arrive (a publisher
  // whose QoS this subscriber cannot match), for the end-of-run report; empty
  // if nothing is known.
  virtual std::string diagnosis() const { return {}; }
};

class Sink {
 public:
  virtual ~Sink() = default;
  // Publishes one payload. Reliable sinks block rather than drop.
  virtual void put(std::string_view payload, uint64_t seq) = 0;
  // Publishes the end-of-stream marker after the last payload (seq = last seq).
  virtual void put_eos(uint64_t last_seq) = 0;
  // Waits until at least n subscribers match; false on timeout.
  virtual bool wait_matched(size_t n, std::chrono::milliseconds timeout) { return true; }
  // How subscribers can find this sink (what a user checks when none
  // matches): locators, scouting, domain, interface. Empty for files.
  virtual std::string discovery() const { return {}; }
  virtual void flush() {}
  // Called by long-running loops when no message is pending: a chance to make
  // buffered output visible (files) without a write per message.
  virtual void idle() {}
};

}  // namespace rvc::transport
