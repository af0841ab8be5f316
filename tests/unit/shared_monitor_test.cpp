// The discrete monitor beyond Boolean verdicts per property: --explain's
// sentences (written down by hand) and sub-formulas shared between
// properties (checked against a monitor per property, step by step).
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <stdexcept>

#include "engine/checker.hpp"
#include "spec/parser.hpp"

namespace rvc::engine {
namespace {

// --explain: the sentences a violation carries, written down by hand.
TEST(Explain, AViolationSaysWhichSubformulasAndSteps) {
  std::vector<std::pair<double, std::vector<std::string>>> got;
  Checker checker(TimeModel::Discrete, false, [&](const Verdict& v) {
    if (v.explanation) got.emplace_back(v.time, *v.explanation);
  });
  checker.enable_explain();
  checker.add_property({"p", "historically({e} -> once[0:1]{h})"});
  // atoms: {e}, {h}
  const uint8_t steps[][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}, {1, 0}, {1, 0}};
  for (const auto& m : steps) checker.step(m);
  ASSERT_EQ(got.size(), 1u);  // one violation, explained once (not at every false step)
  EXPECT_EQ(got[0].first, 4);
  EXPECT_EQ(got[0].second,
            (std::vector<std::string>{
                "(historically ({e} implies (once[:1] {h}))) is false: ({e} implies (once[:1] {h})) failed at least "
                "once at steps 0..4",
                "{e} is true at step 4", "(once[:1] {h}) is false: {h} never held at steps 3..4",
                "{h} is false at step 4"}));
  // Dense time and data references are explained too (dense_ops_test, data_monitor_test);
  // robustness values are not yet: refused, not silently left without reasons.
  Checker dense(TimeModel::Dense, false, nullptr);
  EXPECT_NO_THROW(dense.enable_explain());
  Checker robust(TimeModel::Discrete, false, nullptr);
  robust.enable_robustness();
  EXPECT_THROW(robust.enable_explain(), std::invalid_argument);
}

}  // namespace
}  // namespace rvc::engine

namespace rvc::engine {
namespace {

// Properties share their common sub-formulas (stepped once per message), and
// still give each its own verdicts: those of a monitor of its own.
TEST(SharedMonitor, CommonSubformulasAreSteppedOnce) {
  std::vector<std::string> specs;
  for (int b : {10, 20, 30, 40, 50, 60, 70, 80})
    specs.push_back("historically(({r} && !{q} && once{q}) -> ({p} since[" + std::to_string(b / 3) + ":" +
                    std::to_string(b) + "] {q}))");
  specs.push_back("once{q} || pre{p}");  // shares once{q} too
  AtomTable shared_atoms;
  discrete::Monitor shared;
  std::vector<std::unique_ptr<discrete::Monitor>> alone;
  size_t alone_ops = 0;
  for (const auto& s : specs) {
    spec::NodePtr ast = spec::parse(s, {});
    ASSERT_TRUE(shared.add(compile(*ast, shared_atoms, TimeModel::Discrete, s)));
    alone.push_back(std::make_unique<discrete::Monitor>());
    alone.back()->add(compile(*ast, shared_atoms, TimeModel::Discrete, s));
    alone_ops += alone.back()->operators();
  }
  // Alone: 6 operators per Timescales shape (and, and, once, since, implies, historically) + 2.
  EXPECT_EQ(alone_ops, 8u * 6 + 3);
  // Shared: `{r} && !{q}`, its `&& once{q}` and once{q} once; since, implies, historically each;
  // then pre{p} and the or.
  EXPECT_EQ(shared.operators(), 3u + 8 * 3 + 2);
  std::mt19937 rng(11);
  std::vector<uint8_t> atoms(shared_atoms.size());
  for (int step = 0; step < 500; ++step) {
    for (auto& a : atoms) a = rng() % 4 == 0;
    shared.step(atoms.data());
    for (size_t k = 0; k < specs.size(); ++k) {
      alone[k]->step(atoms.data());
      ASSERT_EQ(shared.value(k), alone[k]->value(0)) << specs[k] << " at step " << step;
    }
  }
}

}  // namespace
}  // namespace rvc::engine
