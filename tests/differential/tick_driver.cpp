// rvc_tick_driver: drives an engine::Checker in dense time with clock ticks,
// for the clock differential test (test_clock_differential.py). Not part of
// rvc: the runtime wires ticks into its loop; this is the engine alone.
//
//   rvc_tick_driver [--robustness] [--deadlines] SPEC... < input
//
// Input lines: a JSON message with a "time" (values hold until the next
// one, as `rvc check --dense` reads them), or `tick T` (a clock tick at T).
// With --deadlines the driver ticks as a runtime would: after each message
// and tick, at next_deadline() while that is before the next message.
// Output: one JSON line per verdict, {"property": "f<i>", "time": t,
// "value": v} (v: true/false, or the robustness; bounded future adds
// "known_at"), and {"tick": T} for each tick made at a deadline.
#include <simdjson.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "io/json_decoder.hpp"

namespace {

void print_time(double t) { std::printf("%.17g", t); }

}  // namespace

int main(int argc, char** argv) {
  using namespace rvc;
  bool robust = false, deadlines = false;
  std::vector<std::string> specs;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--robustness") robust = true;
    else if (a == "--deadlines") deadlines = true;
    else specs.push_back(a);
  }
  engine::Checker checker(engine::TimeModel::Dense, false, [&](const engine::Verdict& v) {
    std::printf("{\"property\": \"%s\", \"time\": ", v.property.c_str());
    print_time(v.time);
    if (!std::isnan(v.known_at)) {  // a bounded-future property's verdict: when it became known
      std::printf(", \"known_at\": ");
      print_time(v.known_at);
    }
    if (v.robust) {
      std::printf(", \"value\": ");
      if (std::isinf(v.robustness)) std::printf("\"%s\"", v.robustness > 0 ? "inf" : "-inf");
      else print_time(v.robustness);
      std::printf("}\n");
    } else {
      std::printf(", \"value\": %s}\n", v.value ? "true" : "false");
    }
  });
  if (robust) checker.enable_robustness();
  for (size_t i = 0; i < specs.size(); ++i) checker.add_property({"f" + std::to_string(i), specs[i]});
  io::DecoderOptions options;
  options.need_time = true;
  options.robustness = robust;
  io::JsonDecoder decoder(checker.atoms(), options);
  simdjson::ondemand::parser parser;

  std::vector<std::string> lines;
  for (std::string line; std::getline(std::cin, line);)
    if (!line.empty()) lines.push_back(line);
  // The time of each line (messages: parsed below; ticks: after "tick ").
  const auto tick_time = [](const std::string& line) { return std::stod(line.substr(5)); };

  bool seen = false;
  double last = 0;
  const auto tick = [&](double t) {
    if (robust) checker.tick_robust(t, decoder.margins());
    else checker.tick(t, decoder.values(), decoder.bound());
  };
  const auto deadline = [&] {
    return robust ? checker.next_deadline_robust(decoder.margins())
                  : checker.next_deadline(decoder.values(), decoder.bound());
  };
  for (size_t k = 0; k < lines.size(); ++k) {
    const std::string& line = lines[k];
    if (line.rfind("tick ", 0) == 0) {
      tick(tick_time(line));
    } else {
      simdjson::padded_string json(line);
      simdjson::ondemand::document doc = parser.iterate(json);
      simdjson::ondemand::object object = doc.get_object();
      std::string error;
      if (!decoder.decode(object, error)) {
        std::fprintf(stderr, "rvc_tick_driver: %s: %s\n", line.c_str(), error.c_str());
        return 2;
      }
      const double t = decoder.time();
      // As the runtime does (pipeline.cpp): the message closes [previous, t) with the held values.
      if (robust) checker.step_robust(seen ? last : 0, t, decoder.margins());
      else checker.step(seen ? last : 0, t, decoder.values(), decoder.bound());
      decoder.commit();
      seen = true;
      last = t;
    }
    if (!deadlines || !seen || k + 1 == lines.size()) continue;
    // Ticks at deadlines before the next line: the next message, as a runtime's sleep would be cut short.
    const std::string& next = lines[k + 1];
    double until = std::numeric_limits<double>::infinity();
    if (next.rfind("tick ", 0) == 0) {
      until = tick_time(next);
    } else {
      simdjson::padded_string json(next);
      simdjson::ondemand::parser p;
      simdjson::ondemand::document doc = p.iterate(json);
      until = double(doc["time"]);
    }
    for (double d = deadline(); d < until; d = deadline()) {
      std::printf("{\"tick\": ");
      print_time(d);
      std::printf("}\n");
      tick(d);
      if (d <= checker.clock() && deadline() == d) {  // a deadline that does not move on: a bug
        std::fprintf(stderr, "rvc_tick_driver: deadline stuck at %.17g\n", d);
        return 3;
      }
    }
  }
  return 0;
}
