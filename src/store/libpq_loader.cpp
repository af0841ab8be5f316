#include "store/libpq_loader.hpp"

#include "store/database.hpp"
#include "util/dynamic_library.hpp"

namespace rvc::store {

const Libpq& libpq() {
  // A throw leaves it unset: the next call tries again.
  static const Libpq pq = util::load_functions<DbError, Libpq>(
      kLibpqSoname, RTLD_LOCAL, "PostgreSQL output needs libpq, Debian package libpq5", [](Libpq& t, auto set) {
#define RVC_LIBPQ_SET(name) set(t.name, #name);
        RVC_LIBPQ_FUNCTIONS(RVC_LIBPQ_SET)
#undef RVC_LIBPQ_SET
      });
  return pq;
}

}  // namespace rvc::store
