// PostgreSQL backend (`--output postgresql://user@host/db`), over libpq.
//
// One connection, used by one thread at a time (a PGconn is not
// thread-safe): the store's writer, or a reader such as the dashboard with
// its own instance. A batch is one transaction: the append-only tables
// (verdicts, violations, counters) go in with COPY, one stream per table,
// about 4x faster than prepared INSERTs over a unix socket and far more over
// a network, where each INSERT costs a round trip. Runs and properties need
// ON CONFLICT / UPDATE, so they use prepared statements; there are few.

#include <set>
#include <string_view>

#include "store/database.hpp"
#include "store/libpq_loader.hpp"
#include "store/schema.hpp"

namespace rvc::store {
namespace {

// libpq messages end in a newline and may span lines ("server closed the
// connection unexpectedly\n\tThis probably means ..."): make them one line.
std::string one_line(const char* message) {
  std::string out;
  bool space = false;
  for (const char* p = message ? message : ""; *p; ++p) {
    const bool ws = *p == '\n' || *p == '\r' || *p == '\t' || *p == ' ';
    if (ws) {
      space = !out.empty();
      continue;
    }
    if (space) out += ' ';
    space = false;
    out += *p;
  }
  return out.empty() ? "unknown error" : out;
}

// The URI without its password: the user part's ":secret" and any
// password=... parameter. Other conninfo forms (key=value) are rebuilt from
// libpq's own parse, minus the password.
std::string without_password(const std::string& conninfo) {
  const auto scheme = conninfo.find("://");
  if (scheme == std::string::npos) {
    PQconninfoOption* options = libpq().PQconninfoParse(conninfo.c_str(), nullptr);
    if (!options) return "postgresql (unparsable conninfo)";
    std::string out;
    for (auto* o = options; o->keyword; ++o) {
      if (!o->val || std::string_view(o->keyword) == "password") continue;
      if (!out.empty()) out += ' ';
      out += std::string(o->keyword) + "=" + o->val;
    }
    libpq().PQconninfoFree(options);
    return out;
  }
  std::string base = conninfo, query;
  if (const auto q = conninfo.find('?', scheme); q != std::string::npos) {
    base = conninfo.substr(0, q);
    query = conninfo.substr(q + 1);
  }
  // user:password@host; a password may hold '/' or '@' if not encoded, so
  // the user part ends at the last '@'.
  if (const auto at = base.rfind('@'); at != std::string::npos && at > scheme) {
    const auto colon = base.find(':', scheme + 3);
    if (colon < at && base.find('/', scheme + 3) > colon) base.erase(colon, at - colon);
  }
  std::string kept;
  size_t start = 0;
  while (start <= query.size() && !query.empty()) {
    size_t end = query.find('&', start);
    if (end == std::string::npos) end = query.size();
    const std::string param = query.substr(start, end - start);
    if (param.rfind("password=", 0) != 0 && !param.empty()) kept += (kept.empty() ? "" : "&") + param;
    start = end + 1;
  }
  return kept.empty() ? base : base + "?" + kept;
}

// '?' placeholders to $1, $2, ...; a '?' inside '...' or "..." stays.
std::string number_placeholders(const std::string& sql) {
  std::string out;
  char quote = 0;
  int n = 0;
  for (char c : sql) {
    if (quote) {
      if (c == quote) quote = 0;  // a doubled quote toggles twice: still fine
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '?') {
      out += '$' + std::to_string(++n);
      continue;
    }
    out += c;
  }
  return out;
}

// "INSERT INTO t (a, b) VALUES ..." -> "COPY t (a, b) FROM STDIN": the
// column list stays the one insert_values() fills.
std::string copy_statement(Table table) {
  const std::string insert = insert_statement(table);
  const std::string prefix = "INSERT INTO ";
  const auto values = insert.find(" VALUES");
  if (insert.rfind(prefix, 0) != 0 || values == std::string::npos) return "";
  return "COPY " + insert.substr(prefix.size(), values - prefix.size()) + " FROM STDIN";
}

// COPY text format: a tab between values, a newline after the row, and
// backslash escapes for the characters that would be read as either (a
// literal backslash too, so no value reads as \N or as the \. end marker).
void append_copy_value(std::string& out, const std::string& value) {
  for (char c : value) {
    switch (c) {
      case '\\': out += "\\\\"; break;
      case '\t': out += "\\t"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      default: out += c;
    }
  }
}

// Any lock id will do, as long as every rvc uses the same one.
constexpr long long kSchemaLock = 0x7276635f736368;  // "rvc_sch"

class PostgresDatabase final : public Database {
 public:
  explicit PostgresDatabase(const std::string& conninfo) : description_(without_password(conninfo)) {
    // Defaults, listed before the conninfo so that its own values win. Our
    // texts are UTF-8 whatever PGCLIENTENCODING says. The timeouts make a
    // host that vanishes (no RST: a cable, a VM) noticed within about a
    // minute instead of TCP's 15 (sending) or 2 h (waiting for a reply), so
    // the writer thread gets to reconnect and spool; unix sockets ignore them.
    const char* keys[] = {"client_encoding", "connect_timeout", "keepalives_idle", "keepalives_interval",
                          "keepalives_count", "tcp_user_timeout", "dbname", nullptr};
    const char* values[] = {"UTF8", "10", "30", "10", "3", "60000", conninfo.c_str(), nullptr};
    conn_ = libpq().PQconnectdbParams(keys, values, /*expand_dbname=*/1);
    if (!conn_ || libpq().PQstatus(conn_) != CONNECTION_OK) {
      const std::string what = conn_ ? one_line(libpq().PQerrorMessage(conn_)) : "out of memory";
      libpq().PQfinish(conn_);
      conn_ = nullptr;
      throw DbError("cannot connect to " + describe() + ": " + what, true);
    }
    // NOTICEs ("relation already exists, skipping") would go to stderr.
    libpq().PQsetNoticeProcessor(conn_, [](void*, const char*) {}, nullptr);
  }
  ~PostgresDatabase() override { libpq().PQfinish(conn_); }

