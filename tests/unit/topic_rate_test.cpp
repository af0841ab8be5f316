// rvc hz's statistics and topic_state_monitor's state machine at their edges:
// rates exactly at warn_rate/error_rate (strictly below is the state), the
// timeout deadline (strictly after), a window filling and sliding, and the
// sliding sums against a recomputation from the window's own numbers.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "runtime/topic_rate.hpp"

namespace {

using rvc::runtime::RateThresholds;
using rvc::runtime::TopicRate;
using rvc::runtime::TopicState;

RateThresholds thresholds(double warn, double error, double timeout, size_t window) {
  RateThresholds t;
  t.warn_rate = warn;
  t.error_rate = error;
  t.timeout = timeout;
  t.window_size = window;
  return t;
}

TEST(TopicRate, NotReceivedBeforeAnyMessageAndNoRateStateWithOneArrival) {
  TopicRate r(thresholds(10, 5, 1, 4));
  EXPECT_EQ(r.state(0), TopicState::NotReceived);
  EXPECT_EQ(r.state(1e9), TopicState::NotReceived);  // never Timeout before the first message
  EXPECT_FALSE(r.timeout_at());
  r.add(1.0, std::nullopt);
  EXPECT_TRUE(std::isinf(r.rate()));  // topic_state_monitor's "max rate": no rate state from one arrival
  EXPECT_EQ(r.state(1.5), TopicState::Ok);
}

TEST(TopicRate, RateExactlyAtThresholdIsNotBelowIt) {
  // Arrivals every 0.25 s (exact in binary): 4 Hz.
  TopicRate at_warn(thresholds(4, 2, 0, 5));
  TopicRate above_warn(thresholds(4.000001, 2, 0, 5));
  TopicRate at_error(thresholds(8, 4, 0, 5));
  TopicRate above_error(thresholds(8, 4.000001, 0, 5));
  for (int i = 0; i < 5; ++i)
    for (TopicRate* r : {&at_warn, &above_warn, &at_error, &above_error}) r->add(i * 0.25, std::nullopt);
  EXPECT_DOUBLE_EQ(at_warn.rate(), 4.0);
  EXPECT_EQ(at_warn.state(1.0), TopicState::Ok);
  EXPECT_EQ(above_warn.state(1.0), TopicState::WarnRate);
  EXPECT_EQ(at_error.state(1.0), TopicState::WarnRate);  // 4 Hz: below warn 8, not below error 4
  EXPECT_EQ(above_error.state(1.0), TopicState::ErrorRate);  // error outranks warn
}

TEST(TopicRate, TimeoutStrictlyAfterTheDeadlineAndOutranksRates) {
  TopicRate r(thresholds(100, 50, 0.5, 3));
  r.add(10.0, std::nullopt);
  r.add(10.25, std::nullopt);  // 4 Hz: ErrorRate
  ASSERT_TRUE(r.timeout_at());
  EXPECT_DOUBLE_EQ(*r.timeout_at(), 10.75);
  EXPECT_EQ(r.state(10.75), TopicState::ErrorRate);  // exactly at the deadline: not yet
  EXPECT_EQ(r.state(std::nextafter(10.75, 20.0)), TopicState::Timeout);
  r.add(10.8, std::nullopt);  // a message ends the Timeout
  EXPECT_EQ(r.state(10.8), TopicState::ErrorRate);
}

TEST(TopicRate, ZeroMeansOff) {
  TopicRate r(thresholds(0, 0, 0, 2));
  r.add(0, std::nullopt);
  r.add(1000, std::nullopt);  // 0.001 Hz
  EXPECT_EQ(r.state(1e9), TopicState::Ok);
  EXPECT_FALSE(r.timeout_at());
}

TEST(TopicRate, WindowFillsThenSlides) {
  TopicRate r(thresholds(0, 0, 0, 3));
  r.add(0.0, 0.5);
  EXPECT_EQ(r.summary(0).window, 1u);
  r.add(1.0, std::nullopt);
  r.add(1.5, 0.25);
  auto s = r.summary(2.0);
  EXPECT_EQ(s.window, 3u);
  EXPECT_DOUBLE_EQ(s.rate, 2.0 / 1.5);
  EXPECT_DOUBLE_EQ(s.interval_min, 0.5);
  EXPECT_DOUBLE_EQ(s.interval_max, 1.0);
  EXPECT_DOUBLE_EQ(s.interval_mean, 0.75);
  EXPECT_DOUBLE_EQ(s.interval_std, 0.25);
  EXPECT_EQ(s.latency_samples, 2u);
  EXPECT_DOUBLE_EQ(s.latency_mean, 0.375);
  EXPECT_DOUBLE_EQ(s.latency_max, 0.5);
  EXPECT_DOUBLE_EQ(s.silence, 0.5);
  // The fourth arrival pushes out the first: its interval (1.0) and latency (0.5) leave.
  r.add(1.75, std::nullopt);
  s = r.summary(1.75);
  EXPECT_EQ(s.window, 3u);
  EXPECT_EQ(s.received, 4u);
  EXPECT_DOUBLE_EQ(s.rate, 2.0 / 0.75);
  EXPECT_DOUBLE_EQ(s.interval_max, 0.5);
  EXPECT_DOUBLE_EQ(s.interval_min, 0.25);
  EXPECT_EQ(s.latency_samples, 1u);
  EXPECT_DOUBLE_EQ(s.latency_max, 0.25);
  EXPECT_DOUBLE_EQ(s.silence, 0.0);
}

// The sliding sums and deques against the window recomputed from scratch, on
// jittered arrivals long enough to slide many times.
TEST(TopicRate, SlidingStatisticsMatchARecomputation) {
  const size_t window = 7;
  TopicRate r(thresholds(0, 0, 0, window));
  std::mt19937 rng(26);
  std::uniform_real_distribution<double> jitter(-0.004, 0.004), lat(0.001, 0.03);
  std::vector<double> arrivals, latencies;
  double t = 1.7e9;  // epoch seconds, as ROS stamps
  for (int i = 0; i < 500; ++i) {
    t += 0.1 + jitter(rng);
    const double l = lat(rng);
    arrivals.push_back(t);
    latencies.push_back(l);
    r.add(t, l);
    const size_t n = std::min(arrivals.size(), window);
    const size_t first = arrivals.size() - n;
    const auto s = r.summary(t);
    ASSERT_EQ(s.window, n);
    if (n < 2) continue;
    std::vector<double> iv;
    for (size_t k = first + 1; k < arrivals.size(); ++k) iv.push_back(arrivals[k] - arrivals[k - 1]);
    double mean = 0, mn = iv[0], mx = iv[0];
    for (double v : iv) mean += v, mn = std::min(mn, v), mx = std::max(mx, v);
    mean /= static_cast<double>(iv.size());
    double var = 0;
    for (double v : iv) var += (v - mean) * (v - mean);
    var /= static_cast<double>(iv.size());
    double lmean = 0, lmax = 0;
    for (size_t k = first; k < arrivals.size(); ++k) lmean += latencies[k], lmax = std::max(lmax, latencies[k]);
    lmean /= static_cast<double>(n);
    EXPECT_DOUBLE_EQ(s.rate, static_cast<double>(n - 1) / (arrivals.back() - arrivals[first])) << i;
    EXPECT_DOUBLE_EQ(s.interval_min, mn) << i;
    EXPECT_DOUBLE_EQ(s.interval_max, mx) << i;
    EXPECT_NEAR(s.interval_mean, mean, 1e-12) << i;
    EXPECT_NEAR(s.interval_std, std::sqrt(var), 1e-9) << i;
    EXPECT_NEAR(s.latency_mean, lmean, 1e-12) << i;
    EXPECT_DOUBLE_EQ(s.latency_max, lmax) << i;
  }
}

TEST(TopicRate, DiagnosticLevelsAsTopicStateMonitor) {
  using rvc::io::DiagLevel;
  EXPECT_EQ(rvc::runtime::diag_level(TopicState::Ok), DiagLevel::Ok);
  EXPECT_EQ(rvc::runtime::diag_level(TopicState::WarnRate), DiagLevel::Warn);
  EXPECT_EQ(rvc::runtime::diag_level(TopicState::ErrorRate), DiagLevel::Error);
  EXPECT_EQ(rvc::runtime::diag_level(TopicState::Timeout), DiagLevel::Error);
  EXPECT_EQ(rvc::runtime::diag_level(TopicState::NotReceived), DiagLevel::Error);
}

TEST(TopicRate, RefusesABadWindowOrThreshold) {
  EXPECT_THROW(TopicRate(thresholds(0, 0, 0, 1)), std::invalid_argument);
  EXPECT_THROW(TopicRate(thresholds(-1, 0, 0, 10)), std::invalid_argument);
  EXPECT_THROW(TopicRate(thresholds(0, 0, NAN, 10)), std::invalid_argument);
}

}  // namespace
