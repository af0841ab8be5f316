#include "transport/rosbag2/sqlite_bag.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cstdio>

namespace rvc::transport {

namespace {

// A path as a file: URI (RFC 3986 percent-encoding of what a URI reserves).
std::string file_uri(const std::string& path) {
  std::string uri = "file:";
  for (unsigned char c : path) {
    if (c == '?' || c == '#' || c == '%' || c < 0x20 || c >= 0x7f) {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", c);
      uri += buf;
    } else {
      uri += static_cast<char>(c);
    }
  }
  return uri + "?immutable=1";
}

const char* type_name(int t) {
  switch (t) {
    case SQLITE_INTEGER: return "an integer";
    case SQLITE_FLOAT: return "a real";
    case SQLITE_TEXT: return "text";
    case SQLITE_BLOB: return "a blob";
    default: return "NULL";
  }
}

std::string text_column(sqlite3_stmt* s, int i) {
  const unsigned char* t = sqlite3_column_text(s, i);
  return t ? std::string(reinterpret_cast<const char*>(t), static_cast<size_t>(sqlite3_column_bytes(s, i))) : "";
}

// One prepared statement, finalized on every path out.
struct Statement {
  sqlite3_stmt* s = nullptr;
  ~Statement() { sqlite3_finalize(s); }
};

}  // namespace

void SqliteBag::fail(const std::string& what) const { throw BagError("bag '" + path_ + "': " + what); }

SqliteBag::SqliteBag(const std::string& path) : BagReader(path) {
  if (sqlite3_open_v2(file_uri(path).c_str(), &db_, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr) != SQLITE_OK) {
    const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    fail("cannot open it as a SQLite database: " + why);
  }
  try {
    // SQLite reads the header only now: a file that is no database fails here.
    if (!has_table("topics") || !has_table("messages"))
      fail(std::string("a SQLite database, but not a rosbag2 bag: it has no table '") +
           (has_table("topics") ? "messages" : "topics") + "'");
    require_columns("topics", {"id", "name", "type", "serialization_format"});
    require_columns("messages", {"topic_id", "timestamp", "data"});
    Statement st;
    if (sqlite3_prepare_v2(db_, "SELECT id, name, type, serialization_format FROM topics", -1, &st.s, nullptr) !=
        SQLITE_OK)
      fail(std::string("table 'topics': ") + sqlite3_errmsg(db_));
    for (int row = 1, rc; (rc = sqlite3_step(st.s)) != SQLITE_DONE; ++row) {
      if (rc != SQLITE_ROW) fail(std::string("table 'topics': ") + sqlite3_errmsg(db_));
      if (sqlite3_column_type(st.s, 0) != SQLITE_INTEGER || sqlite3_column_type(st.s, 1) != SQLITE_TEXT)
        fail("table 'topics', row " + std::to_string(row) + ": id is " + type_name(sqlite3_column_type(st.s, 0)) +
             " and name " + type_name(sqlite3_column_type(st.s, 1)) + " (expected an integer and text)");
      BagTopicInfo t;
      t.name = text_column(st.s, 1);
      t.type = text_column(st.s, 2);
      t.encoding = text_column(st.s, 3);
      topics_[sqlite3_column_int64(st.s, 0)] = std::move(t);
    }
    if (has_table("message_definitions")) {  // Iron and later: the types' own text
      require_columns("message_definitions", {"topic_type", "encoding", "encoded_message_definition"});
      Statement defs;
      if (sqlite3_prepare_v2(db_, "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions",
                             -1, &defs.s, nullptr) != SQLITE_OK)
        fail(std::string("table 'message_definitions': ") + sqlite3_errmsg(db_));
      int rc;
      while ((rc = sqlite3_step(defs.s)) == SQLITE_ROW) {
        const std::string type = text_column(defs.s, 0);
        // A service's events (pkg/srv/Name_Event) are recorded with the
        // .srv text under pkg/srv/Name, as MCAP's schema carries it.
        for (auto& [id, t] : topics_)
          if (t.type == type || (t.definition.empty() && t.type == type + "_Event")) {
            t.definition_encoding = text_column(defs.s, 1);
            t.definition = text_column(defs.s, 2);
          }
      }
      if (rc != SQLITE_DONE) fail(std::string("table 'message_definitions': ") + sqlite3_errmsg(db_));
    }
    if (sqlite3_prepare_v2(db_, "SELECT topic_id, timestamp, data, id FROM messages ORDER BY timestamp, id", -1, &rows_,
                           nullptr) != SQLITE_OK)
      fail(std::string("table 'messages': ") + sqlite3_errmsg(db_));
  } catch (...) {
    sqlite3_finalize(rows_);
    sqlite3_close(db_);
    throw;
  }
}

SqliteBag::~SqliteBag() {
  sqlite3_finalize(rows_);
  sqlite3_close(db_);
}

bool SqliteBag::has_table(const char* name) const {
  Statement st;
  if (sqlite3_prepare_v2(db_, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", -1, &st.s, nullptr) !=
      SQLITE_OK)
    fail(std::string("SQLite cannot read it: ") + sqlite3_errmsg(db_));
  sqlite3_bind_text(st.s, 1, name, -1, SQLITE_STATIC);
  const int rc = sqlite3_step(st.s);
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) fail(std::string("SQLite cannot read it: ") + sqlite3_errmsg(db_));
  return rc == SQLITE_ROW;
}

void SqliteBag::require_columns(const char* table, std::initializer_list<const char*> columns) const {
  Statement st;
  const std::string sql = std::string("PRAGMA table_info(") + table + ")";
  if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &st.s, nullptr) != SQLITE_OK)
    fail(std::string("table '") + table + "': " + sqlite3_errmsg(db_));
  std::vector<std::string> have;
  while (sqlite3_step(st.s) == SQLITE_ROW) have.push_back(text_column(st.s, 1));
  for (const char* c : columns)
    if (std::find(have.begin(), have.end(), c) == have.end())
      fail(std::string("a SQLite database, but not a rosbag2 bag: table '") + table + "' has no column '" + c + "'");
}

