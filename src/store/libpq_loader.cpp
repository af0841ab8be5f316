#include "store/libpq_loader.hpp"

#include <dlfcn.h>

#include <string>

#include "store/database.hpp"

namespace rvc::store {
namespace {

Libpq load() {
  void* lib = ::dlopen(kLibpqSoname, RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    const char* why = ::dlerror();
    throw DbError(std::string("PostgreSQL output needs libpq (") + kLibpqSoname + ", Debian package libpq5): " +
                  (why ? why : "not found"));
  }
  Libpq pq;
  const char* missing = nullptr;
#define RVC_LIBPQ_RESOLVE(name)                                                 \
  pq.name = reinterpret_cast<decltype(pq.name)>(::dlsym(lib, #name));          \
  if (!pq.name && !missing) missing = #name;
  RVC_LIBPQ_FUNCTIONS(RVC_LIBPQ_RESOLVE)
#undef RVC_LIBPQ_RESOLVE
  if (missing) throw DbError(std::string(kLibpqSoname) + " has no function " + missing + " (libpq too old?)");
  return pq;  // the library stays loaded for the life of the process
}

}  // namespace

const Libpq& libpq() {
  static const Libpq pq = load();  // a throw leaves it unset: the next call tries again
  return pq;
}

}  // namespace rvc::store
