// --explain for properties with data references: the explain::Walker over
// a data monitor's tables. Each sub-formula's value is read at the entry of
// the assignment fixed so far (the quantifiers fix one value per variable as
// the walk passes them), and values are named by their JSON text when the
// caller can name them (explain::ValueNames), else by where they were bound.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "engine/data/tables.hpp"
#include "engine/explain.hpp"

namespace rvc::engine::data {

class DataWalker : public explain::Walker {
 public:
  DataWalker(const Program& program, bool dense, double now, const Bindings& bindings,
             const explain::ValueNames* names)
      : Walker(program, dense, now), bindings_(bindings), names_(names), dense_(dense) {}

 protected:
  uint32_t indexes(int var) const override { return bindings_.domains().size(var); }

  std::vector<uint32_t> bound_now(int var) const override {
    std::vector<uint32_t> out;
    for (size_t i = 0; i < program_.code.size(); ++i) {
      const Instr& in = program_.code[i];
      if (in.code != Code::Bind || in.var != var) continue;
      const uint32_t k = bindings_.index(i);
      if (k != 0 && std::find(out.begin(), out.end(), k) == out.end()) out.push_back(k);
    }
    return out;
  }

  std::string value_name(int var, uint32_t k) const override {
    if (k == 0) return "any value not seen yet";
    const Bindings::Origin* o = bindings_.origin(var, k);
    if (!o) return "value #" + std::to_string(k);  // origins not kept (not --explain)
    if (names_ && *names_) {
      std::string text = (*names_)(o->id);
      if (!text.empty()) return text;
    }
    // Named by where it came from: the field of the test that bound it first ({file: *f}: file).
    const std::string& test = program_.text[o->instr];
    const size_t star = test.rfind(": *");
    const std::string field = star == std::string::npos || star < 1 ? test : test.substr(1, star - 1);
    return "the value of " + field + " at " +
           (dense_ ? "time " + explain::seconds(o->time) : "step " + std::to_string(static_cast<int64_t>(o->time)));
  }

  // The entry of `table` for the assignment fixed so far.
  template <class T>
  size_t offset(const Table<T>& table) const {
    size_t off = 0;
    for (size_t v = 0; v < kMaxVariables; ++v)
      if (table.mask & bit(static_cast<int>(v))) off += assignment_[v] * table.strides.of[v];
    return off;
  }

 private:
  const Bindings& bindings_;
  const explain::ValueNames* names_;
  bool dense_;
};

}  // namespace rvc::engine::data
