#include "store/database.hpp"

namespace rvc::store {

namespace {
bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }
}  // namespace

bool is_database_uri(const std::string& uri) {
  return starts_with(uri, "sqlite:") || starts_with(uri, "postgresql://") || starts_with(uri, "postgres://");
}

std::unique_ptr<Database> open_database(const std::string& uri) {
  std::unique_ptr<Database> db;
  if (starts_with(uri, "sqlite:")) {
    const std::string path = uri.substr(7);
    if (path.empty()) throw DbError("sqlite: needs a file path (sqlite:results.db)");
    db = open_sqlite(path);
  } else if (starts_with(uri, "postgresql://") || starts_with(uri, "postgres://")) {
    db = open_postgres(uri);
  } else {
    throw DbError("'" + uri + "' is not a results database (sqlite:PATH or postgresql://...)");
  }
  db->ensure_schema();
  return db;
}

}  // namespace rvc::store
