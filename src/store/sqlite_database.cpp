// SQLite backend: the embedded default (`--output sqlite:results.db`).
// WAL journal, so the dashboard (another process) reads while the monitor
// writes; one prepared statement per table, one transaction per batch.
//
// rvc changes only its own databases: a file it creates is stamped with
// PRAGMA application_id = kApplicationId in the transaction that creates its
// tables; an existing file is used only if it has that stamp, or (made by an
// rvc before the stamp) exactly rvc's tables with rvc's columns. Anything
// else (another application's database, even one whose tables share rvc's
// names; an empty file; a file that is not SQLite) is refused before a byte
// of it changes: that is decided on a read-only, immutable connection (no
// lock, no journal, no -wal/-shm files), before the file is opened for
// writing; no journal mode, no stamp, no tables.
#include <fcntl.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <thread>

#include "store/database.hpp"
#include "store/schema.hpp"

namespace rvc::store {
namespace {

constexpr int kApplicationId = 0x72766331;  // "rvc1"

// The tables of an rvc results database, as rvc before the stamp made them,
// with the columns they had then (later ones are added: added_columns()).
const std::map<std::string, std::set<std::string>>& rvc_tables() {
  static const std::map<std::string, std::set<std::string>> tables{
      {"runs", {"run", "command", "inputs", "time_model", "started_at", "ended_at", "exit_status", "end_reason",
                "counters"}},
      {"properties", {"run", "name", "spec"}},
      {"verdicts", {"id", "run", "property", "time", "value", "wall"}},
      {"violations", {"id", "run", "property", "time", "wall", "witness"}},
      {"counters", {"id", "run", "wall", "counters"}}};
  return tables;
}

// file:PATH?immutable=1 for sqlite3_open_v2 (SQLITE_OPEN_URI): '%', '?' and
// '#' in the path are escaped.
std::string immutable_uri(const std::string& path) {
  std::string out = "file:";
  for (const char c : path) {
    if (c == '%' || c == '?' || c == '#') {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", static_cast<unsigned char>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "?immutable=1";
}

class SqliteDatabase final : public Database {
 public:
  SqliteDatabase(const std::string& path, bool read_only) : path_(path), read_only_(read_only) {
    bool created = false;
    if (!read_only) created = create_if_missing();
    if (!created) {
      // Whose file it is, decided before it is opened (for writing, or for
      // reading a WAL file, which makes -wal and -shm files).
      if (sqlite3_open_v2(immutable_uri(path).c_str(), &db_, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr) !=
          SQLITE_OK) {
        std::string what = db_ ? sqlite3_errmsg(db_) : "out of memory";
        sqlite3_close(db_);
        db_ = nullptr;
        throw DbError("cannot open " + describe() + ": " + what);
      }
      try {
        check_ours();
      } catch (...) {
        sqlite3_close(db_);
        db_ = nullptr;
        throw;
      }
      sqlite3_close(db_);
      db_ = nullptr;
    }
    const int flags = read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE;
    if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      std::string what = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw DbError("cannot open " + describe() + ": " + what);
    }
    sqlite3_busy_timeout(db_, 5000);
    if (created) {
      // Stamp and tables in one transaction: the file is rvc's whole, or empty.
      exec("BEGIN EXCLUSIVE");
      exec("PRAGMA application_id=" + std::to_string(kApplicationId));
      for (const auto& sql : schema_statements(Dialect::Sqlite)) exec(sql);
      exec("COMMIT");
    }
    if (read_only) return;  // the dashboard changes nothing, not even the journal mode
    exec("PRAGMA journal_mode=WAL");
    exec("PRAGMA synchronous=NORMAL");  // WAL: durable at checkpoints, no fsync per batch
    exec("PRAGMA cache_size=-32768");   // 32 MiB: indexes of a long run stay in memory
    exec("PRAGMA wal_autocheckpoint=16384");  // checkpoint (and fsync) every 64 MiB of log, not every 4 MiB
  }
  ~SqliteDatabase() override {
    for (auto& [table, stmt] : inserts_) sqlite3_finalize(stmt);
    sqlite3_close(db_);
  }

  void ensure_schema() override {
    if (read_only_) return;
    if (!stamped_) exec("PRAGMA application_id=" + std::to_string(kApplicationId));  // an older rvc's file
    stamped_ = true;
    for (const auto& sql : schema_statements(Dialect::Sqlite)) exec(sql);
    for (const AddedColumn& c : added_columns())
      if (!has_column(c.table, c.column))
        exec(std::string("ALTER TABLE ") + c.table + " ADD COLUMN " + c.column + " " + c.type);
  }

  void write(const std::vector<Row>& rows) override {
    exec("BEGIN IMMEDIATE");
    try {
      for (const Row& row : rows) {
        sqlite3_stmt* stmt = insert(row.table);
        bind(stmt, row);
        const int rc = sqlite3_step(stmt);
        sqlite3_reset(stmt);
        if (rc != SQLITE_DONE) throw error("insert into " + std::string(table_name(row.table)));
      }
      exec("COMMIT");
    } catch (const DbError&) {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
      throw;
    }
  }

  // A file does not go away like a server; a failed write (disk full, a
  // lock held too long) is simply tried again.
  bool reconnect() override { return true; }

  QueryResult query(const std::string& sql, const std::vector<std::string>& params) override {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) throw error("query");
    for (size_t i = 0; i < params.size(); ++i)
      sqlite3_bind_text(stmt, static_cast<int>(i + 1), params[i].data(), static_cast<int>(params[i].size()),
                        SQLITE_TRANSIENT);
    QueryResult out;
    int rc;
    while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
      const int n = sqlite3_column_count(stmt);
      std::vector<std::string> row(n);
      for (int c = 0; c < n; ++c) {
        const auto* text = sqlite3_column_text(stmt, c);
        if (text) row[c].assign(reinterpret_cast<const char*>(text), sqlite3_column_bytes(stmt, c));
      }
      out.push_back(std::move(row));
    }
    sqlite3_finalize(stmt);
    if (rc != SQLITE_DONE) throw error("query");
    return out;
  }

