// Built without libpq: a postgresql:// output is a clear error, not a crash.
#include "store/database.hpp"

namespace rvc::store {

void check_postgres_conninfo(const std::string&) {}

std::unique_ptr<Database> open_postgres(const std::string& conninfo) {
  throw DbError("this rvc was built without PostgreSQL (install libpq-dev and rebuild)");
}

}  // namespace rvc::store
