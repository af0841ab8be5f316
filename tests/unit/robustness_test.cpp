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

// φ since[lo:hi] ψ is Reelay's rewriting: min(historically[0:lo](φ since ψ), once[lo:hi] ψ).
// a = {x > 3}, b = {y > 1}, margins per step (a, b): (2, -1) (-1, 3) (1, 0) (2, -4) (-2, 5) (3, -1).
//   since (unbounded), max(b, min(a, previous)) from -inf: -1, 3, 1, 1, 5, 3
//   [1:2]: H = min of since over steps t-1..t:   -1, -1, 1, 1, 1, 3
//          O = max of b over steps t-2..t-1:      -inf, -1, 3, 3, 0, 5
//          min(H, O):                             -inf, -1, 1, 1, 0, 3   (Reelay 25 gives these)
//   At step 4 the textbook max over s in {2, 3} of min(b(s), a over (s, 4]) is -2: the rewriting
//   is at least that (its since at step 3 comes from b at step 1).
//   [1:]:  O = max of b over steps 0..t-1:        -inf, -1, 3, 3, 3, 5
//          min(H, O):                             -inf, -1, 1, 1, 1, 3
//   [:2]:  H = since itself; O = max of b over steps t-2..t: -1, 3, 3, 3, 5, 5
//          min(H, O):                             -1, 3, 1, 1, 5, 3
TEST(RobustChecker, BoundedSinceByHand) {
  const auto run = [](const std::string& spec) {
    std::vector<double> got;
    Checker checker(TimeModel::Discrete, true, [&](const Verdict& v) { got.push_back(v.robustness); });
    checker.enable_robustness();
    checker.add_property({"p", spec});
    const double steps[][2] = {{2, -1}, {-1, 3}, {1, 0}, {2, -4}, {-2, 5}, {3, -1}};
    for (const auto& m : steps) checker.step_robust(m);
    return got;
  };
  using V = std::vector<double>;
  EXPECT_EQ(run("{x > 3} since {y > 1}"), (V{-1, 3, 1, 1, 5, 3}));
  EXPECT_EQ(run("{x > 3} since[1:2] {y > 1}"), (V{-kInf, -1, 1, 1, 0, 3}));
  EXPECT_EQ(run("{x > 3} since[1:] {y > 1}"), (V{-kInf, -1, 1, 1, 1, 3}));
  EXPECT_EQ(run("{x > 3} since[:2] {y > 1}"), (V{-1, 3, 1, 1, 5, 3}));
}

// A dense-time robustness Checker over one property, recording every change in `out`.
Checker dense_robust(const std::string& spec, std::vector<std::pair<double, double>>& out) {
  Checker c(TimeModel::Dense, false, [&out](const Verdict& v) { out.emplace_back(v.time, v.robustness); });
  c.enable_robustness();
  c.add_property({"p", spec});
  return c;
}

// Dense time: x = 1 on [0, 1), 3 on [1, 2.5), 0 on [2.5, 3), 5 on [3, 6), 2 on [6, 7); the
// margins of {x > 2} are -1, 1, -2, 3, 0. Windows are closed, pieces right-open; values worked
// out by hand (and equal to Reelay 25's).
TEST(RobustDense, WindowsOverPiecesByHand) {
  const std::pair<double, double> pieces[] = {{0, -1}, {1, 1}, {2.5, -2}, {3, 3}, {6, 0}};
  const auto run = [&](const std::string& spec) {
    std::vector<std::pair<double, double>> out;
    Checker c = dense_robust(spec, out);
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
}

// Dense since, a = {x > 0} and b = {y > 0} (margins x and y), on [0, 5):
//   [0, 1): a 1, b -1;  [1, 2): a 2, b 3;  [2, 4): a -1, b 0;  [4, 5): a 4, b -2.
// Unbounded, max(b, min(a, before)) per piece from -inf: -1, 3, 0, 0.
// since[0.5:1.5]: each piece [u, w) of the unbounded value contributes to H (minimum) over
// [u, w + 0.5), each piece of b to O (maximum) over [u + 0.5, w + 1.5):
//   H: -1 on [0, 1.5), 3 on [1.5, 2), 0 on [2, 5)
//   O: -inf on [0, 0.5), -1 on [0.5, 1.5), 3 on [1.5, 3.5), 0 on [3.5, 5)
//   min(H, O): -inf from 0, -1 from 0.5, 3 from 1.5, 0 from 2 (Reelay 25 reports the same
//   changes; at 1.75 the textbook max over s in [0.25, 1.25] of min(b(s), a over (s, t]) is 2).
TEST(RobustDense, SinceOverPiecesByHand) {
  struct Piece {
    double t, x, y;
  };
  const Piece pieces[] = {{0, 1, -1}, {1, 2, 3}, {2, -1, 0}, {4, 4, -2}};
  const auto run = [&](const std::string& spec) {
    std::vector<std::pair<double, double>> out;
    Checker c = dense_robust(spec, out);
    for (size_t i = 0; i < std::size(pieces); ++i) {
      const double margins[] = {pieces[i].x, pieces[i].y};
      c.step_robust(pieces[i].t, i + 1 < std::size(pieces) ? pieces[i + 1].t : 5.0, margins);
    }
    return out;
  };
  using V = std::vector<std::pair<double, double>>;
  EXPECT_EQ(run("{x > 0} since {y > 0}"), (V{{0, -1}, {1, 3}, {2, 0}}));
  EXPECT_EQ(run("{x > 0} since[0.5:1.5] {y > 0}"), (V{{0, -kInf}, {0.5, -1}, {1.5, 3}, {2, 0}}));
}

}  // namespace
}  // namespace rvc::engine::robust

