// The rows of a rosbag2 `messages` table in row-id order, read around the
// pages SQLite finds damaged, so a bag with one bad page loses only the rows
// on that page (SQLite's own cursor stops at the first bad page for good).
//
// A row-id order scan walks the table's b-tree leaf by leaf. When a step
// fails (SQLITE_CORRUPT, a short read of a file cut short, ...), the scan
// looks for the smallest row id at or after the failure where a fresh
// search of the b-tree reads a row again: probes at growing distances, then
// a bisection between the last probe that failed and the first that read.
// The rows in between are lost (they were on the bad page); the scan goes on
// from there. One damaged leaf costs about 2 x 64 probes, each one search
// from the root; a bag without damage never probes.
#pragma once

#include <cstdint>
#include <string>

struct sqlite3;
struct sqlite3_stmt;

namespace rvc::transport {

class SqliteRows {
 public:
  // `columns`: what each row gives (its last column must be `rowid`). Every
  // row is returned (no WHERE on other columns: a filter would make SQLite
  // pass over rows the scan cannot then account for).
  SqliteRows(sqlite3* db, std::string columns);
  ~SqliteRows();
  SqliteRows(const SqliteRows&) = delete;
  SqliteRows& operator=(const SqliteRows&) = delete;

  enum Step { Row, Done, Damaged, Stuck };
  // Row: the row is in stmt(). Damaged: rows from lost_from() to lost_to()
  // could not be read (error() says why); the next step goes on after
  // them. Stuck: no row after the failure could be read (a file cut short,
  // the table's root page damaged): the scan ends.
  Step step();
  sqlite3_stmt* stmt() const { return st_; }
  const std::string& error() const { return error_; }
  // The first row id that was not read (INT64_MIN: the table's start), and
  // the last one lost; lost_to() < INT64_MAX unless Stuck.
  int64_t lost_from() const { return lost_from_; }
  int64_t lost_to() const { return lost_to_; }

 private:
  bool open_at(int64_t id);    // a statement reading rows with rowid >= id
  bool readable_at(int64_t id);  // whether a fresh search reads a row (or the end) at rowid >= id

  sqlite3* db_;
  std::string columns_;
  sqlite3_stmt* st_ = nullptr;     // the scan
  sqlite3_stmt* probe_ = nullptr;  // one row at rowid >= ?1
  bool prepared_ = false, open_ = false;
  int64_t start_ = INT64_MIN;  // where the open statement's search began
  uint64_t restarts_ = 0, max_restarts_ = uint64_t{1} << 20;
  int64_t next_ = INT64_MIN;  // the first row id not read yet
  int64_t retried_ = INT64_MIN;  // a failure where a fresh search read on: failing there again skips it
  bool retry_armed_ = false;
  bool at_end_ = false;  // the row with the largest possible id was read
  int64_t lost_from_ = 0, lost_to_ = 0;
  std::string error_;
};

}  // namespace rvc::transport
