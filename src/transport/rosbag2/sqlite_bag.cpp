#include "transport/rosbag2/sqlite_bag.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

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
  scan_.reset();
  sqlite3_value_free(last_timestamp_);
  sqlite3_finalize(rows_);
  sqlite3_close(db_);
}

void SqliteBag::start_scan(const std::string& why) {
  sort_error_ = why;
  sqlite3_finalize(rows_);
  rows_ = nullptr;
  scan_ = std::make_unique<SqliteRows>(db_, "topic_id, timestamp, data, rowid");
}

// SQLite's order of values (NULL, numbers, text, blobs; text and blobs
// bytewise), as ORDER BY timestamp, id had them: a row at or before the last
// one read in that order was read then (or skipped for its timestamp).
bool SqliteBag::read_already(sqlite3_stmt* st) const {
  if (!started_) return false;
  auto rank = [](int type) { return type == SQLITE_NULL ? 0 : type == SQLITE_TEXT ? 2 : type == SQLITE_BLOB ? 3 : 1; };
  const int type = sqlite3_column_type(st, 1);
  const int last_type = last_is_int_ ? SQLITE_INTEGER : sqlite3_value_type(last_timestamp_);
  int c = rank(type) - rank(last_type);
  if (c == 0 && rank(type) == 1) {
    if (type == SQLITE_INTEGER && last_type == SQLITE_INTEGER) {
      const int64_t a = sqlite3_column_int64(st, 1);
      const int64_t b = last_is_int_ ? last_int_ : sqlite3_value_int64(last_timestamp_);
      c = a < b ? -1 : a > b ? 1 : 0;
    } else {
      const double a = sqlite3_column_double(st, 1);
      const double b = last_is_int_ ? static_cast<double>(last_int_) : sqlite3_value_double(last_timestamp_);
      c = a < b ? -1 : a > b ? 1 : 0;
    }
  } else if (c == 0 && rank(type) > 1) {
    const void* a = type == SQLITE_TEXT ? static_cast<const void*>(sqlite3_column_text(st, 1)) : sqlite3_column_blob(st, 1);
    const int na = sqlite3_column_bytes(st, 1);
    const void* b = type == SQLITE_TEXT ? static_cast<const void*>(sqlite3_value_text(last_timestamp_))
                                        : sqlite3_value_blob(last_timestamp_);
    const int nb = sqlite3_value_bytes(last_timestamp_);
    const int m = std::memcmp(a ? a : "", b ? b : "", static_cast<size_t>(std::min(na, nb)));
    c = m != 0 ? m : na - nb;
  }
  return c < 0 || (c == 0 && sqlite3_column_int64(st, 3) <= last_id_);
}

