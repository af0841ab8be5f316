// Data references (exists/forall over {key: *x}): verdicts computed by hand
// or by brute force over explicit sets, across many distinct values (so the
// tables are laid out again several times), two variables, the value limit,
// and memory that grows with distinct values, not with the trace.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>
#include <string>
#include <utility>
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
  const uint32_t s3 = ids.id(FieldValue{ValueKind::String, false, 0, "3", {}});
  const uint32_t n3 = ids.id(FieldValue{ValueKind::Number, false, 3, {}, {}});
  const uint32_t n30 = ids.id(FieldValue{ValueKind::Number, false, 3.0, {}, {}});
  const uint32_t t = ids.id(FieldValue{ValueKind::Bool, true, 0, {}, {}});
  const uint32_t zero = ids.id(FieldValue{ValueKind::Number, false, 0.0, {}, {}});
  const uint32_t minus_zero = ids.id(FieldValue{ValueKind::Number, false, -0.0, {}, {}});
  EXPECT_NE(s3, n3);
  EXPECT_EQ(n3, n30);
  EXPECT_NE(t, n3);
  EXPECT_EQ(zero, minus_zero);
  EXPECT_EQ(ids.id(FieldValue{ValueKind::Null, false, 0, {}, {}}), 0u);
  EXPECT_EQ(ids.id(FieldValue{ValueKind::Object, false, 0, {}, {}}), 0u);
  EXPECT_EQ(ids.size(), 4u);
}

// --explain names a value by its JSON text, as it would appear in a message.
TEST(BoundValues, NameTheirValuesAsJson) {
  io::BoundValues ids;
  using io::FieldValue, io::ValueKind;
  const uint32_t s = ids.id(FieldValue{ValueKind::String, false, 0, "a \"b\"\\c", {}});
  const uint32_t n = ids.id(FieldValue{ValueKind::Number, false, 2.5, {}, {}});
  const uint32_t f = ids.id(FieldValue{ValueKind::Bool, false, 0, {}, {}});
  const uint32_t digits = ids.id(FieldValue{ValueKind::String, false, 0, "3", {}});
  EXPECT_EQ(ids.json(s), R"("a \"b\"\\c")");
  EXPECT_EQ(ids.json(n), "2.5");
  EXPECT_EQ(ids.json(f), "false");
  EXPECT_EQ(ids.json(digits), "\"3\"");  // the string, not the number
  EXPECT_EQ(ids.json(0), "");
  EXPECT_EQ(ids.json(99), "");
}

// ---------------------------------------------------------------- --explain

// A Checker with --explain over messages given as key -> value id (0: the
// field is missing and its tests keep their values). Collects (time,
// sentences) per violation start; values are named as JSON text by `names`
// (as the decoders' ids would be), or by where they were bound without it.
struct ExplainDriver {
  using Explained = std::vector<std::pair<double, std::vector<std::string>>>;
  Checker checker;
  Explained explained;
  std::vector<std::pair<double, bool>> verdicts;
  std::vector<uint8_t> atoms;
  std::vector<uint32_t> bound;

  ExplainDriver(TimeModel model, const std::string& spec, const std::vector<std::string>& names)
      : checker(model, false, [this](const Verdict& v) {
          verdicts.emplace_back(v.time, v.value);
          if (v.explanation) explained.emplace_back(v.time, *v.explanation);
        }) {
    checker.enable_explain();
    if (!names.empty())
      checker.set_value_names([names](uint32_t id) { return id <= names.size() ? names[id - 1] : std::string(); });
    checker.add_property({"p", spec});
    atoms.assign(checker.atoms().size(), 0);
    bound.assign(checker.atoms().size(), 0);
  }
  void set(const std::map<std::string, uint32_t>& message) {
    const auto& tests = checker.atoms().tests();
    for (const auto& [key, v] : message)
      for (size_t id = 0; id < tests.size(); ++id)
        if (tests[id].op == spec::FieldTest::Op::Bind && tests[id].key() == key && v != 0) bound[id] = v;
  }
  void step(const std::map<std::string, uint32_t>& message) {
    set(message);
    checker.step(atoms.data(), bound.data());
  }
  // Dense: `message` holds over [begin, end).
  void step(double begin, double end, const std::map<std::string, uint32_t>& message) {
    set(message);
    checker.step(begin, end, atoms.data(), bound.data());
  }
};
using Explained = ExplainDriver::Explained;

