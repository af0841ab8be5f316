// Typed input cost (issue 11): what `rvc monitor --type` pays per message for
// ROS 2 CDR compared with the same message as JSON, on two of the paper's
// Table-3 types. Side by side in one run, same properties, same values:
//   json   Pipeline::feed(JSON payload)             (rvc's JSON path)
//   typed  Pipeline::feed(CDR payload), --type T   (CDR straight into the tests' values)
//   via    cdr_to_json (tested fields only) + the JSON path: the typed path
//          before io::CdrDecoder, kept here to measure the change side by side
//   decode cdr_to_json alone                        (what `rvc echo` pays per sample)
// Prints a markdown table (ns per message, typed/json ratio) and writes it as
// JSON lines to the file given as argument (default bench/results/cdr.jsonl).
//   build/release/rvc_cdr_bench [OUT]
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
#include "io/json_writer.hpp"
#include "msg/type_registry.hpp"
#include "runtime/pipeline.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Case {
  const char* type;
  std::vector<rvc::engine::PropertySpec> properties;
  std::string (*make)(std::mt19937_64&, int);
};

std::string steering(std::mt19937_64& rng, int i) {
  std::uniform_real_distribution<float> angle(-0.6f, 0.6f);
  char buf[160];
  std::snprintf(buf, sizeof buf, R"({"stamp":{"sec":%d,"nanosec":%d},"steering_tire_angle":%.6g})", 1000 + i / 30,
                (i % 30) * 33333333, static_cast<double>(angle(rng)));
  return buf;
}

std::string vehicle_status(std::mt19937_64& rng, int i) {
  std::uniform_real_distribution<double> speed(0, 15), yaw(-0.3, 0.3);
  std::uniform_int_distribution<int> gear(0, 5), signal(0, 3);
  char buf[400];
  std::snprintf(buf, sizeof buf,
                R"({"stamp":{"sec":%d,"nanosec":%d},"status":{"twist":{"linear":{"x":%.6g,"y":0,"z":0},)"
                R"("angular":{"x":0,"y":0,"z":%.6g}},"steering":{"data":%.5g},"turn_signal":{"data":%d},)"
                R"("gear_shift":{"data":%d}}})",
                1000 + i / 30, (i % 30) * 33333333, speed(rng), yaw(rng), yaw(rng), signal(rng), gear(rng));
  return buf;
}

double run(const rvc::msg::MessageType* type, const std::vector<rvc::engine::PropertySpec>& props,
           const std::vector<std::string>& payloads, uint64_t& verdicts) {
  rvc::runtime::PipelineOptions o;
  o.type = type;
  o.emit_all = true;
  verdicts = 0;
  rvc::runtime::Pipeline p(props, o, [&](const rvc::engine::Verdict&) { ++verdicts; });
  const auto t0 = Clock::now();
  uint64_t seq = 0;
  for (const auto& m : payloads) p.feed(m, ++seq);
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  if (p.stats().rejected) std::fprintf(stderr, "cdr_bench: %llu rejected\n", (unsigned long long)p.stats().rejected);
  return s * 1e9 / payloads.size();
}