  void ensure_schema() override {
    // CREATE ... IF NOT EXISTS is not safe against a concurrent CREATE (one
    // of two fails on a unique index of the catalog): a transaction-scoped
    // advisory lock makes a second rvc wait for the first.
    std::string sql = "BEGIN; SELECT pg_advisory_xact_lock(" + std::to_string(kSchemaLock) + ");";
    for (const auto& statement : schema_statements(Dialect::Postgres)) sql += statement + ";";
    for (const AddedColumn& c : added_columns())
      sql += std::string("ALTER TABLE ") + c.table + " ADD COLUMN IF NOT EXISTS " + c.column + " " + c.type + ";";
    sql += "COMMIT";
    transaction([&] { exec(sql, "schema"); });
  }

  void write(const std::vector<Row>& rows) override {
    if (rows.empty()) return;
    // Runs first and run ends last: an end updates its run's row, which may
    // be in the same batch. Per table the rows keep their order (ids grow).
    std::vector<const Row*> by_table[6];
    for (const Row& row : rows) by_table[static_cast<int>(row.table)].push_back(&row);
    transaction([&] {
      exec("BEGIN", "begin");
      for (Table t : {Table::Run, Table::Property}) execute_each(t, by_table[static_cast<int>(t)]);
      for (Table t : {Table::Verdict, Table::Violation, Table::Counters}) copy(t, by_table[static_cast<int>(t)]);
      execute_each(Table::RunEnd, by_table[static_cast<int>(Table::RunEnd)]);
      exec("COMMIT", "commit");
    });
  }

  bool reconnect() override {
    libpq().PQreset(conn_);
    if (libpq().PQstatus(conn_) != CONNECTION_OK) return false;
    prepared_.clear();  // a new session has none of them
    try {
      ensure_schema();
      return true;
    } catch (const DbError&) {
      return false;
    }
  }

  QueryResult query(const std::string& sql, const std::vector<std::string>& params) override {
    std::vector<const char*> values;
    for (const auto& p : params) values.push_back(p.c_str());
    PGresult* res = libpq().PQexecParams(conn_, number_placeholders(sql).c_str(), static_cast<int>(values.size()), nullptr,
                                 values.data(), nullptr, nullptr, 0);
    check(res, "query");
    QueryResult out;
    const int rows = libpq().PQntuples(res), columns = libpq().PQnfields(res);
    out.reserve(rows);
    for (int r = 0; r < rows; ++r) {
      std::vector<std::string> row(columns);
      for (int c = 0; c < columns; ++c)
        if (!libpq().PQgetisnull(res, r, c)) row[c].assign(libpq().PQgetvalue(res, r, c), libpq().PQgetlength(res, r, c));
      out.push_back(std::move(row));
    }
    libpq().PQclear(res);
    return out;
  }

