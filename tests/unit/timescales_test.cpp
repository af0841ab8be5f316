// Timescales generator: reproducible bytes, the 30 published formulas, and
// every family's trace satisfying its (intended) formula.
#include <gtest/gtest.h>
#include <simdjson.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "io/json_decoder.hpp"
#include "tools/timescales.hpp"

namespace rvc::tools {
namespace {

std::string generate(const TimescalesOptions& o) {
  char* data = nullptr;
  size_t size = 0;
  std::FILE* f = open_memstream(&data, &size);
  EXPECT_NE(f, nullptr);
  try {
    generate_timescales(o, f);
  } catch (...) {  // the stream must not leak when a test expects a throw (ASan tier)
    std::fclose(f);
    std::free(data);
    throw;
  }
  std::fclose(f);
  std::string out(data, size);
  std::free(data);
  return out;
}

TimescalesOptions opts(const std::string& family, int64_t ubound, uint64_t duration, uint64_t seed) {
  TimescalesOptions o;
  o.family = family;
  o.ubound = ubound;
  o.duration = duration;
  o.seed = seed;
  return o;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST(Timescales, TenFamilies) {
  EXPECT_EQ(timescales_families(),
            (std::vector<std::string>{"AbsentAQ", "AbsentBQR", "AbsentBR", "AlwaysAQ", "AlwaysBQR", "AlwaysBR",
                                      "RecurBQR", "RecurGLB", "RespondBQR", "RespondGLB"}));
  EXPECT_TRUE(is_timescales_family("RecurGLB"));
  EXPECT_FALSE(is_timescales_family("recurglb"));
  EXPECT_THROW(timescales_formula("Nope", 3, 10), std::invalid_argument);
  EXPECT_THROW(generate(opts("Nope", 10, 10, 1)), std::invalid_argument);
}

TEST(Timescales, DefaultLowerBoundIsThirtyPercent) {
  TimescalesOptions o;
  o.ubound = 10;
  EXPECT_EQ(effective_lbound(o), 3);
  o.ubound = 1000;
  EXPECT_EQ(effective_lbound(o), 300);
  o.ubound = 15;
  EXPECT_EQ(effective_lbound(o), 4);  // 4.5 rounds down
  o.lbound = 7;
  EXPECT_EQ(effective_lbound(o), 7);  // explicit wins
}

TEST(Timescales, SameSeedSameBytes) {
  for (const std::string& family : timescales_families()) {
    std::string a = generate(opts(family, 10, 3000, 42));
    std::string b = generate(opts(family, 10, 3000, 42));
    EXPECT_EQ(a, b) << family;
    EXPECT_FALSE(a.empty()) << family;
  }
}

TEST(Timescales, DifferentSeedsDiffer) {
  for (const std::string& family : timescales_families()) {
    EXPECT_NE(generate(opts(family, 10, 3000, 1)), generate(opts(family, 10, 3000, 2))) << family;
  }
}

TEST(Timescales, ExactlyDurationLinesWithStepTimesAndTheFamilysPropositions) {
  const std::map<std::string, std::string> props = {
      {"AbsentAQ", "pq"}, {"AbsentBQR", "pqr"}, {"AbsentBR", "pr"},   {"AlwaysAQ", "pq"},     {"AlwaysBQR", "pqr"},
      {"AlwaysBR", "pr"}, {"RecurBQR", "pqr"},  {"RecurGLB", "p"},    {"RespondBQR", "pqrs"}, {"RespondGLB", "ps"}};
  for (const auto& [family, names] : props) {
    std::vector<std::string> ls = lines(generate(opts(family, 10, 257, 5)));
    ASSERT_EQ(ls.size(), 257u) << family;
    for (size_t i = 0; i < ls.size(); ++i) {
      std::string expected_start = "{\"time\":" + std::to_string(i) + ",";
      ASSERT_EQ(ls[i].rfind(expected_start, 0), 0u) << family << ": " << ls[i];
      for (char p : std::string("pqrs")) {
        bool has = ls[i].find(std::string("\"") + p + "\":") != std::string::npos;
        ASSERT_EQ(has, names.find(p) != std::string::npos) << family << ": " << ls[i];
      }
    }
  }
}

// The 30 lines of shared/reference/timescales-formulas.tsv (name, formula),
// copied here verbatim.
const std::vector<std::pair<std::string, std::string>> kPublished = {
    {"AbsentAQ10", "historically((once[:10]{q}) -> ((not{p}) since {q}))"},
    {"AbsentAQ100", "historically((once[:100]{q}) -> ((not{p}) since {q}))"},
    {"AbsentAQ1000", "historically((once[:1000]{q}) -> ((not{p}) since {q}))"},
    {"AbsentBQR10", "historically({r} && !{q} && once{q}) -> ((not{p}) since[3:10] {q})"},
    {"AbsentBQR100", "historically({r} && !{q} && once{q}) -> ((not{p}) since[30:100] {q})"},
    {"AbsentBQR1000", "historically({r} && !{q} && once{q}) -> ((not{p}) since[300:1000] {q})"},
    {"AbsentBR10", "historically({r} -> (historically[:10](not{p})))"},
    {"AbsentBR100", "historically({r} -> (historically[:100](not{p})))"},
    {"AbsentBR1000", "historically({r} -> (historically[:1000](not{p})))"},
    {"AlwaysAQ10", "historically((once[:10]{q}) -> ({p} since {q}))"},
    {"AlwaysAQ100", "historically((once[:100]{q}) -> ({p} since {q}))"},
    {"AlwaysAQ1000", "historically((once[:1000]{q}) -> ({p} since {q}))"},
    {"AlwaysBQR10", "historically(({r} && !{q} && once{q}) -> ({p} since[3:10] {q}))"},
    {"AlwaysBQR100", "historically(({r} && !{q} && once{q}) -> ({p} since[30:100] {q}))"},
    {"AlwaysBQR1000", "historically(({r} && !{q} && once{q}) -> ({p} since[300:1000] {q}))"},
    {"AlwaysBR10", "historically({r} -> (historically[:10]{p}))"},
    {"AlwaysBR100", "historically({r} -> (historically[:100]{p}))"},
    {"AlwaysBR1000", "historically({r} -> (historically[:1000]{p}))"},
    {"RecurBQR10", "historically(({r} && !{q} && once{q}) -> ((once[:10]({p} or {q})) since {q}))"},
    {"RecurBQR100", "historically(({r} && !{q} && once{q}) -> ((once[:100]({p} or {q})) since {q}))"},
    {"RecurBQR1000", "historically(({r} && !{q} && once{q}) -> ((once[:1000]({p} or {q})) since {q}))"},
    {"RecurGLB10", "historically(once[:10]{p})"},
    {"RecurGLB100", "historically(once[:100]{p})"},
    {"RecurGLB1000", "historically(once[:1000]{p})"},
    {"RespondBQR10",
     "historically(({r} && !{q} && once{q}) -> ( (({s} -> once[3:10]{p}) and not((not {s}) since[10:] {p})) since {q}))"},
    {"RespondBQR100",
     "historically(({r} && !{q} && once{q}) -> ( (({s} -> once[30:100]{p}) and not((not {s}) since[100:] {p})) since "
     "{q}))"},
    {"RespondBQR1000",
     "historically(({r} && !{q} && once{q}) -> ( (({s} -> once[300:1000]{p}) and not((not {s}) since[1000:] {p})) "
     "since {q}))"},
    {"RespondGLB10", "historically(({s} -> once[3:10]{p}) and not((not {s}) since[10:] {p}))"},
    {"RespondGLB100", "historically(({s} -> once[30:100]{p}) and not((not {s}) since[100:] {p}))"},
    {"RespondGLB1000", "historically(({s} -> once[300:1000]{p}) and not((not {s}) since[1000:] {p}))"},
};

TEST(Timescales, PublishedFormulas) {
  ASSERT_EQ(kPublished.size(), 30u);
  for (const auto& [name, formula] : kPublished) {
    std::string family = name.substr(0, name.find_first_of("0123456789"));
    int64_t u = std::stoll(name.substr(family.size()));
    TimescalesOptions o;
    o.family = family;
    o.ubound = u;
    EXPECT_EQ(timescales_formula(family, effective_lbound(o), u), formula) << name;
  }
}

TEST(Timescales, IntendedAbsentBQRBracketsTheWholeImplication) {
  EXPECT_EQ(timescales_formula("AbsentBQR", 3, 10, /*intended=*/true),
            "historically(({r} && !{q} && once{q}) -> ((not{p}) since[3:10] {q}))");
  // Other families are unchanged by `intended`.
  EXPECT_EQ(timescales_formula("AlwaysBQR", 3, 10, true), timescales_formula("AlwaysBQR", 3, 10, false));
}

// Runs `formula` over a generated trace with the discrete checker; returns
// the number of violations and, through `seen`, how often each atom held.
uint64_t check(const std::string& formula, const std::string& trace, std::map<std::string, int>* seen = nullptr) {
  engine::Checker checker(engine::TimeModel::Discrete, false, nullptr);
  checker.add_property({"f", formula});
  io::JsonDecoder decoder(checker.atoms(), io::DecoderOptions{});
  simdjson::ondemand::parser parser;
  for (const std::string& line : lines(trace)) {
    simdjson::padded_string padded(line);
    simdjson::ondemand::document doc = parser.iterate(padded);
    std::string error;
    EXPECT_TRUE(decoder.decode(doc.get_object(), error)) << error;
    decoder.commit();
    checker.step(decoder.values());
    if (seen)
      for (size_t i = 0; i < checker.atoms().size(); ++i)
        (*seen)[checker.atoms().tests()[i].to_string()] += decoder.values()[i];
  }
  return checker.violations();
}

TEST(Timescales, EveryFamilysTraceSatisfiesItsIntendedFormula) {
  for (const std::string& family : timescales_families()) {
    for (int64_t u : {10, 100}) {
      for (uint64_t seed : {1, 7}) {
        TimescalesOptions o = opts(family, u, 6000, seed);
        std::string formula = timescales_formula(family, effective_lbound(o), u, /*intended=*/true);
        std::map<std::string, int> seen;
        EXPECT_EQ(check(formula, generate(o), &seen), 0u) << family << u << " seed " << seed << ": " << formula;
        // The trace exercises the pattern: every proposition holds somewhere.
        for (const auto& [atom, count] : seen) EXPECT_GT(count, 0) << family << u << ": {" << atom << "} never held";
      }
    }
  }
}

TEST(Timescales, TheCheckCanFail) {
  // After q, AlwaysAQ holds p for U steps, which is exactly what AbsentAQ forbids.
  std::string always = generate(opts("AlwaysAQ", 10, 500, 3));
  EXPECT_GT(check(timescales_formula("AbsentAQ", 3, 10), always), 0u);
  // RecurGLB with a tighter bound than the trace was made for: gaps of up to
  // 99 steps without p break once[:10].
  std::string sparse = generate(opts("RecurGLB", 100, 2000, 3));
  EXPECT_GT(check(timescales_formula("RecurGLB", 3, 10), sparse), 0u);
}

}  // namespace
}  // namespace rvc::tools