bool SqliteBag::next(BagMessage& m) {
  for (;;) {
    const int rc = sqlite3_step(rows_);
    if (rc == SQLITE_DONE) return false;
    if (rc != SQLITE_ROW)
      fail("SQLite cannot read on after message " + std::to_string(index_) + ": " + sqlite3_errmsg(db_));
    const uint64_t n = ++index_;
    const std::string where = "message " + std::to_string(n) + " (row id " +
                              std::to_string(sqlite3_column_int64(rows_, 3)) + " of table 'messages')";
    const int ttype = sqlite3_column_type(rows_, 0), stype = sqlite3_column_type(rows_, 1),
              dtype = sqlite3_column_type(rows_, 2);
    if (ttype != SQLITE_INTEGER) {
      skipped(where + ": topic_id is " + type_name(ttype) + ", not an integer (skipped)");
      continue;
    }
    const auto topic = topics_.find(sqlite3_column_int64(rows_, 0));
    if (topic == topics_.end()) {
      skipped(where + ": topic_id " + std::to_string(sqlite3_column_int64(rows_, 0)) +
              " is no row of table 'topics' (skipped)");
      continue;
    }
    if (stype != SQLITE_INTEGER || sqlite3_column_int64(rows_, 1) < 0) {
      skipped(where + ": timestamp is " + (stype == SQLITE_INTEGER ? "negative" : type_name(stype)) +
              ", not nanoseconds since the epoch (skipped)");
      continue;
    }
    if (dtype != SQLITE_BLOB && dtype != SQLITE_TEXT) {  // an empty blob reads as NULL only if written so
      skipped(where + ": data is " + std::string(type_name(dtype)) + ", not a blob (skipped)");
      continue;
    }
    const void* data = sqlite3_column_blob(rows_, 2);
    m.topic = topic->second.name;
    m.data = std::string_view(static_cast<const char*>(data), static_cast<size_t>(sqlite3_column_bytes(rows_, 2)));
    m.log_time = static_cast<uint64_t>(sqlite3_column_int64(rows_, 1));
    m.index = n;
    return true;
  }
}

void SqliteBag::summarize(BagSummary& s) const {
  s.storage = "sqlite3";
  std::map<int64_t, BagTopicInfo> topics = topics_;
  Statement st;
  if (sqlite3_prepare_v2(db_,
                         "SELECT topic_id, count(*), min(timestamp), max(timestamp) FROM messages "
                         "WHERE typeof(timestamp) = 'integer' AND timestamp >= 0 GROUP BY topic_id",
                         -1, &st.s, nullptr) != SQLITE_OK)
    fail(std::string("table 'messages': ") + sqlite3_errmsg(db_));
  int rc;
  while ((rc = sqlite3_step(st.s)) == SQLITE_ROW) {
    const auto t = topics.find(sqlite3_column_int64(st.s, 0));
    if (t == topics.end()) continue;  // reported as skipped when the messages are read
    t->second.messages = static_cast<uint64_t>(sqlite3_column_int64(st.s, 1));
    t->second.first_time = static_cast<uint64_t>(sqlite3_column_int64(st.s, 2));
    t->second.last_time = static_cast<uint64_t>(sqlite3_column_int64(st.s, 3));
  }
  if (rc != SQLITE_DONE) s.broken = "bag '" + path_ + "': SQLite cannot read table 'messages': " + sqlite3_errmsg(db_);
  for (auto& [id, t] : topics) s.topics.push_back(std::move(t));
}

}  // namespace rvc::transport
