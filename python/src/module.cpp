// The _rvc extension module: rvc's engine in-process (python/rvc/ is the
// Python API over it, docs/python.md).
#include <nanobind/stl/string.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <cstdint>
#include <stdexcept>

#include "bindings.hpp"
#include "msg/msg_types.hpp"
#include "io/json_writer.hpp"
#include "py_json.hpp"
#include "spec/spec_error.hpp"

namespace rvc::python {

void to_json_line(std::string& line, nb::handle obj) {
  line.clear();
  std::string error;
  if (!append_py_json(line, obj.ptr(), error)) throw UnjsonableMessage(error);
}

void emit_warnings(Session& session) {
  for (const std::string& w : session.take_warnings())
    if (PyErr_WarnEx(PyExc_RuntimeWarning, w.c_str(), 2) != 0) throw nb::python_error();
}

namespace {

// (property index, time, value, robustness or None, explanation or None);
// time is the step (an int) in discrete time.
nb::tuple verdict_tuple(const Captured& c, const SessionOptions& o) {
  nb::object time = o.dense ? nb::object(nb::float_(c.time)) : nb::object(nb::int_(static_cast<int64_t>(c.time)));
  nb::object robustness = o.robustness ? nb::object(nb::float_(c.robustness)) : nb::none();
  nb::object why = nb::none();
  if (c.explained) {
    nb::list l;
    for (const auto& s : c.explanation) l.append(nb::str(s.c_str(), s.size()));
    why = l;
  }
  return nb::make_tuple(c.property, time, nb::bool_(c.value), robustness, why);
}

nb::list take_verdicts(Session& s) {
  nb::list out;
  for (const Captured& c : s.captured()) out.append(verdict_tuple(c, s.options()));
  s.captured().clear();
  return out;
}

// A batch: each message fed alone (so each verdict knows its message), one
// refused message costs only itself (a RuntimeWarning names it).
template <class Fill>
nb::list feed_batch(Session& s, size_t count, Fill&& fill) {
  nb::list out;
  std::string line;
  s.captured().clear();
  std::vector<std::string> refused;
  for (size_t i = 0; i < count; ++i) {
    try {
      fill(line, i);
    } catch (const UnjsonableMessage& e) {  // a value JSON cannot hold: this message only
      s.refuse();
      refused.push_back("message " + std::to_string(s.messages()) + ": " + e.what() + " (message skipped)");
      continue;
    }
    s.feed_lenient(line);
    for (const Captured& c : s.captured()) {
      nb::tuple t = verdict_tuple(c, s.options());
      out.append(nb::make_tuple(i, t[0], t[1], t[2], t[3], t[4]));
    }
    s.captured().clear();
  }
  for (const std::string& r : refused)
    if (PyErr_WarnEx(PyExc_RuntimeWarning, r.c_str(), 2) != 0) throw nb::python_error();
  for (const std::string& r : s.take_rejections())
    if (PyErr_WarnEx(PyExc_RuntimeWarning, r.c_str(), 2) != 0) throw nb::python_error();
  emit_warnings(s);
  return out;
}


}  // namespace

void bind_session(nb::module_& m) {
  nb::class_<Session>(m, "Session")
      .def("__init__",
           [](Session* self, const std::vector<std::pair<std::string, std::string>>& properties, bool dense,
              bool robustness, bool explain, bool emit_all, const std::string& time_field, const std::string& type,
              const std::vector<std::string>& msg_paths, uint32_t max_data_values, size_t max_message_size,
              const std::string& origin) {
             std::vector<engine::PropertySpec> specs;
             for (const auto& [name, spec] : properties) specs.push_back({name, spec});
             SessionOptions o;
             o.dense = dense;
             o.robustness = robustness;
             o.explain = explain;
             o.emit_all = emit_all;
             o.time_field = time_field;
             o.type = type;
             o.msg_paths = msg_paths;
             o.max_data_values = max_data_values;
             o.max_message_size = max_message_size;
             if (origin != "first" && origin != "zero")
               throw nb::value_error(("origin must be 'first' or 'zero', not '" + origin + "'").c_str());
             o.origin_zero = origin == "zero";
             new (self) Session(std::move(specs), std::move(o));
           },
           nb::arg("properties"), nb::arg("dense"), nb::arg("robustness"), nb::arg("explain"), nb::arg("emit_all"),
           nb::arg("time_field"), nb::arg("type"), nb::arg("msg_paths"), nb::arg("max_data_values"),
           nb::arg("max_message_size") = 0, nb::arg("origin") = "first")
      .def("update",
           [](Session& s, nb::handle message) {
             std::string line;
             try {
               to_json_line(line, message);
             } catch (const UnjsonableMessage&) {
               s.refuse();  // counted, as a refused message is; the monitors do not move
               throw;
             }
             s.captured().clear();
             s.feed(line);
             emit_warnings(s);
             return take_verdicts(s);
           })
      .def("update_json",
           [](Session& s, const std::string& text) {
             s.captured().clear();
             s.feed(text);
             emit_warnings(s);
             return take_verdicts(s);
           })
      .def("update_cdr",
           [](Session& s, nb::bytes sample) {
             s.captured().clear();
             s.feed(std::string_view(sample.c_str(), sample.size()));
             emit_warnings(s);
             return take_verdicts(s);
           })
      .def("update_many",
           [](Session& s, nb::list messages) {
             return feed_batch(s, messages.size(), [&](std::string& line, size_t i) {
               to_json_line(line, messages[i]);
             });
           })
      .def("update_rows",
           [](Session& s, nb::bytes data, size_t count, size_t itemsize,
              const std::vector<std::tuple<std::string, size_t, std::string, size_t>>& fields) {
             if (count * itemsize > data.size()) throw std::invalid_argument("update_rows: fewer bytes than rows");
             std::vector<Column> columns;
             for (const auto& [name, offset, kind, size] : fields) {
               if (kind.size() != 1 || std::string("biuf").find(kind[0]) == std::string::npos)
                 throw std::invalid_argument("column " + name + ": kind '" + kind +
                                             "' (columns are bool, int, uint or float)");
               if (offset + size > itemsize) throw std::invalid_argument("column " + name + " lies outside the row");
               std::string quoted;
               io::append_json_string(quoted, name);
               columns.push_back({quoted, offset, kind[0], size});
             }
             const auto* base = reinterpret_cast<const uint8_t*>(data.c_str());
             return feed_batch(s, count, [&](std::string& line, size_t i) {
               line.clear();
               append_row_json(line, base + i * itemsize, columns.data(), columns.size());
             });
           })
      .def("tick",
           [](Session& s, double t) {
             s.captured().clear();
             s.tick(t);
             return take_verdicts(s);
           })
      .def_prop_ro("names", [](const Session& s) { return s.names(); })
      .def_prop_ro("clock", &Session::clock)
      .def("stats", [](const Session& s) {
        nb::dict d;
        d["messages"] = s.messages();
        d["checked"] = s.stats().accepted;
        d["rejected"] = s.rejected();
        d["warnings"] = s.stats().warnings;
        d["violations"] = s.violations();
        return d;
      });
}

}  // namespace rvc::python

NB_MODULE(_rvc, m) {
  using namespace rvc::python;
  m.doc() = "rvc's engine (see the rvc package)";
  nb::register_exception_translator([](const std::exception_ptr& p, void*) {
    try {
      std::rethrow_exception(p);
    } catch (const rvc::spec::SpecError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const rvc::msg::MsgError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const RejectedMessage& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const UnjsonableMessage& e) {
      PyErr_SetString(PyExc_TypeError, e.what());
    }
  });
#ifdef RVC_HAVE_MCAP
  m.attr("has_mcap") = true;  // check_bag reads MCAP bags (built with the Rust library)
#else
  m.attr("has_mcap") = false;
#endif
  bind_reelay(m);
  bind_session(m);
  bind_bag(m);
}
