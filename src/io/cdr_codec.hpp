// ROS 2 CDR (OMG XCDR1 "plain CDR", as rmw_cyclonedds and rmw_fastrtps write
// it) to JSON and back, driven by a message type read at run time.
//
// Wire rules: a 4-byte encapsulation header (representation id 0x0000 big
// endian / 0x0001 little endian, then a 2-byte options field that is
// ignored); every primitive aligned to its size (at most 8) counted from the
// end of that header; strings as uint32 length including the NUL, then the
// bytes and the NUL; sequences as uint32 count then the elements; fixed arrays
// as the elements only; a message with no fields as one uint8. Up to 3 bytes
// of padding may follow the last field (writers pad samples to 4 bytes).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "msg/msg_types.hpp"

namespace rvc::io {

// A sample that cannot be decoded: what went wrong, the field path and the
// byte offset in the sample (counted from its first byte, the header).
struct CdrError {
  std::string message;
  size_t offset = 0;
  std::string to_string() const { return message + " at byte " + std::to_string(offset); }
};

// The fields of a sample worth writing as JSON: the paths properties read
// ({status.twist.linear.x > 1} selects status.twist.linear.x). A path that
// ends at a nested message selects all of it. Fields outside the selection
// are still read and checked (a bad sample is refused whatever is selected),
// only not written: formatting numbers the properties never look at was most
// of the typed input's cost.
class CdrSelection {
 public:
  void add(const std::vector<std::string>& path);
  void add_all() { all_ = true; }
  bool all() const { return all_; }
  // The selection below field `name`, or null if nothing there is selected.
  const CdrSelection* find(const std::string& name) const;

 private:
  bool all_ = false;
  std::vector<std::pair<std::string, CdrSelection>> children_;
};

// Appends the sample as one JSON object (fields in definition order, numbers
// exact: float32 values widened to double, 64-bit integers in full) to `out`;
// with `select`, only the selected fields. Returns false with `error` for a
// malformed or truncated sample; `out` then holds a partial object the caller
// discards.
bool cdr_to_json(const msg::MessageType& type, std::string_view sample, std::string& out, CdrError& error,
                 const CdrSelection* select = nullptr);

struct CdrWriteOptions {
  bool big_endian = false;
};

// Encodes one JSON object (as cdr_to_json writes it) as a CDR sample with its
// header. Fields missing from the object take their default (the .msg default
// value, else 0, false, "", empty); unknown keys, wrong types and values out of
// range are errors naming the field. Returns false with `error`.
bool json_to_cdr(const msg::MessageType& type, std::string_view json, std::string& sample, std::string& error,
                 const CdrWriteOptions& options = {});

}  // namespace rvc::io
