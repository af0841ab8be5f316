#include "transport/rosbag2/sqlite_rows.hpp"

#include <sqlite3.h>

#include <algorithm>

namespace rvc::transport {

namespace {
// Row ids as unsigned offsets from INT64_MIN: distances and midpoints never overflow.
uint64_t offset(int64_t id) { return static_cast<uint64_t>(id) ^ (uint64_t{1} << 63); }
int64_t from_offset(uint64_t o) { return static_cast<int64_t>(o ^ (uint64_t{1} << 63)); }
}  // namespace

SqliteRows::SqliteRows(sqlite3* db, std::string columns) : db_(db), columns_(std::move(columns)) {
  // A file of N pages has at most N damaged ones: more restarts than that
  // means a b-tree so damaged that searches land in it anywhere (a crawl
  // through 2^64 row ids, one at a time), and the scan stops.
  sqlite3_stmt* st = nullptr;
  if (sqlite3_prepare_v2(db_, "PRAGMA page_count", -1, &st, nullptr) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
    max_restarts_ = static_cast<uint64_t>(std::max<int64_t>(0, sqlite3_column_int64(st, 0))) * 2 + 16;
  sqlite3_finalize(st);
}

SqliteRows::~SqliteRows() {
  sqlite3_finalize(st_);
  sqlite3_finalize(probe_);
}

// Both statements are prepared once and reset for each new start: a damaged
// schema can make a prepare costly (a table of 2,000 columns), and one
// damaged page costs up to 128 probes.
bool SqliteRows::open_at(int64_t id) {
  if (!prepared_) {
    prepared_ = true;
    const std::string sql = "SELECT " + columns_ + " FROM messages WHERE rowid >= ?1 ORDER BY rowid";
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &st_, nullptr) != SQLITE_OK) {
      sqlite3_finalize(st_);
      st_ = nullptr;
    }
  }
  if (!st_) return false;
  sqlite3_reset(st_);
  sqlite3_bind_int64(st_, 1, id);
  open_ = true;
  start_ = id;
  return true;
}

bool SqliteRows::readable_at(int64_t id) {
  // The same columns as the scan: a row whose data spills onto a bad
  // overflow page fails here too, not only when the scan reaches it.
  if (!probe_) {
    const std::string sql = "SELECT " + columns_ + " FROM messages WHERE rowid >= ?1 ORDER BY rowid LIMIT 1";
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &probe_, nullptr) != SQLITE_OK) {
      sqlite3_finalize(probe_);
      probe_ = nullptr;
      return false;
    }
  }
  sqlite3_reset(probe_);
  sqlite3_bind_int64(probe_, 1, id);
  const int rc = sqlite3_step(probe_);
  sqlite3_reset(probe_);
  return rc == SQLITE_ROW || rc == SQLITE_DONE;
}

SqliteRows::Step SqliteRows::step() {
  for (;;) {
    if (!open_ && !open_at(next_)) {
      error_ = sqlite3_errmsg(db_);
      lost_from_ = next_;
      lost_to_ = INT64_MAX;
      return Stuck;
    }
    const int rc = sqlite3_step(st_);
    if (rc == SQLITE_ROW) {
      // The place to go on from only moves forward: a damaged b-tree may give
      // row ids out of order, and going back to one would read in circles.
      const int64_t id = sqlite3_column_int64(st_, sqlite3_column_count(st_) - 1);
      if (id < start_) continue;  // a damaged b-tree's row before where this search began: passed already
      if (id == INT64_MAX) at_end_ = true;
      else if (id >= next_) next_ = id + 1;
      return Row;
    }
    if (rc == SQLITE_DONE || at_end_) return Done;
    error_ = sqlite3_errmsg(db_);
    open_ = false;  // the next step starts the statement again, where reading goes on
    const int64_t from = next_;
    if (++restarts_ > max_restarts_) {
      error_ += "; damaged in more places than the file has pages: reading stopped";
      lost_from_ = from;
      lost_to_ = INT64_MAX;
      return Stuck;
    }
    // A fresh search from the root may read on where the scan stopped (the
    // step failed on its way between leaves): once per place, so a failure
    // that repeats there is stepped over below.
    if (!(retry_armed_ && retried_ == from) && readable_at(from)) {
      retried_ = from;
      retry_armed_ = true;
      continue;
    }
    // Probes at from+1, +2, +4, ... until one reads, then bisection: the
    // smallest row id past the failure where reading works again.
    uint64_t bad = offset(from), good = 0;
    bool found = false;
    for (uint64_t d = 1; d != 0; d <<= 1) {
      const uint64_t c = UINT64_MAX - offset(from) < d ? UINT64_MAX : offset(from) + d;
      if (readable_at(from_offset(c))) {
        good = c;
        found = true;
        break;
      }
      bad = c;
      if (c == UINT64_MAX) break;
    }
    if (!found) {
      lost_from_ = from;
      lost_to_ = INT64_MAX;
      return Stuck;
    }
    while (good - bad > 1) {
      const uint64_t mid = bad + (good - bad) / 2;
      if (readable_at(from_offset(mid))) good = mid;
      else bad = mid;
    }
    lost_from_ = from;
    lost_to_ = from_offset(good) - 1;
    next_ = from_offset(good);
    return Damaged;
  }
}

}  // namespace rvc::transport
