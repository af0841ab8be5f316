// A results database: SQLite (embedded, the default) or PostgreSQL (fleets).
// The store writes rows through this interface on its writer thread; the
// dashboard reads through query(). Both databases hold the same schema
// (schema.hpp), so the dashboard serves either.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "store/row.hpp"

namespace rvc::store {

// A database error. `connection_lost`: the database is away or busy for now
// (a server that went away, a SQLite file locked too long, a full disk):
// worth retrying after reconnect(). Otherwise the rows themselves were
// refused and retrying them as they are cannot succeed.
class DbError : public std::runtime_error {
 public:
  DbError(const std::string& what, bool connection_lost = false)
      : std::runtime_error(what), connection_lost_(connection_lost) {}
  bool connection_lost() const { return connection_lost_; }

 private:
  bool connection_lost_;
};

// Rows of a query: every value as text, "" for NULL.
using QueryResult = std::vector<std::vector<std::string>>;

class Database {
 public:
  virtual ~Database() = default;
  // Creates the tables and indexes if missing. Throws DbError.
  virtual void ensure_schema() = 0;
  // Writes all rows in one transaction: all or nothing. Throws DbError.
  virtual void write(const std::vector<Row>& rows) = 0;
  // After a lost connection: true once connected again (schema ensured).
  virtual bool reconnect() = 0;
  // A read-only query; '?' placeholders take `params` in order (the
  // PostgreSQL backend numbers them). Throws DbError.
  virtual QueryResult query(const std::string& sql, const std::vector<std::string>& params = {}) = 0;
  // What to show users: "sqlite:results.db", "postgresql://host/db" (no password).
  virtual std::string describe() const = 0;
};

// True for the URIs open_database() takes: sqlite:PATH, postgresql://...,
// postgres://... (libpq's connection URIs).
bool is_database_uri(const std::string& uri);
// Opens (and for SQLite creates) the database. Throws DbError: a bad URI, a
// server that cannot be reached, a file that cannot be opened.
std::unique_ptr<Database> open_database(const std::string& uri);
// As open_database, but a server that cannot be reached yet is not an error:
// the database connects on its first write or reconnect() (a monitor that
// starts before its fleet's database keeps its results until it is there).
// Still throws for a bad URI or a file that cannot be opened.
std::unique_ptr<Database> open_database_when_reachable(const std::string& uri);

// For readers (the dashboard): opens a database rvc wrote, changing nothing:
// SQLite read-only (no journal mode, no tables created; a file that is not
// rvc's is refused), PostgreSQL without the schema statements. Throws DbError.
std::unique_ptr<Database> open_database_readonly(const std::string& uri);

// `uri` (or any argument) without a password: "postgresql://u:secret@h/db"
// -> "postgresql://u@h/db", "...?password=secret" -> "...?password=***".
std::string redact_password(const std::string& text);

// Throws DbError (a usage error, not an outage) for a PostgreSQL URI that
// no server could make work: what libpq cannot parse (an unclosed [IPv6
// bracket), a port outside 1-65535, a value libpq would refuse at connect
// time (sslmode=bogus). open_database() calls it before connecting.
void check_postgres_conninfo(const std::string& conninfo);

// The backends (open_database picks one by scheme).
// `read_only`: for readers; else created if missing (and stamped as rvc's).
// Either way an existing file that is not rvc's is refused unchanged.
std::unique_ptr<Database> open_sqlite(const std::string& path, bool read_only = false);
std::unique_ptr<Database> open_postgres(const std::string& conninfo);

}  // namespace rvc::store