// The previous typed path: CDR -> JSON of the tested fields -> JSON decoder.
double run_via_json(const rvc::msg::MessageType& type, const std::vector<rvc::engine::PropertySpec>& props,
                    const std::vector<std::string>& samples, uint64_t& verdicts) {
  rvc::runtime::PipelineOptions o;
  o.emit_all = true;
  verdicts = 0;
  rvc::runtime::Pipeline p(props, o, [&](const rvc::engine::Verdict&) { ++verdicts; });
  rvc::io::CdrSelection selection;
  for (const auto& t : p.checker().atoms().tests()) selection.add(t.path);
  std::string json;
  rvc::io::CdrError e;
  const auto t0 = Clock::now();
  uint64_t seq = 0;
  for (const auto& s : samples) {
    json.clear();
    rvc::io::cdr_to_json(type, s, json, e, &selection);
    p.feed(json, ++seq);
  }
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  return s * 1e9 / samples.size();
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out_path = argc > 1 ? argv[1] : "bench/results/cdr.jsonl";
  constexpr int kMessages = 300000;
  const std::vector<Case> cases = {
      {"autoware_auto_vehicle_msgs/msg/SteeringReport",
       {{"p1", "historically({steering_tire_angle < 0.5} and {steering_tire_angle > -0.5})"},
        {"p2", "{steering_tire_angle > 0.4} -> once[0:10]{steering_tire_angle < 0.1}"}},
       steering},
      {"tier4_external_api_msgs/msg/VehicleStatusStamped",
       {{"p1", "{status.gear_shift.data == 2} -> {status.twist.linear.x < 3}"},
        {"p2", "historically[0:30]({status.turn_signal.data == 3} -> {status.steering.data < 0.2})"}},
       vehicle_status},
  };
  rvc::msg::TypeRegistry registry;
  std::FILE* out = nullptr;
  std::filesystem::create_directories(std::filesystem::path(out_path).parent_path());
  out = std::fopen(out_path.c_str(), "w");
  std::printf("| type | bytes JSON / CDR | json ns/msg | typed ns/msg | typed / json | via JSON ns/msg | via JSON / json "
              "| cdr_to_json ns/msg |\n");
  std::printf("|------|------------------|-------------|--------------|--------------|-----------------|-----------------"
              "|--------------------|\n");
  for (const auto& c : cases) {
    const auto& type = registry.resolve(c.type);
    std::mt19937_64 rng(7);
    std::vector<std::string> json, cdr;
    std::string sample, error;
    size_t json_bytes = 0, cdr_bytes = 0;
    for (int i = 0; i < kMessages; ++i) {
      json.push_back(c.make(rng, i));
      if (!rvc::io::json_to_cdr(type, json.back(), sample, error)) {
        std::fprintf(stderr, "cdr_bench: %s\n", error.c_str());
        return 1;
      }
      cdr.push_back(sample);
      json_bytes += json.back().size();
      cdr_bytes += sample.size();
    }
    uint64_t v_json = 0, v_typed = 0;
    run(nullptr, c.properties, json, v_json);  // warm-up
    const double ns_json = run(nullptr, c.properties, json, v_json);
    const double ns_typed = run(&type, c.properties, cdr, v_typed);
    uint64_t v_via = 0;
    const double ns_via = run_via_json(type, c.properties, cdr, v_via);
    if (v_json != v_typed || v_json != v_via) {
      std::fprintf(stderr, "cdr_bench: %s: %llu verdicts from JSON, %llu from CDR\n", c.type,
                   (unsigned long long)v_json, (unsigned long long)v_typed);
      return 1;
    }
    std::string decoded;
    rvc::io::CdrError e;
    const auto t0 = Clock::now();
    for (const auto& s : cdr) {
      decoded.clear();
      rvc::io::cdr_to_json(type, s, decoded, e);
    }
    const double ns_decode = std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / kMessages;
    std::printf("| %s | %.0f / %.0f | %.0f | %.0f | %.2f | %.0f | %.2f | %.0f |\n", c.type,
                double(json_bytes) / kMessages, double(cdr_bytes) / kMessages, ns_json, ns_typed, ns_typed / ns_json,
                ns_via, ns_via / ns_json, ns_decode);
    if (out) {
      rvc::io::JsonObject o;
      o.add("type", std::string(c.type))
          .add("messages", static_cast<uint64_t>(kMessages))
          .add_fixed("json_ns_per_msg", ns_json, 1)
          .add_fixed("typed_ns_per_msg", ns_typed, 1)
          .add_fixed("typed_over_json", ns_typed / ns_json, 3)
          .add_fixed("via_json_ns_per_msg", ns_via, 1)
          .add_fixed("via_json_over_json", ns_via / ns_json, 3)
          .add_fixed("cdr_to_json_ns_per_msg", ns_decode, 1);
      std::fprintf(out, "%s\n", o.str().c_str());
    }
  }
  if (out) std::fclose(out);
  std::printf("\nresults: %s\n", out_path.c_str());
  return 0;
}
