// Helpers shared by the unit tests: run a property over a hand-written trace
// and collect its verdicts, write temporary files, decode one JSON message.
#pragma once

#include <gtest/gtest.h>
#include <simdjson.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "engine/checker.hpp"

namespace rvc::test {

// One verdict as reported by a Checker: (time, value).
using TV = std::pair<double, bool>;

// The atom-table index of the field test whose canonical text is `canonical`
// (e.g. "p" for {p}, "x > 2" for {x > 2}); fails the test if absent.
inline int atom_index(engine::Checker& checker, const std::string& canonical) {
  const auto& tests = checker.atoms().tests();
  for (size_t i = 0; i < tests.size(); ++i)
    if (tests[i].to_string() == canonical) return static_cast<int>(i);
  ADD_FAILURE() << "no atom {" << canonical << "} in the table";
  return -1;
}

// Discrete time: the verdict at every step (emit_all) of `spec`, given each
// atom's value per step, keyed by the atom's canonical text.
inline std::vector<int> run_discrete(const std::string& spec, const std::map<std::string, std::vector<int>>& atoms) {
  std::vector<int> out;
  engine::Checker checker(engine::TimeModel::Discrete, /*emit_all=*/true,
                          [&](const engine::Verdict& v) {
                            EXPECT_EQ(v.time, static_cast<double>(out.size()));  // step index
                            out.push_back(v.value ? 1 : 0);
                          });
  checker.add_property({"p", spec});
  size_t steps = atoms.empty() ? 0 : atoms.begin()->second.size();
  std::vector<uint8_t> values(checker.atoms().size(), 0);
  std::vector<int> index;
  for (const auto& [name, trace] : atoms) {
    EXPECT_EQ(trace.size(), steps) << "all atom traces must have the same length";
    index.push_back(atom_index(checker, name));
  }
  EXPECT_EQ(index.size(), checker.atoms().size()) << "every atom of the spec needs a trace";
  for (size_t s = 0; s < steps; ++s) {
    size_t k = 0;
    for (const auto& [name, trace] : atoms) values[index[k++]] = static_cast<uint8_t>(trace[s]);
    checker.step(values.data());
  }
  return out;
}

// Dense time: messages (time, atom values); each message's values hold until
// the next message, the last one until `end`. Returns the condensed verdicts.
struct DenseMsg {
  double time;
  std::map<std::string, int> values;
};
inline std::vector<TV> run_dense(const std::string& spec, const std::vector<DenseMsg>& msgs, double end,
                                 bool emit_all = false) {
  std::vector<TV> out;
  engine::Checker checker(engine::TimeModel::Dense, emit_all,
                          [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  checker.add_property({"p", spec});
  std::vector<uint8_t> values(checker.atoms().size(), 0);
  for (size_t i = 0; i < msgs.size(); ++i) {
    for (const auto& [name, v] : msgs[i].values) {
      int idx = atom_index(checker, name);
      if (idx >= 0) values[idx] = static_cast<uint8_t>(v);
    }
    double until = i + 1 < msgs.size() ? msgs[i + 1].time : end;
    checker.step(msgs[i].time, until, values.data());
  }
  return out;
}

// A temporary file removed when the object goes out of scope.
class TempFile {
 public:
  explicit TempFile(const std::string& content) {
    char name[] = "/tmp/rvc_unit_XXXXXX";
    int fd = ::mkstemp(name);
    EXPECT_GE(fd, 0);
    path_ = name;
    size_t off = 0;
    while (off < content.size()) {
      ssize_t n = ::write(fd, content.data() + off, content.size() - off);
      if (n <= 0) break;
      off += static_cast<size_t>(n);
    }
    ::close(fd);
  }
  ~TempFile() { ::unlink(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace rvc::test