TEST(DataExplain, ForallNamesTheValueThatMadeItFalse) {
  const std::string spec = "forall[f]. ({close: *f} -> once{open: *f})";
  for (const bool named : {true, false}) {
    ExplainDriver d(TimeModel::Discrete, spec, named ? std::vector<std::string>{"\"a.txt\"", "\"b.txt\""}
                                                     : std::vector<std::string>{});
    d.step({{"open", 1}});   // 0: a opened
    d.step({{"close", 1}});  // 1: a closed
    d.step({{"close", 2}});  // 2: b closed, never opened
    const std::string b = named ? "\"b.txt\"" : "the value of close at step 2";
    EXPECT_EQ(d.verdicts, (std::vector<std::pair<double, bool>>{{0, true}, {2, false}}));
    EXPECT_EQ(d.explained,
              (Explained{{2,
                          {"(forall[f]. ({close: *f} implies (once {open: *f}))) is false: ({close: *f} implies "
                           "(once {open: *f})) is false for f = " + b,
                           "for f = " + b + ": {close: *f} is true at step 2",
                           "for f = " + b + ": (once {open: *f}) is false: {open: *f} never held at steps 0..2",
                           "for f = " + b + ": {open: *f} is false at step 2"}}}));
  }
}

TEST(DataExplain, ForallFalseForValuesNotSeenYetAndForSeveral) {
  // once{id: *x} is false for every value not seen yet.
  ExplainDriver d(TimeModel::Discrete, "forall[x]. once{id: *x}", {"1"});
  d.step({{"id", 1}});
  EXPECT_EQ(d.explained,
            (Explained{{0,
                        {"(forall[x]. (once {id: *x})) is false: (once {id: *x}) is false for x = any value not seen "
                         "yet",
                         "for x = any value not seen yet: (once {id: *x}) is false: {id: *x} never held at step 0",
                         "for x = any value not seen yet: {id: *x} is false at step 0"}}}));
  // "every id seen is the current one": at step 2 (id 3) it fails for 1 and for 2; the first
  // is named, the other counted. Read directly from the monitor (the violation started at 1).
  AtomTable atoms;
  const std::string spec = "forall[x]. (once{id: *x} -> {id: *x})";
  data::DiscreteMonitor m(compile(*spec::parse(spec, {}), atoms, TimeModel::Discrete, spec), "p", 100);
  m.enable_explain();
  const uint8_t none[1] = {0};
  for (const uint32_t id : {1u, 2u, 3u}) m.step(none, &id);
  const explain::ValueNames names = [](uint32_t id) { return std::to_string(id); };
  EXPECT_EQ(m.explain(&names),
            (std::vector<std::string>{
                "(forall[x]. ((once {id: *x}) implies {id: *x})) is false: ((once {id: *x}) implies {id: *x}) is false "
                "for x = 1 (and for 1 other value)",
                "for x = 1: (once {id: *x}) is true: {id: *x} held at least once at steps 0..2",
                "for x = 1: {id: *x} is false at step 2"}));
}

