// Window aggregates (issue 26): ns per event for count, sum, avg, min, max
// over windows holding 10, 1,000 and 100,000 events, discrete (steps) and
// dense (seconds, events at 1 kHz). The window is filled first, so every
// timed event adds one sample and expires one: the steady state of a long
// run. Flat across window sizes is the claim (two-stack aggregation,
// engine/timed/two_stack.hpp); a recomputed window would grow 10,000-fold.
// Not a test: Google Benchmark, results to a file:
//   build/release/rvc_timed_bench --benchmark_out=timed_bench.json --benchmark_out_format=json
#include <benchmark/benchmark.h>

#include <cstdint>

#include "engine/timed/window_aggregate.hpp"

namespace {

using rvc::engine::timed::WindowAggregate;
using Func = rvc::spec::Timed::Func;

void run(benchmark::State& state, Func func, bool dense) {
  const auto events = static_cast<uint64_t>(state.range(0));
  const double period = dense ? 0.001 : 1;  // dense: 1 kHz
  rvc::spec::Bounds window;
  window.lo = 0;
  // Steps [0 : n-1] hold n samples; seconds (t - n*period, t] too.
  window.hi = dense ? static_cast<double>(events) * period : static_cast<double>(events - 1);
  WindowAggregate w(func, window, dense);
  uint64_t i = 0;
  uint32_t x = 12345;
  auto event = [&] {
    const double t = static_cast<double>(i++) * period;
    x = x * 1103515245u + 12345u;  // a cheap pseudo-random value
    w.advance(t);
    w.add(t, static_cast<double>(x >> 16));
    return w.value();
  };
  for (uint64_t k = 0; k < 2 * events; ++k) event();  // fill the window
  for (auto _ : state) benchmark::DoNotOptimize(event());
  state.counters["window"] = static_cast<double>(w.size());
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}

void Args(benchmark::internal::Benchmark* b) { b->Arg(10)->Arg(1000)->Arg(100000); }

#define RVC_WINDOW_BENCH(name, func)                                                              \
  void name##_discrete(benchmark::State& s) { run(s, func, false); }                             \
  void name##_dense(benchmark::State& s) { run(s, func, true); }                                 \
  BENCHMARK(name##_discrete)->Apply(Args);                                                        \
  BENCHMARK(name##_dense)->Apply(Args);

RVC_WINDOW_BENCH(count, Func::Count)
RVC_WINDOW_BENCH(sum, Func::Sum)
RVC_WINDOW_BENCH(avg, Func::Avg)
RVC_WINDOW_BENCH(min, Func::Min)
RVC_WINDOW_BENCH(max, Func::Max)

}  // namespace

BENCHMARK_MAIN();
