// A shared library opened with dlopen, and a table of its functions filled by
// name: how rvc loads the libraries only some runs need (CycloneDDS, libpq;
// cmake/RuntimeLibraries.cmake says why). Each caller lists its functions once,
// as an X-macro, and gets a struct of typed pointers.
#pragma once

#include <dlfcn.h>

#include <string>
#include <type_traits>

namespace rvc::util {

// Opens `soname` (kept loaded for the life of the process) and fills `table`
// through `for_each(callback)`, which calls callback(pointer member, name) for
// every function. Throws Error(message) naming the library, and `needed_for`,
// if it is missing or lacks a function.
template <class Error, class Table, class ForEach>
Table load_functions(const char* soname, int flags, const std::string& needed_for, ForEach for_each) {
  void* lib = ::dlopen(soname, RTLD_NOW | flags);
  if (!lib) {
    const char* why = ::dlerror();
    throw Error(needed_for + " (" + soname + "): " + (why ? why : "not found"));
  }
  Table table;
  const char* missing = nullptr;
  for_each(table, [&](auto& pointer, const char* name) {
    pointer = reinterpret_cast<std::remove_reference_t<decltype(pointer)>>(::dlsym(lib, name));
    if (!pointer && !missing) missing = name;
  });
  if (missing) throw Error(std::string(soname) + " has no function " + missing + " (" + needed_for + ")");
  return table;
}

}  // namespace rvc::util
