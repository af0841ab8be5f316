// Shared by the nanobind binding files of the _rvc module.
#pragma once

#include <nanobind/nanobind.h>

#include <stdexcept>
#include <string>

#include "session.hpp"

namespace rvc::python {

namespace nb = nanobind;

// A message with a value JSON cannot hold; Python's TypeError.
struct UnjsonableMessage : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The message `obj` (a dict) as a JSON line in `line`; UnjsonableMessage if it cannot be one.
void to_json_line(std::string& line, nb::handle obj);
// The session's warnings (a field that kept its value) as Python RuntimeWarnings.
void emit_warnings(Session& session);

void bind_reelay(nb::module_& m);
void bind_session(nb::module_& m);
void bind_bag(nb::module_& m);

}  // namespace rvc::python
