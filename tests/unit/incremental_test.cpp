// The optimized evaluation (comparisons of one field with many constants
// evaluated together, io/threshold_index.hpp; change-driven stepping,
// discrete::Monitor::step_changed) gives exactly the verdicts of the plain
// path (PipelineOptions::incremental = false, `--plain-eval`), which
// evaluates every test and steps every operator at every message.
//
// Oracle: the plain path, itself checked against Reelay (tests/differential).
// Random suites of many properties sharing numeric fields compared with many
// constants, over random traces (random walks and jumps, missing fields,
// wrong types, NaN, integers beyond 2^53), JSON and typed (CDR), discrete and
// dense, Boolean and robustness, changes only and --all, with --explain.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "engine/discrete/monitor.hpp"
#include "io/cdr_codec.hpp"
#include "io/threshold_index.hpp"
#include "msg/type_registry.hpp"
#include "runtime/pipeline.hpp"
#include "spec/parser.hpp"

namespace rvc {
namespace {

const char* kType = "bool flag\nint32 i\nfloat64 x\nint64 big\nfloat32 f\nt_msgs/In inner\nfloat64 t\n";
const char* kInner = "float32 y\nbool on\n";

struct Types {
  msg::TypeRegistry reg;
  const msg::MessageType* type;
  Types() {
    reg.add_definition("t_msgs/msg/In", kInner, "test");
    reg.add_definition("t_msgs/msg/Nums", kType, "test");
    type = &reg.resolve("t_msgs/msg/Nums");
  }
};

using Rng = std::mt19937;
int pick(Rng& rng, int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); }

// Constants from a small set, so that each field and operator gets several
// (grouped) and some repeat (equal constants in one group).
std::string constant(Rng& rng) {
  const char* ks[] = {"-3", "-0.5", "0", "1", "2", "2.5", "3", "4", "7", "10", "12.25", "20", "1e3"};
  return ks[pick(rng, 13)];
}

std::string atom(Rng& rng) {
  const char* fields[] = {"i", "x", "f", "inner.y", "big"};
  const char* ops[] = {">", ">=", "<", "<=", ">", "<", "==", "!="};
  switch (pick(rng, 6)) {
    case 0: return "{flag}";
    case 1: return "{inner.on}";
    default: return std::string("{") + fields[pick(rng, 5)] + " " + ops[pick(rng, 8)] + " " + constant(rng) + "}";
  }
}

std::string bounds(Rng& rng, bool dense) {
  const int lo = pick(rng, 4), width = 1 + pick(rng, 5);
  const std::string half = dense && pick(rng, 2) ? ".5" : "";
  switch (pick(rng, 5)) {
    case 0: return "[" + std::to_string(lo) + ":" + std::to_string(lo + width) + half + "]";
    case 1: return "[" + std::to_string(lo + 1) + ":]";
    case 2: return "[:" + std::to_string(width) + half + "]";
    default: return "";
  }
}

std::string formula(Rng& rng, int depth, bool dense) {
  if (depth == 0 || pick(rng, 5) == 0) return atom(rng);
  auto sub = [&] { return "(" + formula(rng, depth - 1, dense) + ")"; };
  switch (pick(rng, dense ? 8 : 9)) {
    case 0: return "not " + sub();
    case 1: return "once" + bounds(rng, dense) + " " + sub();
    case 2: return "historically" + bounds(rng, dense) + " " + sub();
    case 3:
    case 4: return sub() + " since" + bounds(rng, dense) + " " + sub();
    case 5: return sub() + " and " + sub();
    case 6: return sub() + " or " + sub();
    case 7: return sub() + " -> " + sub();
    default: return "pre " + sub();
  }
}

std::vector<engine::PropertySpec> suite(Rng& rng, bool dense, int n) {
  std::vector<engine::PropertySpec> out;
  for (int k = 0; k < n; ++k) {
    // A third are single comparisons (each group's atoms seen directly), the
    // rest random formulas; some the benchmark's shape, whose historically dies.
    std::string spec = k % 3 == 0 ? atom(rng)
                       : k % 7 == 1 ? "historically((" + formula(rng, 2, dense) + ") -> (" + formula(rng, 2, dense) +
                                          ")) || " + atom(rng)
                                    : formula(rng, 1 + pick(rng, 4), dense);
    out.push_back({"p" + std::to_string(k), spec});
  }
  return out;
}

std::string number(double d) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", d);
  return buf;
}