  std::string describe() const override { return description_; }

 private:
  // Runs `body` (which begins and commits); on an error rolls back what the
  // server still holds open, then rethrows.
  template <typename Body>
  void transaction(Body&& body) {
    try {
      body();
    } catch (const DbError&) {
      if (libpq().PQstatus(conn_) == CONNECTION_OK && libpq().PQtransactionStatus(conn_) != PQTRANS_IDLE)
        libpq().PQclear(libpq().PQexec(conn_, "ROLLBACK"));
      throw;
    }
  }

  // The error of a failed call. The connection counts as lost if libpq says
  // so, or if the server said it is going away (shutdown, crash recovery) or
  // failed the connection (SQLSTATE class 08): reconnect() may help then;
  // for any other error the same statement would fail again.
  DbError error(const std::string& what, const PGresult* res) const {
    const char* state = res ? libpq().PQresultErrorField(res, PG_DIAG_SQLSTATE) : nullptr;
    const std::string code = state ? state : "";
    const bool lost = libpq().PQstatus(conn_) != CONNECTION_OK || code.rfind("08", 0) == 0 || code.rfind("57P", 0) == 0;
    const char* message = res && *libpq().PQresultErrorMessage(res) ? libpq().PQresultErrorMessage(res) : libpq().PQerrorMessage(conn_);
    return DbError(what + ": " + one_line(message), lost);
  }

  // Throws (and frees `res`) unless `res` is a success.
  void check(PGresult* res, const std::string& what) const {
    const auto status = res ? libpq().PQresultStatus(res) : PGRES_FATAL_ERROR;
    if (status == PGRES_COMMAND_OK || status == PGRES_TUPLES_OK) return;
    DbError e = error(what, res);
    libpq().PQclear(res);
    throw e;
  }

  void exec(const std::string& sql, const std::string& what) {
    if (libpq().PQstatus(conn_) != CONNECTION_OK) throw DbError(what + ": not connected", true);
    // Several statements in one string: PQexec returns the last result, or
    // the first error (the rest is skipped).
    PGresult* res = libpq().PQexec(conn_, sql.c_str());
    check(res, what);
    libpq().PQclear(res);
  }

  void execute_each(Table table, const std::vector<const Row*>& rows) {
    if (rows.empty()) return;
    const std::string name = std::string("rvc_") + table_name(table);
    if (!prepared_.count(table)) {
      check(libpq().PQprepare(conn_, name.c_str(), number_placeholders(insert_statement(table)).c_str(), 0, nullptr),
            "prepare " + name);
      prepared_.insert(table);
    }
    std::vector<const char*> params;
    for (const Row* row : rows) {
      const auto values = insert_values(*row);
      params.clear();
      for (const auto& v : values) params.push_back(v.c_str());
      PGresult* res = libpq().PQexecPrepared(conn_, name.c_str(), static_cast<int>(params.size()), params.data(), nullptr,
                                     nullptr, 0);
      check(res, std::string("write ") + table_name(table));
      libpq().PQclear(res);
    }
  }

