// libFuzzer harness: the `--calls` event stream pairing (src/io/service_calls.*,
// what `rvc calls`, `rvc check BAG --calls` and `rvc monitor --calls` share):
// lines of service events (pkg/srv/Name_Event as JSON) paired into calls, with
// the clock moved between them ("@T" lines: ServiceCalls::advance, as a live
// monitor's ticks do).
//
// Input: one options byte (the timeout), then the lines. Oracles beyond
// crashes: every event is counted once (events = requests + responses +
// duplicates + orphans + rejected); every call started is made answered,
// made unanswered or pending at the end; the calls come out at strictly
// increasing times, each made before the clock passes its next deadline; and
// next_deadline() never lies behind a call not yet made. Pending calls cost
// O(log n) each (a scan per event made 40,000 of them take 50 s), which
// libFuzzer's -timeout enforces on long inputs. Under the harness's memory
// limits (resource_limits.hpp).
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include <simdjson.h>

#include "io/service_calls.hpp"
#include "lines.hpp"
#include "resource_limits.hpp"

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rvc::fuzz::add_resource_limits(argc, argv);
  return 0;
}

// No call waits whose deadline the clock has passed: it would have been made.
bool due_later(const rvc::io::ServiceCalls& calls) {
  const double next = calls.next_deadline();
  return next == INFINITY || next > calls.now();
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  constexpr double kTimeouts[] = {1e-9, 0.001, 0.5, 1, 10, 3600, 1e6, 1e9};
  const double timeout = kTimeouts[data[0] & 7];
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);

  uint64_t emitted = 0;
  double last_time = -INFINITY;
  simdjson::dom::parser parser;
  rvc::io::ServiceCalls calls(timeout, [&](const std::string& call) {
    simdjson::dom::element e;
    double time = 0;
    if (parser.parse(call).get(e) || e["time"].get_double().get(time)) __builtin_trap();  // always JSON
    if (!(time > last_time)) __builtin_trap();  // times always increase
    last_time = time;
    ++emitted;
  });
  std::string error;
  rvc::fuzz::for_each_line(text, [&](std::string_view line) {
    if (!line.empty() && line[0] == '@') {  // the clock moves: calls due by then are made
      const std::string number(line.substr(1));
      char* rest = nullptr;
      const double now = std::strtod(number.c_str(), &rest);
      calls.advance(now);
      if (!due_later(calls)) __builtin_trap();
      return;
    }
    calls.feed(line, error);
    if (!due_later(calls)) __builtin_trap();
  });
  const rvc::io::ServiceCallCounts& c = calls.counts();
  if (c.events != c.requests + c.responses + c.duplicates + c.orphans + c.rejected) __builtin_trap();
  calls.finish();
  if (c.requests != c.answered + c.unanswered + c.pending) __builtin_trap();
  if (emitted != c.answered + c.unanswered) __builtin_trap();
  if (c.responses < c.answered) __builtin_trap();
  return 0;
}