  std::string describe() const override { return "sqlite:" + path_; }

 private:
  // The row's values in insert_statement()'s placeholder order, typed (no
  // text round trip for numbers) and not copied: the row outlives the step.
  static void bind(sqlite3_stmt* stmt, const Row& r) {
    int i = 0;
    auto text = [&](const std::string& v) {
      sqlite3_bind_text(stmt, ++i, v.data(), static_cast<int>(v.size()), SQLITE_STATIC);
    };
    auto real = [&](double v) { sqlite3_bind_double(stmt, ++i, v); };
    auto integer = [&](int64_t v) { sqlite3_bind_int64(stmt, ++i, v); };
    switch (r.table) {
      case Table::Run: text(r.run), text(r.text[0]), text(r.text[1]), text(r.text[2]), real(r.number[0]); break;
      case Table::Property: text(r.run), text(r.text[0]), text(r.text[1]); break;
      case Table::Verdict:
        text(r.run), text(r.text[0]), real(r.number[0]), integer(r.integer), real(r.number[1]), real(r.known());
        break;
      case Table::Violation:
        text(r.run), text(r.text[0]), real(r.number[0]), real(r.number[1]), text(r.text[1]), text(r.text[2]),
            real(r.known());
        break;
      case Table::Counters: text(r.run), real(r.number[1]), text(r.text[0]); break;
      case Table::RunEnd: text(r.text[0]), text(r.text[1]), real(r.number[1]), integer(r.integer), text(r.run); break;
    }
  }
  // Busy, locked, I/O and full-disk errors pass (another process holds the
  // file, space is freed): the store keeps the rows and tries again.
  DbError error(const std::string& what) const {
    const int code = sqlite3_errcode(db_) & 0xff;
    const bool transient = code == SQLITE_BUSY || code == SQLITE_LOCKED || code == SQLITE_IOERR ||
                           code == SQLITE_FULL || code == SQLITE_CANTOPEN || code == SQLITE_READONLY;
    return DbError(describe() + ": " + what + ": " + sqlite3_errmsg(db_), transient);
  }
  void exec(const std::string& sql) {
    char* message = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
      std::string what = message ? message : "unknown error";
      sqlite3_free(message);
      DbError e = error("");
      throw DbError(describe() + ": " + what + " (in: " + sql + ")", e.connection_lost());
    }
  }
  // SQLite has no ADD COLUMN IF NOT EXISTS.
  bool has_column(const std::string& table, const std::string& column) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db_, ("PRAGMA table_info(" + table + ")").c_str(), -1, &stmt, nullptr) != SQLITE_OK)
      throw error("table_info");
    bool found = false;
    while (sqlite3_step(stmt) == SQLITE_ROW)
      found = found || column == reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1));
    sqlite3_finalize(stmt);
    return found;
  }
  sqlite3_stmt* insert(Table table) {
    auto& stmt = inserts_[table];
    if (!stmt && sqlite3_prepare_v2(db_, insert_statement(table), -1, &stmt, nullptr) != SQLITE_OK)
      throw error("prepare");
    return stmt;
  }

  // True if this call made the (empty) file: it is rvc's to fill. A file
  // that exists and is empty may be another rvc's, between its creation and
  // its first commit (a moment): wait a little for its tables, then refuse.
  bool create_if_missing() {
    const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      return true;
    }
    if (errno != EEXIST) throw DbError("cannot create " + describe() + ": " + std::strerror(errno));
    struct stat st {};
    for (int i = 0; i < 100 && ::stat(path_.c_str(), &st) == 0 && st.st_size == 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return false;
  }

  // An existing file: rvc's (stamped, or an older rvc's table set), or refused
  // as it is.
  void check_ours() {
    struct stat st {};
    if (::stat(path_.c_str(), &st) == 0 && st.st_size == 0)
      throw DbError(describe() + " is an empty file that rvc did not create: refusing to turn it into a results "
                    "database (remove it, or name a new file)");
    QueryResult id, tables;
    try {
      id = query("PRAGMA application_id", {});
      tables = query("SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'", {});
    } catch (const DbError&) {
      throw DbError(describe() + " is not a results database rvc can read (" + sqlite3_errmsg(db_) + ")");
    }
    const long long app = id.empty() ? 0 : std::atoll(id[0][0].c_str());
    if (app == kApplicationId) {
      stamped_ = true;
      return;
    }
    std::set<std::string> names;
    for (const auto& row : tables) names.insert(row[0]);
    if (app == 0 && older_rvc(names)) return;  // made by an rvc before the stamp
    std::string listed;
    for (const auto& name : names) listed += (listed.empty() ? "" : ", ") + name;
    throw DbError(describe() + " is not an rvc results database (" +
                  (app ? "application_id " + std::to_string(app) + ", " : std::string()) +
                  (names.empty() ? std::string("no tables") : "tables: " + listed) +
                  "): refusing to change it (name a new file for rvc's results)");
  }

  // rvc's table names, each with (at least) the columns rvc gave it.
  bool older_rvc(const std::set<std::string>& names) {
    if (names.size() != rvc_tables().size()) return false;
    for (const auto& [table, columns] : rvc_tables()) {
      if (!names.count(table)) return false;
      for (const std::string& column : columns)
        if (!has_column(table, column)) return false;
    }
    return true;
  }

  std::string path_;
  bool read_only_ = false;
  bool stamped_ = false;  // application_id is rvc's
  sqlite3* db_ = nullptr;
  std::map<Table, sqlite3_stmt*> inserts_;
};

}  // namespace

std::unique_ptr<Database> open_sqlite(const std::string& path, bool read_only) {
  return std::make_unique<SqliteDatabase>(path, read_only);
}

}  // namespace rvc::store
