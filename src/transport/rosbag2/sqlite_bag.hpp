// rosbag2's sqlite3 storage (.db3): tables `topics` (id, name, type,
// serialization_format, ...), `messages` (id, topic_id, timestamp, data) and,
// from Iron on, `message_definitions` (topic_type, encoding,
// encoded_message_definition). Opened read-only and immutable through a
// file: URI, so SQLite neither writes nor creates anything beside the file
// (no journal, no -wal, no lock), even for a bag on a read-only medium.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "transport/rosbag2/bag_reader.hpp"

struct sqlite3;
struct sqlite3_stmt;

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
  // data is no blob is skipped with its reason; a database that SQLite finds
  // corrupt ends reading (BagError).
  bool next(BagMessage& m) override;

  // Topics, definitions, counts and time span, from the tables.
  void summarize(BagSummary& s) const;

 private:
  [[noreturn]] void fail(const std::string& what) const;
  bool has_table(const char* name) const;
  void require_columns(const char* table, std::initializer_list<const char*> columns) const;

  sqlite3* db_ = nullptr;
  sqlite3_stmt* rows_ = nullptr;
  std::map<int64_t, BagTopicInfo> topics_;  // by topic id
  uint64_t index_ = 0;
};

}  // namespace rvc::transport