TEST(DataExplain, ExistsFalseIsExplainedForTheValuesBoundNow) {
  // A login by a user who failed 1 or 2 steps before.
  ExplainDriver d(TimeModel::Discrete, "exists[u]. ({login: *u} and once[1:2]{failed: *u})", {"\"bob\"", "\"eve\""});
  d.step({{"failed", 1}});  // 0: bob failed; nobody logged in
  d.step({{"login", 1}});   // 1: bob logs in: true
  d.step({{"login", 2}});   // 2: eve logs in, never failed
  const std::string text = "(exists[u]. ({login: *u} and (once[1:2] {failed: *u})))";
  const std::string body = "({login: *u} and (once[1:2] {failed: *u}))";
  EXPECT_EQ(d.verdicts, (std::vector<std::pair<double, bool>>{{0, false}, {1, true}, {2, false}}));
  EXPECT_EQ(d.explained,
            (Explained{{0,
                        {text + " is false: " + body + " is false for every value of u (1 seen so far, and any other)",
                         "for u = \"bob\": {login: *u} is false at step 0"}},
                       {2,
                        {text + " is false: " + body + " is false for every value of u (2 seen so far, and any other)",
                         "for u = \"eve\": (once[1:2] {failed: *u}) is false: {failed: *u} never held at steps "
                         "0..1"}}}));
}

TEST(DataExplain, DenseForallAndExists) {
  // open a on [0, 0.5), then b; a closed at 1: once[0:1]{open: a} holds until 0.5 + 1 = 1.5.
  ExplainDriver d(TimeModel::Dense, "forall[f]. ({close: *f} -> once[0:1]{open: *f})", {});
  d.step(0, 0.5, {{"open", 1}});
  d.step(0.5, 1, {{"open", 2}});
  d.step(1, 3, {{"close", 1}});
  const std::string a = "the value of open at time 0";
  EXPECT_EQ(d.verdicts, (std::vector<std::pair<double, bool>>{{0, true}, {1.5, false}}));
  EXPECT_EQ(d.explained,
            (Explained{{1.5,
                        {"(forall[f]. ({close: *f} implies (once[:1] {open: *f}))) is false: ({close: *f} implies "
                         "(once[:1] {open: *f})) is false for f = " + a,
                         "for f = " + a + ": {close: *f} is true throughout [1, 3)",
                         "for f = " + a + ": (once[:1] {open: *f}) is false: {open: *f} never held in [0.5, 1.5]",
                         "for f = " + a + ": {open: *f} is false throughout [1, 3)"}}}));

  ExplainDriver e(TimeModel::Dense, "exists[u]. ({login: *u} and once[1:2]{failed: *u})", {"\"bob\""});
  e.step(0, 1.5, {{"failed", 1}});
  e.step(1.5, 4, {{"login", 1}});  // bob failed from 0 on: once[1:2] holds from 1
  EXPECT_EQ(e.verdicts, (std::vector<std::pair<double, bool>>{{0, false}, {1.5, true}}));
  EXPECT_EQ(e.explained,
            (Explained{{0,
                        {"(exists[u]. ({login: *u} and (once[1:2] {failed: *u}))) is false: ({login: *u} and "
                         "(once[1:2] {failed: *u})) is false for every value of u (1 seen so far, and any other)",
                         "for u = \"bob\": {login: *u} is false throughout [0, 1.5)"}}}));
}

// Without quantifiers the data monitor's walk says what the shared discrete
// monitor says, sentence for sentence (one wording for both).
TEST(DataExplain, SameSentencesAsTheDiscreteMonitor) {
  const std::vector<std::string> specs = {
      "historically({e} -> once[0:1]{h})", "{a} since[1:3] {b}", "pre {a} or not once[2:4]{b}",
      "historically[0:2]({a} && !{b}) || {a} since {b}", "once[1:]{a} -> historically[:2]{b}"};
  std::mt19937 rng(5);
  for (const std::string& spec : specs) {
    AtomTable atoms;
    const Program program = compile(*spec::parse(spec, {}), atoms, TimeModel::Discrete, spec);
    discrete::Monitor plain;
    plain.add(program);
    data::DiscreteMonitor walked(program, "p", 100);
    std::vector<uint8_t> values(atoms.size());
    for (int step = 0; step < 40; ++step) {
      for (auto& v : values) v = rng() % 3 == 0;
      plain.step(values.data());
      walked.step(values.data(), nullptr);
      ASSERT_EQ(walked.explain(), plain.explain(0)) << spec << " at step " << step;
    }
  }
}

}  // namespace
}  // namespace rvc::engine