namespace {
std::string row_span(int64_t from, int64_t to) {
  if (from == INT64_MIN && to == INT64_MAX) return "all the rows";
  if (to == INT64_MAX) return "the rows from row id " + std::to_string(from) + " on";
  if (from == INT64_MIN) return "the rows before row id " + std::to_string(to + 1);
  if (from == to) return "row id " + std::to_string(from);
  return "row ids " + std::to_string(from) + "-" + std::to_string(to);
}
}  // namespace

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
    sqlite3_stmt* st = rows_;  // the row's statement: time-ordered, or the scan's
    if (!scan_) {
      const int rc = sqlite3_step(st);
      if (rc == SQLITE_DONE) return false;
      if (rc != SQLITE_ROW) {
        start_scan(sqlite3_errmsg(db_));
        continue;
      }
      // Kept for start_scan (an integer as it is: no allocation per row).
      last_id_ = sqlite3_column_int64(st, 3);
      started_ = true;
      if ((last_is_int_ = sqlite3_column_type(st, 1) == SQLITE_INTEGER)) {
        last_int_ = sqlite3_column_int64(st, 1);
      } else {
        sqlite3_value_free(last_timestamp_);
        last_timestamp_ = sqlite3_value_dup(sqlite3_column_value(st, 1));
      }
    } else {
      switch (scan_->step()) {
        case SqliteRows::Row:
          st = scan_->stmt();
          if (read_already(st)) continue;
          break;
        case SqliteRows::Done:
          if (!damage_reported_ && !sort_error_.empty()) {  // every row read: the damage was elsewhere (an index)
            damage_reported_ = true;
            skipped("SQLite cannot read table 'messages' in time order (" + sort_error_ +
                    "), yet every row of it read in row-id order: the damage is in an index (nothing skipped)");
          }
          return false;
        case SqliteRows::Damaged:
          damage_reported_ = true;
          skipped(row_span(scan_->lost_from(), scan_->lost_to()) + " of table 'messages' cannot be read (SQLite: " +
                  scan_->error() + "), after message " + std::to_string(index_) + ": skipped; reading goes on at row id " +
                  std::to_string(scan_->lost_to() + 1));
          continue;
        case SqliteRows::Stuck:
          fail("SQLite cannot read on after message " + std::to_string(index_) + ": " +
               row_span(scan_->lost_from(), INT64_MAX) + " of table 'messages' cannot be read (" + scan_->error() + ")");
      }
    }
    const uint64_t n = ++index_;
    const std::string where = "message " + std::to_string(n) + " (row id " +
                              std::to_string(sqlite3_column_int64(st, 3)) + " of table 'messages')";
    const int ttype = sqlite3_column_type(st, 0), stype = sqlite3_column_type(st, 1),
              dtype = sqlite3_column_type(st, 2);
    if (ttype != SQLITE_INTEGER) {
      skipped(where + ": topic_id is " + type_name(ttype) + ", not an integer (skipped)");
      continue;
    }
    const auto topic = topics_.find(sqlite3_column_int64(st, 0));
    if (topic == topics_.end()) {
      skipped(where + ": topic_id " + std::to_string(sqlite3_column_int64(st, 0)) +
              " is no row of table 'topics' (skipped)");
      continue;
    }
    if (stype != SQLITE_INTEGER || sqlite3_column_int64(st, 1) < 0) {
      skipped(where + ": timestamp is " + (stype == SQLITE_INTEGER ? "negative" : type_name(stype)) +
              ", not nanoseconds since the epoch (skipped)");
      continue;
    }
    if (dtype != SQLITE_BLOB && dtype != SQLITE_TEXT) {  // an empty blob reads as NULL only if written so
      skipped(where + ": data is " + std::string(type_name(dtype)) + ", not a blob (skipped)");
      continue;
    }
    const void* data = sqlite3_column_blob(st, 2);
    m.topic = topic->second.name;
    m.data = std::string_view(static_cast<const char*>(data), static_cast<size_t>(sqlite3_column_bytes(st, 2)));
    m.log_time = static_cast<uint64_t>(sqlite3_column_int64(st, 1));
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
  if (rc != SQLITE_DONE) {
    // Damaged: count what a read around the damage finds (as next() reads it).
    for (auto& [id, t] : topics) t.messages = t.first_time = t.last_time = 0;
    SqliteRows scan(db_, "topic_id, timestamp, rowid");
    for (bool more = true; more;) {
      switch (scan.step()) {
        case SqliteRows::Row: {
          sqlite3_stmt* r = scan.stmt();
          if (sqlite3_column_type(r, 0) != SQLITE_INTEGER || sqlite3_column_type(r, 1) != SQLITE_INTEGER) break;
          const int64_t ts = sqlite3_column_int64(r, 1);
          const auto t = topics.find(sqlite3_column_int64(r, 0));
          if (ts < 0 || t == topics.end()) break;
          BagTopicInfo& info = t->second;
          const auto u = static_cast<uint64_t>(ts);
          info.first_time = info.messages ? std::min(info.first_time, u) : u;
          info.last_time = info.messages ? std::max(info.last_time, u) : u;
          ++info.messages;
          break;
        }
        case SqliteRows::Done: more = false; break;
        case SqliteRows::Damaged:
          if (s.first_skipped.empty())
            s.first_skipped = "bag '" + path_ + "': " + row_span(scan.lost_from(), scan.lost_to()) +
                              " of table 'messages' cannot be read (SQLite: " + scan.error() + ")";
          break;
        case SqliteRows::Stuck:
          s.broken = "bag '" + path_ + "': SQLite cannot read " + row_span(scan.lost_from(), INT64_MAX) +
                     " of table 'messages' (" + scan.error() + ")";
          more = false;
          break;
      }
    }
  }
  for (auto& [id, t] : topics) s.topics.push_back(std::move(t));
}

}  // namespace rvc::transport
