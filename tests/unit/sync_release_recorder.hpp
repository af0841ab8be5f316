// What the exact, latest and merge policy tests record of releases: for each
// message (token), why and at which step it left, and how often (exactly
// once is the contract). Each test file records sets in its own shape.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>

#include "sync/policy.hpp"

namespace rvc::sync::test {

struct ReleaseRecorder : Handler {
  std::map<uint64_t, std::pair<Release, size_t>> released;  // token -> (why, step)
  std::map<uint64_t, int> count;                             // token -> releases
  size_t step = 0;
  void on_release(const Member& m, Release why) override {
    ++count[m.token];
    released[m.token] = {why, step};
  }
  int releases_of(uint64_t token) const {
    auto it = count.find(token);
    return it == count.end() ? 0 : it->second;
  }
};

}  // namespace rvc::sync::test