// A message: numbers mostly walk (few atoms change), sometimes jump;
// `json_only`: also missing fields, wrong types, null, NaN and 2^53 + 1,
// which typed samples cannot carry.
std::string message(Rng& rng, double t, double& walk, bool json_only) {
  walk += pick(rng, 3) - 1;
  if (pick(rng, 10) == 0) walk = pick(rng, 30) - 8;
  auto value = [&](bool integer) -> std::string {
    if (json_only) {
      switch (pick(rng, 40)) {
        case 0: return "\"3\"";
        case 1: return "null";
        case 2: return "true";
        case 3: return "NaN";
        case 4: return "9007199254740993";
        case 5: return "-Infinity";
        default: break;
      }
    }
    const double v = integer ? walk : walk + 0.25 * pick(rng, 4);
    return integer ? std::to_string(static_cast<long long>(v)) : number(v);
  };
  std::string j = "{";
  auto field = [&](const std::string& key, const std::string& v) {
    if (json_only && pick(rng, 8) == 0) return;  // missing: keeps its value
    j += (j.size() > 1 ? "," : "") + ("\"" + key + "\":") + v;
  };
  field("flag", pick(rng, 3) ? "true" : "false");
  field("i", value(true));
  field("x", value(false));
  field("big", value(true));
  field("f", value(false));
  j += std::string(j.size() > 1 ? "," : "") + "\"inner\":{\"y\":" + value(false) + ",\"on\":" +
       (pick(rng, 2) ? "true" : "false") + "}";
  j += ",\"t\":" + number(t) + "}";
  return j;
}

struct Outcome {
  std::vector<std::string> verdicts;
  runtime::PipelineStats stats;
};

struct Config {
  bool dense, robustness, all, explain, typed, incremental;
};

Outcome run(const std::vector<engine::PropertySpec>& props, const std::vector<std::string>& jsons, const Config& c,
        const msg::MessageType* type) {
  runtime::PipelineOptions o;
  o.model = c.dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete;
  o.emit_all = c.all;
  o.robustness = c.robustness;
  o.explain = c.explain;
  o.time_field = "t";
  o.max_reported = 0;
  o.incremental = c.incremental;
  if (c.typed) o.type = type;
  Outcome r;
  runtime::Pipeline p(props, o, [&](const engine::Verdict& v) {
    std::string s = v.property + "@" + number(v.time) + (v.value ? "T" : "F");
    if (v.robust) s += " r=" + number(v.robustness);
    if (v.explanation)
      for (const auto& why : *v.explanation) s += " | " + why;
    r.verdicts.push_back(s);
  });
  uint64_t seq = 0;
  for (const auto& j : jsons) {
    if (c.typed) {
      std::string sample, error;
      EXPECT_TRUE(io::json_to_cdr(*type, j, sample, error, {})) << error;
      p.feed(sample, ++seq);
    } else {
      p.feed(j, ++seq);
    }
  }
  p.end_of_input();  // dense: the end-of-input tick
  r.stats = p.stats();
  return r;
}

std::string first_difference(const Outcome& a, const Outcome& b) {
  for (size_t i = 0; i < std::min(a.verdicts.size(), b.verdicts.size()); ++i)
    if (a.verdicts[i] != b.verdicts[i]) return "verdict " + std::to_string(i) + ": " + a.verdicts[i] + " vs " + b.verdicts[i];
  return "counts " + std::to_string(a.verdicts.size()) + " vs " + std::to_string(b.verdicts.size());
}

