// Ids for the values data references bind ({id: *x}): each distinct value a
// message gives a bound field becomes a small integer, so the data monitors
// index their tables with integers, never with strings.
//
// Values keep their JSON type: the string "3", the number 3 and the Boolean
// true are three values (numbers compare as numbers: 3 and 3.0 are one).
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "io/field_tests.hpp"

namespace rvc::io {

class BoundValues {
 public:
  // 1, 2, ...: the value's id. 0: not a value a reference can bind (null,
  // an array, an object).
  uint32_t id(const FieldValue& value);
  size_t size() const { return ids_.size(); }
  // The value with this id as JSON text ("\"a.txt\"", 3, true), for --explain;
  // "" for an id never given out.
  std::string json(uint32_t id) const;

 private:
  std::unordered_map<std::string, uint32_t> ids_;
  std::vector<const std::string*> keys_;  // by id - 1: the map's own keys (nodes do not move)
  std::string key_;  // reused: no allocation for a value seen before
};

}  // namespace rvc::io
