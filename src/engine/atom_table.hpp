// The field tests of every property in one process, each stored once. A test
// written in several properties ({speed > 3} in three of them) is evaluated
// once per message; its value is an index into one shared byte array.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "spec/ast.hpp"

namespace rvc::engine {

class AtomTable {
 public:
  int intern(const spec::FieldTest& test) {
    auto [it, inserted] = index_.emplace(test.to_string(), static_cast<int>(tests_.size()));
    if (inserted) tests_.push_back(test);
    return it->second;
  }
  const std::vector<spec::FieldTest>& tests() const { return tests_; }
  // Replaces a test's value once its meaning is known (a message constant
  // named by a bare word becomes its number), before any message is decoded.
  void set_value(int id, const spec::Literal& value) { tests_[static_cast<size_t>(id)].value = value; }
  size_t size() const { return tests_.size(); }

 private:
  std::vector<spec::FieldTest> tests_;
  std::unordered_map<std::string, int> index_;
};

}  // namespace rvc::engine
