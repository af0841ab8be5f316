// SQLite backend: the embedded default (`--output sqlite:results.db`).
// WAL journal, so the dashboard (another process) reads while the monitor
// writes; one prepared statement per table, one transaction per batch.
#include <sqlite3.h>

#include <map>

#include "store/database.hpp"
#include "store/schema.hpp"

namespace rvc::store {
namespace {

class SqliteDatabase final : public Database {
 public:
  explicit SqliteDatabase(const std::string& path) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
      std::string what = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw DbError("cannot open " + describe() + ": " + what);
    }
    sqlite3_busy_timeout(db_, 5000);
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
      case Table::Verdict: text(r.run), text(r.text[0]), real(r.number[0]), integer(r.integer), real(r.number[1]); break;
      case Table::Violation:
        text(r.run), text(r.text[0]), real(r.number[0]), real(r.number[1]), text(r.text[1]), text(r.text[2]);
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

  std::string path_;
  sqlite3* db_ = nullptr;
  std::map<Table, sqlite3_stmt*> inserts_;
};

}  // namespace

std::unique_ptr<Database> open_sqlite(const std::string& path) { return std::make_unique<SqliteDatabase>(path); }

}  // namespace rvc::store
