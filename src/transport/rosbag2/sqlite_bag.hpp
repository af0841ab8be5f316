// rosbag2's sqlite3 storage (.db3): tables `topics` (id, name, type,
// serialization_format, ...), `messages` (id, topic_id, timestamp, data) and,
// from Iron on, `message_definitions` (topic_type, encoding,
// encoded_message_definition). Opened read-only and immutable through a
// file: URI, so SQLite neither writes nor creates anything beside the file
// (no journal, no -wal, no lock), even for a bag on a read-only medium.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "transport/rosbag2/bag_reader.hpp"
#include "transport/rosbag2/sqlite_rows.hpp"

struct sqlite3;
struct sqlite3_stmt;
struct sqlite3_value;

namespace rvc::transport {

class SqliteBag : public BagReader {
 public:
  // Throws BagError for a file that is no SQLite database or no rosbag2 bag
  // (a table or a column missing), naming what is missing.
  explicit SqliteBag(const std::string& path);
  ~SqliteBag() override;
  SqliteBag(const SqliteBag&) = delete;
  SqliteBag& operator=(const SqliteBag&) = delete;

  // Messages by timestamp (then row id: the order they were written). A row
  // whose topic_id names no topic, whose timestamp is no integer or whose
  // data is no blob is skipped with its reason.
  //
  // A database that SQLite finds damaged part-way is read around the damage
  // (SqliteRows): from the first failure on, the rows not read yet come in
  // row-id order (the order rosbag2 wrote them), each damaged stretch is
  // skipped once with the row ids it lost, and reading goes on after it.
  // BagError only when nothing after the damage can be read.
  bool next(BagMessage& m) override;

  // Topics, definitions, counts and time span, from the tables; for a
  // damaged table, from a pass over the rows that can be read (the first
  // damage in first_skipped, or in broken if reading could not go on).
  void summarize(BagSummary& s) const;

 private:
  [[noreturn]] void fail(const std::string& what) const;
  bool has_table(const char* name) const;
  void require_columns(const char* table, std::initializer_list<const char*> columns) const;

  void start_scan(const std::string& why);
  bool read_already(sqlite3_stmt* st) const;  // whether the time-ordered read had passed this row

  sqlite3* db_ = nullptr;
  sqlite3_stmt* rows_ = nullptr;
  std::map<int64_t, BagTopicInfo> topics_;  // by topic id
  uint64_t index_ = 0;
  // Where the time-ordered read stopped: the last row's (timestamp, id),
  // for the row-id scan to take only the rows after it.
  bool started_ = false, last_is_int_ = false;
  int64_t last_int_ = 0, last_id_ = 0;
  sqlite3_value* last_timestamp_ = nullptr;  // when it is no integer
  std::unique_ptr<SqliteRows> scan_;  // the read around damaged pages, once one was met
  std::string sort_error_;            // why the time-ordered read stopped
  bool damage_reported_ = false;
};

}  // namespace rvc::transport
