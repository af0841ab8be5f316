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
}

// Dense time: x = 1 on [0, 1), 3 on [1, 2.5), 0 on [2.5, 3), 5 on [3, 6), 2 on [6, 7); the
// margins of {x > 2} are -1, 1, -2, 3, 0. Windows are closed, pieces right-open; values worked
// out by hand (and equal to Reelay 25's).
TEST(RobustDense, WindowsOverPiecesByHand) {
  const std::pair<double, double> pieces[] = {{0, -1}, {1, 1}, {2.5, -2}, {3, 3}, {6, 0}};
  const auto run = [&](const std::string& spec) {
    std::vector<std::pair<double, double>> out;
    Checker c(TimeModel::Dense, false, [&](const Verdict& v) { out.emplace_back(v.time, v.robustness); });
    c.enable_robustness();
    c.add_property({"p", spec});
    for (size_t i = 0; i < std::size(pieces); ++i) {
      const double margin = pieces[i].second;
      c.step_robust(pieces[i].first, i + 1 < std::size(pieces) ? pieces[i + 1].first : 7.0, &margin);
    }
    return out;
  };
  using V = std::vector<std::pair<double, double>>;
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(run("once{x > 2}"), (V{{0, -1}, {1, 1}, {3, 3}}));
  EXPECT_EQ(run("once[1:2]{x > 2}"), (V{{0, -inf}, {1, -1}, {2, 1}, {4, 3}}));
  EXPECT_EQ(run("historically[0:1]{x > 2}"), (V{{0, -1}, {2, 1}, {2.5, -2}, {4, 3}, {6, 0}}));
  EXPECT_EQ(run("historically[1:2]{x > 2}"), (V{{0, inf}, {1, -1}, {3, 1}, {3.5, -2}, {5, 3}}));
  EXPECT_EQ(run("not once[0.5:]{x > 2}"), (V{{0, inf}, {0.5, 1}, {1.5, -1}, {3.5, -3}}));
  Checker refuses(TimeModel::Dense, false, nullptr);
  refuses.enable_robustness();
  EXPECT_THROW(refuses.add_property({"p", "{x > 2} since {x < 1}"}), spec::SpecError);
}

}  // namespace
}  // namespace rvc::engine::robust