  void copy(Table table, const std::vector<const Row*>& rows) {
    if (rows.empty()) return;
    const std::string what = std::string("write ") + table_name(table) + " (COPY)";
    PGresult* res = libpq().PQexec(conn_, copy_statement(table).c_str());
    if (!res || libpq().PQresultStatus(res) != PGRES_COPY_IN) {
      DbError e = error(what, res);
      libpq().PQclear(res);
      throw e;
    }
    libpq().PQclear(res);
    // Sent in pieces of about 1 MB: a batch of violations with long witness
    // windows need not be built in memory all at once.
    std::string data;
    data.reserve(1 << 20);
    bool sent = true;
    for (const Row* row : rows) {
      const auto values = insert_values(*row);
      for (size_t i = 0; i < values.size(); ++i) {
        if (i) data += '\t';
        append_copy_value(data, values[i]);
      }
      data += '\n';
      if (data.size() >= (1 << 20)) {
        sent = libpq().PQputCopyData(conn_, data.data(), static_cast<int>(data.size())) == 1;
        data.clear();
        if (!sent) break;
      }
    }
    if (sent && !data.empty()) sent = libpq().PQputCopyData(conn_, data.data(), static_cast<int>(data.size())) == 1;
    libpq().PQputCopyEnd(conn_, sent ? nullptr : "rvc: sending the rows failed");
    // The COPY's own result, then NULL; a dead connection gives an error
    // result too (never an endless PGRES_COPY_IN once the copy is ended).
    PGresult* outcome = nullptr;
    while (PGresult* r = libpq().PQgetResult(conn_)) {
      const bool stuck = libpq().PQresultStatus(r) == PGRES_COPY_IN;
      if (!outcome) outcome = r;
      else libpq().PQclear(r);
      if (stuck) break;
    }
    if (outcome && libpq().PQresultStatus(outcome) == PGRES_COMMAND_OK) {
      libpq().PQclear(outcome);
      return;
    }
    // Still copying after the end was sent: the session is unusable.
    const bool stuck = outcome && libpq().PQresultStatus(outcome) == PGRES_COPY_IN;
    DbError e = stuck ? DbError(what + ": the server did not end the copy", true) : error(what, outcome);
    libpq().PQclear(outcome);
    throw e;
  }

  std::string description_;
  PGconn* conn_ = nullptr;
  std::set<Table> prepared_;  // statements this session has prepared
};

// Values libpq accepts for its enumerated options (libpq's documentation,
// "Parameter Key Words"); anything else fails every connection attempt.
const char* allowed_values(std::string_view keyword) {
  if (keyword == "sslmode") return "disable allow prefer require verify-ca verify-full";
  if (keyword == "gssencmode" || keyword == "channel_binding") return "disable prefer require";
  if (keyword == "target_session_attrs") return "any read-write read-only primary standby prefer-standby";
  if (keyword == "load_balance_hosts") return "disable random";
  return nullptr;
}

bool all_digits(std::string_view s) { return !s.empty() && s.find_first_not_of("0123456789") == std::string_view::npos; }

}  // namespace

void check_postgres_conninfo(const std::string& conninfo) {
  const std::string shown = redact_password(conninfo);
  char* message = nullptr;
  PQconninfoOption* options = libpq().PQconninfoParse(conninfo.c_str(), &message);
  if (!options) {
    const std::string why = message ? one_line(message) : "out of memory";
    if (message) libpq().PQfreemem(message);
    throw DbError("bad PostgreSQL URI '" + shown + "': " + why);
  }
  std::string problem;
  for (auto* o = options; o->keyword && problem.empty(); ++o) {
    if (!o->val) continue;
    const std::string_view keyword = o->keyword, value = o->val;
    if (keyword == "port") {
      // One port, or one per host (host=a,b port=5432,5433); empty: the default.
      size_t start = 0;
      for (;;) {
        const size_t comma = value.find(',', start);
        const std::string_view port = value.substr(start, comma == std::string_view::npos ? comma : comma - start);
        if (!port.empty() && (!all_digits(port) || port.size() > 5 || std::stoi(std::string(port)) < 1 ||
                              std::stoi(std::string(port)) > 65535))
          problem = "port '" + std::string(port) + "' is not a port number (1 to 65535)";
        if (comma == std::string_view::npos || !problem.empty()) break;
        start = comma + 1;
      }
    } else if (const char* allowed = allowed_values(keyword)) {
      const std::string words = std::string(" ") + allowed + " ";
      if (words.find(" " + std::string(value) + " ") == std::string::npos)
        problem = std::string(keyword) + "=" + std::string(value) + " is not one of: " + allowed;
    } else if (keyword == "connect_timeout" || keyword.rfind("keepalives", 0) == 0 ||
               keyword == "tcp_user_timeout") {
      if (!value.empty() && !all_digits(value))
        problem = std::string(keyword) + "=" + std::string(value) + " is not a whole number";
    }
  }
  libpq().PQconninfoFree(options);
  if (!problem.empty()) throw DbError("bad PostgreSQL URI '" + shown + "': " + problem);
}

std::unique_ptr<Database> open_postgres(const std::string& conninfo) {
  return std::make_unique<PostgresDatabase>(conninfo);
}

}  // namespace rvc::store
