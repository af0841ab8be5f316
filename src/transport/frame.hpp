// One message as a transport hands it to rvc: borrowed payload bytes plus the
// bookkeeping that loss accounting needs. Nothing here knows about Zenoh or DDS.
#pragma once

#include <cstdint>
#include <functional>
#include <string_view>

namespace rvc::transport {

struct Frame {
  std::string_view payload;  // borrowed: valid only during the callback
  uint64_t seq = 0;          // publisher's sequence number (1-based), 0 if unknown
  bool eos = false;          // end-of-stream marker: payload is empty, seq = last data seq
  uint64_t publisher = 0;    // who sent it (DDS publication handle, rvc's Zenoh publisher id); 0 if unknown
  uint32_t input = 0;        // which input of several (set by the monitor loop, not by transports)
  std::string_view key;      // the sample's own key (Zenoh: a wildcard subscriber sees many); empty if none
};

// Called on a transport thread. Must copy what it keeps and return quickly.
using FrameHandler = std::function<void(const Frame&)>;

}  // namespace rvc::transport
