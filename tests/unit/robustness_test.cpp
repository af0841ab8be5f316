// Robustness semantics (src/engine/robust): sliding-window extrema checked
// against a direct computation over every window, and a property's values
// computed by hand. Reelay itself is the oracle of tests/differential
// (test_robustness_differential.py).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "engine/checker.hpp"
#include "engine/robust/window.hpp"
#include "spec/spec_error.hpp"

namespace rvc::engine::robust {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(RobustWindow, ExtremaEqualADirectScanOfEveryWindow) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> value(-50, 50);
  for (auto [lo, hi] : {std::pair<Step, Step>{0, 0}, {0, 3}, {2, 5}, {4, 4}, {3, kForever}, {0, kForever}}) {
    Window<true> max(lo, hi, true);
    Window<false> min(lo, hi, true);
    std::vector<double> seen;
    for (Step now = 0; now < 200; ++now) {
      seen.push_back(value(rng));
      double want_max = -kInf, want_min = kInf;
      for (Step j = 0; j <= now; ++j)
        if (now - j >= lo && now - j <= hi) {
          want_max = std::max(want_max, seen[j]);
          want_min = std::min(want_min, seen[j]);
        }
      ASSERT_EQ(max.update(now, seen.back()), want_max) << "lo " << lo << " hi " << hi << " step " << now;
      ASSERT_EQ(min.update(now, seen.back()), want_min) << "lo " << lo << " hi " << hi << " step " << now;
    }
  }
}

TEST(RobustChecker, HandComputedValues) {
  std::vector<std::pair<std::string, double>> got;
  Checker checker(TimeModel::Discrete, true,
                  [&](const Verdict& v) { got.emplace_back(v.property, v.robustness); });
  checker.enable_robustness();
  checker.add_property({"a", "{x > 3} since {y > 1}"});
  checker.add_property({"b", "historically[0:1]({x > 3} -> {y < 2})"});
  // atoms in table order: {x > 3}, {y > 1}, {y < 2}
  const double steps[][3] = {{2, -1, 1}, {0, 3, -2}, {-2, 0, 1}, {4, -3, 4}};
  for (const auto& m : steps) checker.step_robust(m);
  // a: max(y>1, min(x>3, previous)): -1, 3, max(0, min(-2, 3)) = 0, max(-3, min(4, 0)) = 0
  // b: (x>3 -> y<2) = max(-(x>3), y<2): -1... window of 2 steps, minimum
  //    step 0: max(-2, 1) = 1; 1: max(0, -2) = 0; 2: max(2, 1) = 2; 3: max(-4, 4) = 4
  //    windows: 1, min(1, 0) = 0, min(0, 2) = 0, min(2, 4) = 2
  EXPECT_EQ(got, (std::vector<std::pair<std::string, double>>{
                     {"a", -1}, {"b", 1}, {"a", 3}, {"b", 0}, {"a", 0}, {"b", 0}, {"a", 0}, {"b", 2}}));
  EXPECT_EQ(checker.violations(), 5u);  // robustness <= 0 is not a pass: a -1, 0, 0 and b 0, 0
}

TEST(RobustChecker, BoundedSinceIsRefusedWithItsReason) {
  Checker checker(TimeModel::Discrete, false, nullptr);
  checker.enable_robustness();
  EXPECT_THROW(checker.add_property({"p", "{x > 1} since[0:2] {y > 1}"}), spec::SpecError);
  Checker dense(TimeModel::Dense, false, nullptr);
  EXPECT_THROW(dense.enable_robustness(), std::invalid_argument);
}

}  // namespace
}  // namespace rvc::engine::robust