TEST(Incremental, SameVerdictsAsThePlainPath) {
  Types types;
  int compared = 0;
  for (int seed = 0; seed < 24; ++seed) {
    Rng rng(9100 + seed);
    const Config base{seed % 2 == 1, seed % 3 == 2, seed % 4 == 3, false, seed % 5 >= 3, true};
    Config c = base;
    c.explain = !c.robustness && seed % 6 == 0;
    const auto props = suite(rng, c.dense, 40 + pick(rng, 80));
    std::vector<std::string> jsons;
    double walk = 2;
    for (int m = 0; m < 300; ++m) jsons.push_back(message(rng, 0.5 * m + 0.25 * pick(rng, 2), walk, !c.typed));
    Config plain = c;
    plain.incremental = false;
    const Outcome fast = run(props, jsons, c, types.type), slow = run(props, jsons, plain, types.type);
    ASSERT_GT(slow.verdicts.size(), props.size()) << "seed " << seed;
    EXPECT_EQ(fast.verdicts, slow.verdicts) << "seed " << seed << " dense " << c.dense << " robust " << c.robustness
                                            << " all " << c.all << " explain " << c.explain << " typed " << c.typed
                                            << "\n" << first_difference(fast, slow);
    EXPECT_EQ(fast.stats.accepted, slow.stats.accepted);
    EXPECT_EQ(fast.stats.warnings, slow.stats.warnings);
    EXPECT_EQ(fast.stats.rejected, slow.stats.rejected);
    ++compared;
  }
  EXPECT_EQ(compared, 24);
}

// Thresholds against a direct evaluation: every group's atoms after every
// value, whatever the order of constants and values (NaN, infinities, ties).
TEST(Incremental, ThresholdIndexEqualsEachComparison) {
  Rng rng(77);
  for (int round = 0; round < 50; ++round) {
    std::vector<spec::FieldTest> tests;
    std::vector<int> ids;
    const char* ops[] = {">", ">=", "<", "<=", "==", "!="};
    for (int k = 0; k < 30; ++k) {
      const std::string text = std::string("{v ") + ops[pick(rng, 6)] + " " + std::to_string(pick(rng, 9) - 4) +
                               (pick(rng, 2) ? ".5" : "") + "}";
      tests.push_back(spec::parse(text)->test);
      ids.push_back(k);
    }
    io::ThresholdIndex index;
    std::vector<int> rest;
    index.build(ids, tests, rest);
    ASSERT_FALSE(index.empty());
    std::vector<uint8_t> atoms(tests.size(), 0);  // all false: no value yet
    for (int m = 0; m < 200; ++m) {
      const double values[] = {std::nan(""), INFINITY, -INFINITY, 0.0, -0.0};
      const double d = pick(rng, 8) == 0 ? values[pick(rng, 5)] : 0.5 * (pick(rng, 21) - 10);
      index.apply(d, atoms.data());
      for (int id : rest) atoms[id] = 2;  // not the index's: left alone
      for (size_t k = 0; k < tests.size(); ++k) {
        if (std::find(rest.begin(), rest.end(), static_cast<int>(k)) != rest.end()) continue;
        const double c = tests[k].value.number;
        using Op = spec::FieldTest::Op;
        const bool want = tests[k].op == Op::Gt ? d > c : tests[k].op == Op::Ge ? d >= c : tests[k].op == Op::Lt ? d < c : d <= c;
        ASSERT_EQ(atoms[k], want ? 1 : 0) << tests[k].to_string() << " at " << d;
      }
    }
  }
}

// Change-driven stepping does less work: 1,000 properties with one operator
// each over one changing atom step only what that atom reaches.
TEST(Incremental, StepsOnlyWhatChanged) {
  engine::AtomTable atoms;
  engine::discrete::Monitor m;
  for (int k = 0; k < 1000; ++k) {
    const auto ast = spec::parse("{a} && {v > " + std::to_string(k) + "}");
    m.add(engine::compile(*ast, atoms, engine::TimeModel::Discrete, ""));
  }
  m.set_prune_dead(true);
  std::vector<uint8_t> values(atoms.size(), 0);
  std::vector<uint32_t> roots;
  m.step_changed(values.data(), nullptr, 0, roots);
  EXPECT_EQ(roots.size(), 1000u);  // the first step: everything
  // {v > 500} turns true: its one operator steps, nothing else.
  uint32_t id = 0;
  for (size_t k = 0; k < atoms.size(); ++k)
    if (atoms.tests()[k].op == spec::FieldTest::Op::Gt && atoms.tests()[k].value.number == 500) id = static_cast<uint32_t>(k);
  values[id] = 1;
  roots.clear();
  m.step_changed(values.data(), &id, 1, roots);
  EXPECT_EQ(m.stepped(), 1u);
  EXPECT_TRUE(roots.empty());  // {a} is false: the value stayed false
}

}  // namespace
}  // namespace rvc
