// Reelay's Python API (PyPI `reelay` 25: discrete_timed_monitor,
// dense_timed_monitor) over rvc's engine: the same constructors' options and
// the same return shapes of update(), so a script written for Reelay runs
// unchanged. The verdicts are rvc's; where they differ from Reelay's by
// design, docs/semantics.md says so (docs/python.md lists it).
#include <nanobind/stl/string.h>

#include "bindings.hpp"

namespace rvc::python {
namespace {

SessionOptions options(bool dense, bool robustness, bool every_step) {
  SessionOptions o;
  o.dense = dense;
  o.robustness = robustness;
  o.emit_all = every_step;
  o.origin_zero = true;  // Reelay's timeline starts at 0 (docs/python.md)
  return o;
}

nb::object verdict_value(const Captured& c, bool robust) {
  return robust ? nb::object(nb::float_(c.robustness)) : nb::object(nb::bool_(c.value));
}

// Discrete time: update() returns {t_name: step, y_name: value} when the
// value changed (condense=True; always on the first call) else {}, or
// {y_name: value} at every step (condense=False), as Reelay does.
class DiscreteTimedMonitor {
 public:
  DiscreteTimedMonitor(const std::string& pattern, bool robustness, const std::string& t_name,
                       const std::string& y_name, bool condense)
      : session_({{"p1", pattern}}, options(false, robustness, !condense)),
        t_(t_name.c_str()), y_(y_name.c_str()), condense_(condense), robust_(robustness) {}

  nb::dict update(nb::handle message) {
    to_json_line(line_, message);
    session_.captured().clear();
    session_.feed(line_);
    ++step_;
    if (session_.has_warnings()) emit_warnings(session_);
    nb::dict out;
    const auto& c = session_.captured();
    if (c.empty()) return out;
    if (condense_) out[t_] = nb::int_(step_);
    out[y_] = verdict_value(c.back(), robust_);
    return out;
  }
  nb::dict now() const {  // the last step: -1 before the first update(), as Reelay 25 says
    nb::dict out;
    out[t_] = nb::int_(step_);
    return out;
  }

 private:
  Session session_;
  nb::str t_, y_;
  bool condense_, robust_;
  int64_t step_ = -1;
  std::string line_;
};

// Dense time: update() returns the list of changes [{t_name: time, y_name:
// value}, ...] over [previous message's time, this message's time), [] on
// the first call at time 0. Reelay's dense robustness starts from 0, and its
// dense data monitors (exists/forall) from false, and report only changes
// from there: such a first value is not reported.
class DenseTimedMonitor {
 public:
  DenseTimedMonitor(const std::string& pattern, bool robustness, const std::string& t_name, const std::string& y_name)
      : session_({{"p1", pattern}}, options(true, robustness, false)),
        t_(t_name.c_str()), y_(y_name.c_str()), robust_(robustness),
        data_(session_.has_data_references()), before_first_(robust_ || data_) {}

  nb::list update(nb::handle message) {
    if (PyDict_Check(message.ptr()) && !PyDict_GetItemString(message.ptr(), "time"))
      throw nb::key_error("time");  // Reelay's dense monitors read the time from "time" whatever t_name says
    to_json_line(line_, message);
    session_.captured().clear();
    session_.feed(line_);
    if (session_.has_warnings()) emit_warnings(session_);
    nb::list out;
    for (const Captured& c : session_.captured()) {
      if (before_first_) {
        before_first_ = false;
        if (robust_ ? c.robustness == 0 : !c.value) continue;
      }
      nb::dict d;
      d[t_] = nb::float_(c.time);
      d[y_] = verdict_value(c, robust_);
      out.append(d);
    }
    return out;
  }
  nb::dict now() const {
    nb::dict out;
    out[t_] = nb::float_(session_.clock());
    return out;
  }

 private:
  Session session_;
  nb::str t_, y_;
  bool robust_, data_;
  bool before_first_;
  std::string line_;
};

}  // namespace

void bind_reelay(nb::module_& m) {
  nb::class_<DiscreteTimedMonitor>(m, "DiscreteTimedMonitor")
      .def(nb::init<const std::string&, bool, const std::string&, const std::string&, bool>(), nb::arg("pattern"),
           nb::arg("robustness"), nb::arg("t_name"), nb::arg("y_name"), nb::arg("condense"))
      .def("update", &DiscreteTimedMonitor::update, nb::arg("message"))
      .def("now", &DiscreteTimedMonitor::now);
  nb::class_<DenseTimedMonitor>(m, "DenseTimedMonitor")
      .def(nb::init<const std::string&, bool, const std::string&, const std::string&>(), nb::arg("pattern"),
           nb::arg("robustness"), nb::arg("t_name"), nb::arg("y_name"))
      .def("update", &DenseTimedMonitor::update, nb::arg("message"))
      .def("now", &DenseTimedMonitor::now);
}

}  // namespace rvc::python
