// The results store: what a run checked and found, kept in a database
// (`--output sqlite:results.db`, `--output postgresql://...`).
//
// The engine thread only appends rows to a queue (and keeps the witness
// window, a ring of the last N input messages); a writer thread commits them
// in batches, one transaction each, so the store keeps up with the engine.
// When the database goes away, rows wait in memory and then in a spool file
// (JSON lines after a {"rvc_spool":1} header) while the writer reconnects;
// nothing is dropped. At the end the store waits for the database
// (wait_seconds; not at all after a stop signal); what still cannot be
// written stays in the spool, and the next run on the same spool writes it
// first. A spool write counts only once it is synced and its size checked:
// rows the spool could not take are reported as lost, never as kept.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <limits>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <unordered_map>
#include <vector>

#include "store/database.hpp"
#include "store/row.hpp"

namespace rvc::store {

struct StoreOptions {
  size_t witness = 10;             // input messages kept with each violation
  size_t max_witness_bytes = 4096;  // per message in the witness (longer ones are cut, marked "truncated")
  std::string spool;               // spool file; "" = "<database file>.spool" or "rvc-results.spool"
  size_t memory_rows = 100000;     // rows held in memory while the database is away, then the spool
  double flush_interval = 0.1;     // seconds between batches
  double retry_interval = 0.5;     // seconds between reconnection attempts (doubling up to 5 s)
  double wait_seconds = 10;        // at the end: how long to wait for an absent database
  // How many stop signals (SIGINT/SIGTERM) arrived; null: none ever. After
  // one, the end does not wait for an absent database (the rest is spooled at
  // once); a second one cuts any wait left (a slow drain: the rest is spooled).
  std::function<int()> stop_signals;
};

struct RunInfo {
  std::string command;                  // the command line
  std::vector<std::string> inputs;      // input names
  std::string time_model;               // "discrete" / "dense"
  std::vector<std::pair<std::string, std::string>> properties;  // name, spec
};

struct StoreStats {
  uint64_t rows = 0;         // rows written to the database
  uint64_t verdicts = 0;     // verdict changes stored
  uint64_t violations = 0;   // violations stored
  uint64_t spooled = 0;      // rows that went through the spool file
  uint64_t reconnects = 0;   // times the database came back
  uint64_t left_in_spool = 0;  // rows still in the spool at the end (database never came back)
  uint64_t refused = 0;      // rows the database refused as they are (reported one by one)
  std::string first_refusal;  // why the first of them was refused
  uint64_t lost = 0;         // rows neither in the database nor in the spool at the end (the spool failed)
  uint64_t outages = 0;      // times the database went away
};

// The first line of every spool file rvc writes: a file without it is not
// rvc's, and is never read, cut or deleted.
inline constexpr const char* kSpoolHeader = "{\"rvc_spool\":1}";

class ResultsStore {
 public:
  // `db` must already hold the schema. Rows left in the spool by an earlier
  // run are written first (from begin_run() on). Throws DbError (not a lost
  // connection: a usage error) when the spool file exists and is not an rvc
  // spool (no header, not a regular file, empty): it is left as it is.
  ResultsStore(std::unique_ptr<Database> db, StoreOptions options);
  ~ResultsStore();  // finishes (as end() without a run end) if end() was not called
  ResultsStore(const ResultsStore&) = delete;
  ResultsStore& operator=(const ResultsStore&) = delete;

  // Engine thread -----------------------------------------------------------
  // Starts the writer. Throws DbError (a usage error) if the spool file is
  // one of the run's inputs: rvc would read it as a spool, then delete it.
  void begin_run(const RunInfo& info);
  const std::string& run_id() const { return run_; }
  // An input message, before the engine sees it (the witness window).
  void on_message(std::string_view input, std::string_view payload, uint64_t position);
  // A verdict: stored if it changes the property's value; a change to false
  // is also a violation, stored with the witness window.
  // `explanation`: --explain's sentences for a violation's start (else null).
  // `known_at`: a delayed (bounded-future) verdict's known instant; NaN: `time`.
  void on_verdict(const std::string& property, double time, bool value,
                  const std::vector<std::string>* explanation = nullptr,
                  double known_at = std::numeric_limits<double>::quiet_NaN());
  // A counters snapshot (JSON object).
  void on_counters(std::string_view counters_json);
  // The run ended: final counters, exit status. Then waits for the writer to
  // commit everything (up to wait_seconds while the database is away).
  // Returns false if rows remain in the spool: the run's results are not all
  // in the database yet (the reason is printed).
  bool end_run(int exit_status, std::string_view reason, std::string_view final_counters);

  StoreStats stats() const;
  std::string describe() const { return description_; }

 private:
  struct Witness {
    std::string input;
    uint64_t position = 0;
    std::string payload;
  };
  void push(Row row);
  std::string witness_json() const;
  void writer_loop();
  bool write_batch(std::vector<Row>& batch);  // writer thread; false: database away
  void write_one_by_one(std::vector<Row>& batch);  // after a refused batch: keep every row it can
  bool spill(std::vector<Row>& rows);          // to the spool file; false: kept in pending_ (it failed)
  bool append_to_spool(const std::vector<Row>& rows, std::string& error);  // synced and size-checked
  bool drain_spool();                          // spool -> database; false: database away
  void went_away(const std::string& why);      // writer thread: the database is away (printed a few times)
  void wrote();                                // writer thread: a write succeeded (back, if it was away)
  bool cut_wait() const { return options_.stop_signals && options_.stop_signals() >= 2; }
  bool finish(double wait_seconds);

  std::unique_ptr<Database> db_;
  StoreOptions options_;
  std::string description_;
  std::string run_;

  // Engine thread only.
  std::vector<Witness> ring_;
  size_t ring_next_ = 0, ring_size_ = 0;
  std::unordered_map<std::string, int> last_value_;  // property -> 0/1

  // Shared with the writer.
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<Row> queue_;
  bool stopping_ = false;
  bool done_ = false;      // writer exited
  bool flushed_ = false;   // writer found queue and spool empty after stopping_
  std::chrono::steady_clock::time_point deadline_;  // of finish(): stop waiting for the database
  StoreStats stats_;
  std::thread writer_;

  // Writer thread only.
  std::deque<Row> pending_;  // failed to write, in order
  bool spooling_ = false;    // the spool file holds rows older than pending_/queue_
  bool connected_ = true;
  bool away_ = false;        // the database went away and no write succeeded since
  bool spool_failing_ = false;  // the last spool write failed (said once per streak)
  std::chrono::steady_clock::time_point spool_retry_;  // no spool write before (while it fails)
  std::string spool_error_;  // why the spool could not be written
  bool started_ = false;     // begin_run() started the writer
  int spool_lock_ = -1;      // flock on "<spool>.lock": one process per spool file
  bool lock_created_ = false;  // the .lock is rvc's: removed at the end
};

}  // namespace rvc::store
