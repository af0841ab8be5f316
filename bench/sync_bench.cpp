// Synchronization policy cost (issue 12): ns per message for each policy at
// 9 inputs (message_filters' limit) and at 100, over 1,000,000 messages, with
// the most messages a policy held at once (memory must stay flat in stream
// length) and the peak RSS of the process that ran the case.
//
// Stream: inputs in round robin, 100 rounds per second; each stamp is the
// round's time plus a jitter below 2 ms (exact: no jitter, or no set would
// ever match). merge waits max_delay = 5 ms. One more approximate case has
// the last input fall silent after 1,000 messages: every message then
// overflows its queue (the policy's worst steady state). The handler counts
// sets and releases. Each case runs in its own forked process so that its RSS
// is its own.
// Latency added per set (a third, untimed pass): in the stream's own time, how
// long after its newest member arrived a set came out, where a message
// arrives at the newest stamp seen so far (round robin, no transport delay):
// what the policy itself adds, waiting for the messages that decide a set.
// Not a test: prints a markdown table, asserts nothing about time.
//   build/release/rvc_sync_bench
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "sync/policy.hpp"

namespace {

using namespace rvc::sync;
using Clock = std::chrono::steady_clock;

constexpr size_t kMessages = 1'000'000;
constexpr double kPeriod = 0.01;

struct Counter : Handler {
  size_t sets = 0, releases = 0;
  void on_set(const Member*, size_t, double) override { ++sets; }
  void on_release(const Member&, Release) override { ++releases; }
};

// Records, per set, now - the newest member's stamp.
struct Waits : Handler {
  double now = 0;
  std::vector<double> waits;
  void on_set(const Member* m, size_t n, double) override {
    double newest = m[0].stamp;
    for (size_t i = 1; i < n; ++i) newest = std::max(newest, m[i].stamp);
    waits.push_back(now - newest);
  }
  void on_release(const Member&, Release) override {}
};

// Stamp of message k: deterministic, cheap (a few ns), per-input increasing.
double stamp_of(size_t k, size_t inputs, bool jitter) {
  double t = static_cast<double>(k / inputs) * kPeriod;
  if (!jitter) return t;
  uint64_t x = k * 0x9e3779b97f4a7c15ULL;
  x ^= x >> 29;
  return t + static_cast<double>(x % 2000) * 1e-6;  // < 2 ms
}

// Feeds the stream; `silent`: the last input stops after the first 1,000 messages.
void feed(Policy& policy, size_t inputs, bool jitter, bool silent, size_t* max_held) {
  for (size_t k = 0; k < kMessages; ++k) {
    const auto input = static_cast<uint32_t>(k % inputs);
    if (silent && k >= 1000 && input == inputs - 1) continue;
    policy.add(Member{input, stamp_of(k, inputs, jitter), k});
    if (max_held && policy.held() > *max_held) *max_held = policy.held();
  }
  policy.finish();
}

// p50 / p99 / max of the waits, in ms (sets emitted by finish() left out).
std::string wait_percentiles(PolicyKind kind, const PolicyOptions& o, size_t inputs, bool jitter, bool silent) {
  Waits w;
  auto policy = make_policy(kind, o, w);
  for (size_t k = 0; k < kMessages; ++k) {
    const auto input = static_cast<uint32_t>(k % inputs);
    if (silent && k >= 1000 && input == inputs - 1) continue;
    const double stamp = stamp_of(k, inputs, jitter);
    w.now = std::max(w.now, stamp);
    policy->add(Member{input, stamp, k});
  }
  if (w.waits.empty()) return "- | - | -";
  std::sort(w.waits.begin(), w.waits.end());
  auto at = [&](double q) { return w.waits[static_cast<size_t>(q * static_cast<double>(w.waits.size() - 1))] * 1e3; };
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f | %.2f | %.2f", at(0.5), at(0.99), w.waits.back() * 1e3);
  return buf;
}

void run_case(PolicyKind kind, size_t inputs, bool silent) {
  PolicyOptions o;
  o.inputs = inputs;
  o.max_delay = 0.005;
  const bool jitter = kind != PolicyKind::Exact;
  Counter counter;
  auto policy = make_policy(kind, o, counter);
  auto start = Clock::now();
  feed(*policy, inputs, jitter, silent, nullptr);
  const size_t added = silent ? kMessages - (kMessages - 1000) / inputs : kMessages;
  double ns = std::chrono::duration<double, std::nano>(Clock::now() - start).count() / static_cast<double>(added);
  // Second pass, untimed: the most messages held at once.
  Counter again;
  auto p2 = make_policy(kind, o, again);
  size_t max_held = 0;
  feed(*p2, inputs, jitter, silent, &max_held);
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  char name[32];
  std::snprintf(name, sizeof name, "%s%s", to_string(kind), silent ? ", 1 silent" : "");
  const std::string waits = wait_percentiles(kind, o, inputs, jitter, silent);
  std::printf("| %-22s | %6zu | %8.1f | %8zu | %8zu | %9ld | %s |\n", name, inputs, ns, counter.sets, max_held,
              usage.ru_maxrss, waits.c_str());
  if (counter.releases != added) std::printf("  (!) %zu releases for %zu messages\n", counter.releases, added);
}

}  // namespace

int main() {
  std::printf("| policy                 | inputs | ns/msg   | sets     | max held | RSS (KiB) | wait p50 ms | p99 ms | max ms |\n");
  std::printf("|------------------------|--------|----------|----------|----------|-----------|---:|---:|---:|\n");
  std::fflush(stdout);
  struct Case {
    PolicyKind kind;
    bool silent;
  };
  const Case cases[] = {{PolicyKind::Approximate, false}, {PolicyKind::Approximate, true}, {PolicyKind::Exact, false},
                        {PolicyKind::Latest, false}, {PolicyKind::Merge, false}};
  for (Case c : cases) {
    for (size_t inputs : {size_t{9}, size_t{100}}) {
      pid_t pid = fork();
      if (pid < 0) {
        run_case(c.kind, inputs, c.silent);
        continue;
      }
      if (pid == 0) {
        run_case(c.kind, inputs, c.silent);
        std::fflush(stdout);
        _exit(0);
      }
      int status = 0;
      waitpid(pid, &status, 0);
    }
  }
  return 0;
}
