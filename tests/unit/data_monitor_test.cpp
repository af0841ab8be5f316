// Data references (exists/forall over {key: *x}): verdicts computed by hand
// or by brute force over explicit sets, across many distinct values (so the
// tables are laid out again several times), two variables, the value limit,
// and memory that grows with distinct values, not with the trace.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "io/bound_values.hpp"
#include "spec/parser.hpp"

namespace rvc::engine {
namespace {

// Drives a Checker with messages given as field -> value id (0: field
// missing, the test keeps its value, as the decoders do).
struct Driver {
  Checker checker;
  std::vector<bool> verdicts;
  std::vector<uint8_t> atoms;
  std::vector<uint32_t> bound;

  Driver(TimeModel model, uint32_t max_values = 100000)
      : checker(model, true, [this](const Verdict& v) { verdicts.push_back(v.value); }) {
    checker.set_max_data_values(max_values);
  }
  void add(const std::string& spec) {
    checker.add_property({"p", spec});
    atoms.assign(checker.atoms().size(), 0);
    bound.assign(checker.atoms().size(), 0);
  }
  // Sets every binding test on `key` to value id v (0 keeps it).
  void set(const std::string& key, uint32_t v) {
    const auto& tests = checker.atoms().tests();
    for (size_t id = 0; id < tests.size(); ++id)
      if (tests[id].op == spec::FieldTest::Op::Bind && tests[id].key() == key && v != 0) bound[id] = v;
  }
  bool step() {
    checker.step(atoms.data(), bound.data());
    return verdicts.back();
  }
};

TEST(DataMonitor, EveryIdSeenBeforeAcrossManyValues) {
  Driver d(TimeModel::Discrete);
  d.add("forall[x]. ({id: *x} -> pre(once{id: *x}))");  // the current id was seen before
  std::set<uint32_t> seen;
  uint32_t next = 1;
  for (int k = 0; k < 600; ++k) {
    // New ids often at first (capacities double many times), then mostly repeats.
    const bool fresh = k < 300 ? k % 2 == 0 : k % 17 == 0;
    const uint32_t id = fresh ? next++ : 1 + static_cast<uint32_t>((k * 7919) % (next - 1));
    d.set("id", id);
    const bool expected = seen.count(id) > 0;
    ASSERT_EQ(d.step(), expected) << "step " << k << " id " << id;
    seen.insert(id);
  }
}

TEST(DataMonitor, TwoVariablesAPairWhoseReverseCameBefore) {
  Driver d(TimeModel::Discrete);
  d.add("exists[x, y]. ({a: *x, b: *y} and pre(once{a: *y, b: *x}))");
  std::set<std::pair<uint32_t, uint32_t>> before;
  uint32_t a = 0, b = 0;
  for (int k = 0; k < 400; ++k) {
    const uint32_t na = 1 + static_cast<uint32_t>((k * 31 + 7) % 23), nb = 1 + static_cast<uint32_t>((k * 17 + 3) % 29);
    // Now and then a field is missing: its test keeps the last value.
    if (k % 5 != 3) a = na;
    if (k % 7 != 4) b = nb;
    d.set("a", a);
    d.set("b", b);
    const bool expected = before.count({b, a}) > 0;
    ASSERT_EQ(d.step(), expected) << "step " << k;
    before.insert({a, b});
  }
}

TEST(DataMonitor, BoundedOperatorsPerValue) {
  Driver d(TimeModel::Discrete);
  // Some id other than the current one was seen 1..2 steps ago (historically[0:0]: now).
  d.add("exists[x]. (not {id: *x} and once[1:2]{id: *x} and historically[0:0] not {id: *x})");
  const uint32_t ids[] = {1, 1, 2, 2, 3, 1, 1, 1, 1};
  const bool expected[] = {false, false, true, true, true, true, true, false, false};
  for (size_t k = 0; k < std::size(ids); ++k) {
    d.set("id", ids[k]);
    EXPECT_EQ(d.step(), expected[k]) << "step " << k;
  }
}

TEST(DataMonitor, MemoryGrowsWithDistinctValuesNotWithTheTrace) {
  Program program;
  AtomTable atoms;
  program = compile(*spec::parse("forall[x]. ({id: *x} -> once[0:100]{ok})", {}), atoms, TimeModel::Discrete, "");
  data::DiscreteMonitor m(program, "p", 1000);
  std::vector<uint8_t> values(atoms.size(), 1);
  std::vector<uint32_t> bound(atoms.size(), 0);
  const int bind = atoms.tests()[0].op == spec::FieldTest::Op::Bind ? 0 : 1;
  for (int k = 0; k < 50; ++k) {
    bound[bind] = 1 + k % 5;
    m.step(values.data(), bound.data());
  }
  const size_t entries = m.entries();
  for (int k = 0; k < 20000; ++k) {
    bound[bind] = 1 + k % 5;
    m.step(values.data(), bound.data());
  }
  EXPECT_EQ(m.entries(), entries);
  bound[bind] = 6;  // one more value: one more entry per table over x
  m.step(values.data(), bound.data());
  EXPECT_GT(m.entries(), entries);
}

TEST(DataMonitor, TheValueLimitIsAnErrorNamingPropertyAndVariable) {
  Driver d(TimeModel::Discrete, 3);
  d.add("forall[k]. ({id: *k} -> pre(once{id: *k}))");
  for (uint32_t v = 1; v <= 3; ++v) {
    d.set("id", v);
    d.step();
  }
  d.set("id", 2);  // seen: no new value
  d.step();
  d.set("id", 4);
  try {
    d.step();
    FAIL() << "no error past the limit";
  } catch (const data::DataLimitError& e) {
    EXPECT_NE(std::string(e.what()).find("property 'p': variable 'k'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--max-data-values"), std::string::npos) << e.what();
  }
}

TEST(DataMonitor, DenseOnceOfTheSameIdWithinOneSecond) {
  std::vector<std::pair<double, bool>> changes;
  Checker c(TimeModel::Dense, false, [&](const Verdict& v) { changes.emplace_back(v.time, v.value); });
  c.add_property({"p", "exists[x]. ({id: *x} and once[1:1.5]{id: *x})"});
  std::vector<uint8_t> atoms(c.atoms().size(), 0);
  std::vector<uint32_t> bound(c.atoms().size(), 0);
  // id 1 on [0, 1), 2 on [1, 2), 1 on [2, 4): true where 1 held 1..1.5 earlier: [2, 2.5) and [3, 4).
  const std::pair<double, uint32_t> msgs[] = {{0, 1}, {1, 2}, {2, 1}, {4, 1}};
  double last = 0;
  for (const auto& [t, id] : msgs) {
    c.step(last, t, atoms.data(), bound.data());  // the previous values over [last, t)
    bound[0] = id;
    last = t;
  }
  EXPECT_EQ(changes, (std::vector<std::pair<double, bool>>{{0, false}, {2, true}, {2.5, false}, {3, true}}));
}

TEST(BoundValues, KeepTheirJsonType) {
  io::BoundValues ids;
  using io::FieldValue, io::ValueKind;
  const uint32_t s3 = ids.id(FieldValue{ValueKind::String, false, 0, "3"});
  const uint32_t n3 = ids.id(FieldValue{ValueKind::Number, false, 3, {}});
  const uint32_t n30 = ids.id(FieldValue{ValueKind::Number, false, 3.0, {}});
  const uint32_t t = ids.id(FieldValue{ValueKind::Bool, true, 0, {}});
  const uint32_t zero = ids.id(FieldValue{ValueKind::Number, false, 0.0, {}});
  const uint32_t minus_zero = ids.id(FieldValue{ValueKind::Number, false, -0.0, {}});
  EXPECT_NE(s3, n3);
  EXPECT_EQ(n3, n30);
  EXPECT_NE(t, n3);
  EXPECT_EQ(zero, minus_zero);
  EXPECT_EQ(ids.id(FieldValue{ValueKind::Null, false, 0, {}}), 0u);
  EXPECT_EQ(ids.id(FieldValue{ValueKind::Object, false, 0, {}}), 0u);
  EXPECT_EQ(ids.size(), 4u);
}

}  // namespace
}  // namespace rvc::engine
