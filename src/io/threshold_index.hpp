// Comparisons of one numeric field with many constants ({v > 3}, {v > 10},
// {v > 250} in a thousand properties), evaluated together.
//
// The constants of one operator are kept sorted. {v > k} holds exactly for
// the constants below v, so the true tests of a group are a prefix of the
// sorted array ({v < k}, {v <= k}: a suffix); one binary search finds where
// the new value falls, a second (over the atom bytes themselves) where the
// old one fell, and only the atoms between the two are written: the ones
// whose truth value changed. A message is then O(log n + changed) for the
// group instead of O(n).
//
// Why the old position can be read from the bytes: every path that writes
// these atoms (this one, the general per-test loop, the exact path beyond
// 2^53) writes all of a field's numeric comparisons from one value, or none
// of them (a missing field, a value of another type), so the group's bytes
// always form such a prefix (suffix), all false before the field is seen
// included. Literals of magnitude 2^53 or more, NaN literals, and ==, !=
// stay with the per-test loop: their order would not be the doubles' order,
// or their true set is no prefix.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "spec/ast.hpp"
#include "spec/exact_number.hpp"

namespace rvc::io {

class ThresholdIndex {
 public:
  // Groups the tests `ids` (of one field) that fit; the others go to `rest`
  // in their order. An operator with fewer than `min_group` tests is not
  // grouped (a binary search over two constants saves nothing).
  void build(const std::vector<int>& ids, const std::vector<spec::FieldTest>& tests, std::vector<int>& rest,
             size_t min_group = 2) {
    using FOp = spec::FieldTest::Op;
    groups_.clear();
    rest.clear();
    std::vector<int> by_op[4];
    for (int id : ids) {
      const spec::FieldTest& t = tests[static_cast<size_t>(id)];
      const double k = t.value.number;
      const bool fits = t.value.kind == spec::Literal::Kind::Number && !std::isnan(k) && std::fabs(k) < spec::kTwo53 &&
                        (t.op == FOp::Gt || t.op == FOp::Ge || t.op == FOp::Lt || t.op == FOp::Le);
      if (fits) by_op[op_index(t.op)].push_back(id);
      else rest.push_back(id);
    }
    for (int o = 0; o < 4; ++o) {
      std::vector<int>& g = by_op[o];
      if (g.size() < min_group) {
        rest.insert(rest.end(), g.begin(), g.end());
        continue;
      }
      std::stable_sort(g.begin(), g.end(), [&](int x, int y) {
        return tests[static_cast<size_t>(x)].value.number < tests[static_cast<size_t>(y)].value.number;
      });
      Group group;
      group.op = static_cast<uint8_t>(o);
      for (int id : g) {
        group.k.push_back(tests[static_cast<size_t>(id)].value.number);
        group.id.push_back(static_cast<uint32_t>(id));
      }
      groups_.push_back(std::move(group));
    }
    std::sort(rest.begin(), rest.end());
  }
  bool empty() const { return groups_.empty(); }

  // The grouped tests' values for the number d (|d| < 2^53, or NaN or
  // infinite: compared as doubles, exactly), written into `out` (the atom
  // bytes, holding the values after the previous message) where they change.
  void apply(double d, uint8_t* out) const {
    for (const Group& g : groups_) apply(g, d, out);
  }

 private:
  // 0: >, 1: >=, 2: <, 3: <=
  static int op_index(spec::FieldTest::Op op) {
    using FOp = spec::FieldTest::Op;
    return op == FOp::Gt ? 0 : op == FOp::Ge ? 1 : op == FOp::Lt ? 2 : 3;
  }
  struct Group {
    uint8_t op;
    std::vector<double> k;     // ascending
    std::vector<uint32_t> id;  // the atom of each constant
  };

  static void apply(const Group& g, double d, uint8_t* out) {
    const size_t n = g.k.size();
    const double* k = g.k.data();
    const uint32_t* id = g.id.data();
    // cut: > and >= hold on [0, cut), < and <= on [cut, n). NaN: every comparison false.
    size_t cut;
    const bool prefix = g.op < 2;
    if (std::isnan(d)) {
      cut = prefix ? 0 : n;
    } else {
      switch (g.op) {
        case 0: cut = static_cast<size_t>(std::lower_bound(k, k + n, d) - k); break;  // k < d
        case 1: cut = static_cast<size_t>(std::upper_bound(k, k + n, d) - k); break;  // k <= d
        case 2: cut = static_cast<size_t>(std::upper_bound(k, k + n, d) - k); break;  // d < k from here
        default: cut = static_cast<size_t>(std::lower_bound(k, k + n, d) - k); break;  // d <= k from here
      }
    }
    // Where the old value fell: the first false byte of a prefix group, the
    // first true byte of a suffix group.
    size_t lo = 0, hi = n;
    while (lo < hi) {
      const size_t mid = lo + (hi - lo) / 2;
      const bool before_cut = prefix ? out[id[mid]] != 0 : out[id[mid]] == 0;
      if (before_cut) lo = mid + 1;
      else hi = mid;
    }
    const size_t old = lo;
    // Between the two cuts the truth value flips; elsewhere it stays.
    if (old < cut) {
      const uint8_t v = prefix ? 1 : 0;
      for (size_t j = old; j < cut; ++j) out[id[j]] = v;
    } else {
      const uint8_t v = prefix ? 0 : 1;
      for (size_t j = cut; j < old; ++j) out[id[j]] = v;
    }
  }

  std::vector<Group> groups_;
};

}  // namespace rvc::io
