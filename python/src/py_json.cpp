#include "py_json.hpp"

#include <cmath>
#include <cstring>

#include "io/json_writer.hpp"

namespace rvc::python {
namespace {

void append_double(std::string& out, double v) {
  if (std::isfinite(v)) io::append_number(out, v);
  else out += io::non_finite_word(v);  // as Python's json writes them; rvc's readers take them back
}

bool append_key(std::string& out, PyObject* key, std::string& error) {
  Py_ssize_t n = 0;
  const char* s = PyUnicode_Check(key) ? PyUnicode_AsUTF8AndSize(key, &n) : nullptr;
  if (!s) {
    PyErr_Clear();
    error = std::string("a message's keys must be str, not ") + Py_TYPE(key)->tp_name;
    return false;
  }
  io::append_json_string(out, std::string_view(s, static_cast<size_t>(n)));
  return true;
}

bool append_value(std::string& out, PyObject* v, std::string& error, int depth) {
  if (depth > 64) {
    error = "a message nested deeper than 64 levels";
    return false;
  }
  if (v == Py_True) out += "true";
  else if (v == Py_False) out += "false";
  else if (v == Py_None) out += "null";
  else if (PyLong_Check(v)) {
    int overflow = 0;
    const long long i = PyLong_AsLongLongAndOverflow(v, &overflow);
    if (overflow) {
      PyObject* text = PyObject_Str(v);  // a big integer: its digits, read as a number
      if (!text) return PyErr_Clear(), error = "an integer that cannot be printed", false;
      out += PyUnicode_AsUTF8(text);
      Py_DECREF(text);
    } else {
      out += std::to_string(i);
    }
  } else if (PyFloat_Check(v)) {
    append_double(out, PyFloat_AS_DOUBLE(v));
  } else if (PyUnicode_Check(v)) {
    Py_ssize_t n = 0;
    const char* s = PyUnicode_AsUTF8AndSize(v, &n);
    if (!s) return PyErr_Clear(), error = "a str that is not valid UTF-8", false;
    io::append_json_string(out, std::string_view(s, static_cast<size_t>(n)));
  } else if (PyDict_Check(v)) {
    out += '{';
    Py_ssize_t pos = 0;
    PyObject *key, *value;
    bool first = true;
    while (PyDict_Next(v, &pos, &key, &value)) {
      if (!first) out += ',';
      first = false;
      if (!append_key(out, key, error)) return false;
      out += ':';
      if (!append_value(out, value, error, depth + 1)) {
        if (error.rfind("field ", 0) != 0) error = "field " + std::string(PyUnicode_AsUTF8(key)) + ": " + error;
        return false;
      }
    }
    out += '}';
  } else if (PyList_Check(v) || PyTuple_Check(v)) {
    out += '[';
    const Py_ssize_t n = PySequence_Fast_GET_SIZE(v);
    PyObject** items = PySequence_Fast_ITEMS(v);
    for (Py_ssize_t i = 0; i < n; ++i) {
      if (i) out += ',';
      if (!append_value(out, items[i], error, depth + 1)) return false;
    }
    out += ']';
  } else if (std::strstr(Py_TYPE(v)->tp_name, "numpy.bool")) {  // numpy.bool_
    out += PyObject_IsTrue(v) ? "true" : "false";
  } else if (PyNumber_Check(v) && PyObject_HasAttrString(v, "__index__")) {  // numpy integers
    PyObject* i = PyNumber_Index(v);
    if (!i) return PyErr_Clear(), error = "an integer that cannot be read", false;
    const bool ok = append_value(out, i, error, depth);
    Py_DECREF(i);
    return ok;
  } else if (PyNumber_Check(v) && PyObject_HasAttrString(v, "__float__")) {  // numpy floats
    const double d = PyFloat_AsDouble(v);
    if (d == -1.0 && PyErr_Occurred()) return PyErr_Clear(), error = "a number that cannot be read", false;
    append_double(out, d);
  } else {
    error = std::string("a value of type ") + Py_TYPE(v)->tp_name + " (messages hold bool, int, float, str, None, dict, list)";
    return false;
  }
  return true;
}

}  // namespace

bool append_py_json(std::string& out, PyObject* obj, std::string& error) {
  if (!PyDict_Check(obj)) {
    error = std::string("a message is a dict, not ") + Py_TYPE(obj)->tp_name;
    return false;
  }
  return append_value(out, obj, error, 0);
}

void append_row_json(std::string& out, const uint8_t* row, const Column* columns, size_t count) {
  out += '{';
  for (size_t i = 0; i < count; ++i) {
    const Column& c = columns[i];
    if (i) out += ',';
    out += c.name;
    out += ':';
    const uint8_t* p = row + c.offset;
    switch (c.kind) {
      case 'b':
        out += *p ? "true" : "false";
        break;
      case 'i': {
        int64_t v = 0;
        if (c.size == 1) { int8_t x; std::memcpy(&x, p, 1); v = x; }
        else if (c.size == 2) { int16_t x; std::memcpy(&x, p, 2); v = x; }
        else if (c.size == 4) { int32_t x; std::memcpy(&x, p, 4); v = x; }
        else std::memcpy(&v, p, 8);
        out += std::to_string(v);
        break;
      }
      case 'u': {
        uint64_t v = 0;
        if (c.size == 1) v = *p;
        else if (c.size == 2) { uint16_t x; std::memcpy(&x, p, 2); v = x; }
        else if (c.size == 4) { uint32_t x; std::memcpy(&x, p, 4); v = x; }
        else std::memcpy(&v, p, 8);
        out += std::to_string(v);
        break;
      }
      default: {  // 'f'
        double v;
        if (c.size == 4) { float x; std::memcpy(&x, p, 4); v = x; }
        else std::memcpy(&v, p, 8);
        append_double(out, v);
      }
    }
  }
  out += '}';
}

}  // namespace rvc::python
