#include "store/database.hpp"

#include <cstdio>

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
    check_postgres_conninfo(uri);  // a typo is a usage error, not a server to wait for
    db = open_postgres(uri);
  } else {
    throw DbError("'" + uri + "' is not a results database (sqlite:PATH or postgresql://...)");
  }
  db->ensure_schema();
  return db;
}

std::unique_ptr<Database> open_database_readonly(const std::string& uri) {
  if (starts_with(uri, "sqlite:")) {
    const std::string path = uri.substr(7);
    if (path.empty()) throw DbError("sqlite: needs a file path (sqlite:results.db)");
    return open_sqlite(path, /*read_only=*/true);
  }
  if (starts_with(uri, "postgresql://") || starts_with(uri, "postgres://")) {
    check_postgres_conninfo(uri);
    return open_postgres(uri);
  }
  throw DbError("'" + uri + "' is not a results database (sqlite:PATH or postgresql://...)");
}

namespace {

// A server database not reachable yet: connects on the first write or
// reconnect(), and behaves as the real one from then on.
class WhenReachable final : public Database {
 public:
  explicit WhenReachable(std::string uri) : uri_(std::move(uri)) {}
  void ensure_schema() override { get().ensure_schema(); }
  void write(const std::vector<Row>& rows) override { get().write(rows); }
  bool reconnect() override {
    if (db_) return db_->reconnect();
    try {
      get();
      return true;
    } catch (const DbError&) {
      return false;
    }
  }
  QueryResult query(const std::string& sql, const std::vector<std::string>& params) override {
    return get().query(sql, params);
  }
  std::string describe() const override { return db_ ? db_->describe() : redact_password(uri_); }

 private:
  Database& get() {
    if (!db_) {
      try {
        db_ = open_database(uri_);
      } catch (const DbError& e) {
        throw DbError(e.what(), true);  // not there yet: keep the rows and retry
      }
    }
    return *db_;
  }
  std::string uri_;
  std::unique_ptr<Database> db_;
};

}  // namespace

std::unique_ptr<Database> open_database_when_reachable(const std::string& uri) {
  try {
    return open_database(uri);
  } catch (const DbError& e) {
    if (!e.connection_lost() || starts_with(uri, "sqlite:")) throw;
    std::fprintf(stderr, "rvc: results database: %s; keeping results until it is reachable\n", e.what());
    return std::make_unique<WhenReachable>(uri);
  }
}

std::string redact_password(const std::string& text) {
  std::string out = text;
  const size_t scheme = out.find("://");
  if (scheme != std::string::npos) {
    const size_t at = out.find('@', scheme + 3);
    const size_t slash = out.find('/', scheme + 3);
    if (at != std::string::npos && (slash == std::string::npos || at < slash)) {
      const size_t colon = out.find(':', scheme + 3);
      if (colon != std::string::npos && colon < at) out.replace(colon, at - colon, ":***");
    }
  }
  for (size_t at = out.find("password="); at != std::string::npos; at = out.find("password=", at + 1)) {
    const size_t begin = at + 9;
    size_t end = out.find_first_of("& ", begin);
    if (end == std::string::npos) end = out.size();
    out.replace(begin, end - begin, "***");
  }
  return out;
}

}  // namespace rvc::store
