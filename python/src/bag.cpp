// rvc.check_bag: one topic of a ROS 2 bag (sqlite3 .db3, a bag folder; MCAP
// when the package is built with it) through runtime::check_bag, the code
// `rvc check BAG` runs, its types from the bag's own schemas.
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bindings.hpp"
#include "runtime/check_bag.hpp"
#include "runtime/verdict_outputs.hpp"

namespace rvc::python {
namespace {

struct BagResult {
  std::vector<Captured> verdicts;
  std::vector<std::string> names, errors;
  std::string topic, type;
  runtime::PipelineStats stats;
  uint64_t messages = 0, received = 0, violations = 0;
  int exit_code = 0;
};

BagResult run(const std::string& path, const std::vector<std::pair<std::string, std::string>>& properties,
              const std::string& topic, bool dense, bool robustness, bool explain, bool emit_all,
              const std::vector<std::string>& msg_paths, size_t max_message_size) {
  BagResult r;
  msg::TypeRegistry registry;
  for (const auto& dir : msg_paths) registry.add_search_path(dir);
  runtime::BagInput bag = runtime::select_bag_topic(path, topic, registry);
  std::vector<engine::PropertySpec> specs;
  for (const auto& [name, spec] : properties) specs.push_back({name, spec});
  runtime::PipelineOptions po;
  po.model = dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete;
  po.emit_all = emit_all;
  po.robustness = robustness;
  po.explain = explain;
  po.position_name = "message";
  po.type = bag.type;
  if (max_message_size) po.max_message_size = po.max_typed_message_size = max_message_size;
  po.on_report = [&](const std::string& text) { r.errors.push_back(text); };
  runtime::set_size_cap(bag, po);
  const std::vector<std::string>* names = nullptr;
  runtime::Pipeline pipeline(specs, po, [&](const engine::Verdict& v) {
    Captured c{static_cast<uint32_t>(&v.property - names->data()), v.time, v.robust ? v.robustness > 0 : v.value,
               v.robustness, {}, false};
    if (v.explanation) c.explanation = *v.explanation, c.explained = true;
    r.verdicts.push_back(std::move(c));
  });
  names = &pipeline.checker().names();
  runtime::VerdictOutputs outputs({}, !dense);
  uint64_t skipped = 0;
  // Dense time ticks at the recording's end, as `rvc check` does by default (--clock auto).
  const runtime::Outcome outcome = runtime::check_bag({bag}, pipeline, outputs, skipped, {}, dense);
  r.names = pipeline.checker().names();
  r.topic = bag.topic;
  r.type = bag.type ? bag.type->full_name() : "JSON";
  r.stats = pipeline.stats();
  r.stats.rejected += skipped;
  r.messages = bag.messages;
  r.received = pipeline.received() + skipped;
  r.violations = pipeline.violations();
  r.exit_code = outcome.exit_code();
  return r;
}

}  // namespace

void bind_bag(nb::module_& m) {
  m.def(
      "check_bag",
      [](const std::string& path, const std::vector<std::pair<std::string, std::string>>& properties,
         const std::string& topic, bool dense, bool robustness, bool explain, bool emit_all,
         const std::vector<std::string>& msg_paths, size_t max_message_size) {
        BagResult r;
        {
          nb::gil_scoped_release unlocked;  // a long bag does not hold up other Python threads
          r = run(path, properties, topic, dense, robustness, explain, emit_all, msg_paths, max_message_size);
        }
        nb::list verdicts;
        for (const Captured& c : r.verdicts) {
          nb::object time = dense ? nb::object(nb::float_(c.time)) : nb::object(nb::int_(static_cast<int64_t>(c.time)));
          nb::object why = nb::none();
          if (c.explained) why = nb::cast(c.explanation);
          verdicts.append(nb::make_tuple(c.property, time, nb::bool_(c.value),
                                         robustness ? nb::object(nb::float_(c.robustness)) : nb::none(), why));
        }
        nb::dict d;
        d["verdicts"] = verdicts;
        d["names"] = nb::cast(r.names);
        d["errors"] = nb::cast(r.errors);
        d["topic"] = r.topic;
        d["type"] = r.type;
        d["messages"] = r.messages;
        d["received"] = r.received;
        d["checked"] = r.stats.accepted;
        d["rejected"] = r.stats.rejected;
        d["warnings"] = r.stats.warnings;
        d["violations"] = r.violations;
        d["exit_code"] = r.exit_code;
        return d;
      },
      nb::arg("path"), nb::arg("properties"), nb::arg("topic"), nb::arg("dense"), nb::arg("robustness"),
      nb::arg("explain"), nb::arg("emit_all"), nb::arg("msg_paths"), nb::arg("max_message_size") = 0);
}

}  // namespace rvc::python
