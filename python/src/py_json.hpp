// A Python message (dict of str -> bool, int, float, str, None, dict, list)
// as one JSON line, the form rvc's decoder reads: update(dict) goes through
// the same decoder, field tests and rules as a JSON-lines file.
#pragma once

#include <Python.h>

#include <cstdint>
#include <string>

namespace rvc::python {

// Appends `obj` (a dict at the top) as JSON. False, with `error` naming the
// field and the type, for a value JSON cannot hold (bytes, an object, a key
// that is not a str).
bool append_py_json(std::string& out, PyObject* obj, std::string& error);

// One row of a numpy structured array: a field's name, offset in the row,
// kind ('b' bool, 'i' signed, 'u' unsigned, 'f' float) and size in bytes.
struct Column {
  std::string name;  // already a JSON string literal with its quotes
  size_t offset;
  char kind;
  size_t size;
};
// Appends one row (the bytes at `row`) as a JSON object.
void append_row_json(std::string& out, const uint8_t* row, const Column* columns, size_t count);

}  // namespace rvc::python
