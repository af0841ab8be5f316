#include "store/results_store.hpp"

#include <fcntl.h>
#include <simdjson.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <random>

#include "io/json_writer.hpp"

namespace rvc::store {
namespace {

using Clock = std::chrono::steady_clock;
constexpr size_t kBatchRows = 10000;  // rows per transaction (and a full queue wakes the writer)

double wall_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// "20261123-181500-4242-a3f9": sorts by start time, unique across hosts'
// processes in practice, readable in the dashboard.
std::string new_run_id() {
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char when[32];
  std::strftime(when, sizeof when, "%Y%m%d-%H%M%S", &tm);
  std::random_device rd;
  char out[80];
  std::snprintf(out, sizeof out, "%s-%d-%04x", when, static_cast<int>(::getpid()), rd() & 0xffff);
  return out;
}

}  // namespace

namespace {

// "rvc-results-<database>.spool": a spool belongs to one database, so rows
// kept for one are never written into another.
std::string default_spool(const std::string& description) {
  const std::string prefix = "sqlite:";
  if (description.rfind(prefix, 0) == 0) return description.substr(prefix.size()) + ".spool";
  std::string name = "rvc-results-";
  for (char c : description.substr(description.find("://") == std::string::npos ? 0 : description.find("://") + 3))
    name += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.' ? c : '_';
  return name.substr(0, 120) + ".spool";
}

}  // namespace

ResultsStore::ResultsStore(std::unique_ptr<Database> db, StoreOptions options)
    : db_(std::move(db)), options_(std::move(options)), description_(db_->describe()) {
  if (options_.spool.empty()) options_.spool = default_spool(description_);
  // Two processes must not append to, drain and cut the same spool: the
  // second one on a spool that is taken uses its own.
  for (int attempt = 0; attempt < 2; ++attempt) {
    spool_lock_ = ::open((options_.spool + ".lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (spool_lock_ >= 0 && ::flock(spool_lock_, LOCK_EX | LOCK_NB) == 0) break;
    if (spool_lock_ >= 0) ::close(spool_lock_);
    spool_lock_ = -1;
    if (attempt == 0) {
      const std::string own = options_.spool + "." + std::to_string(::getpid());
      std::fprintf(stderr, "rvc: results spool %s is in use by another rvc: using %s\n", options_.spool.c_str(),
                   own.c_str());
      options_.spool = own;
    }
  }
  ring_.resize(options_.witness);
  // An earlier run's spool is written before anything of this run.
  if (std::ifstream(options_.spool).good()) spooling_ = true;
  writer_ = std::thread([this] { writer_loop(); });
}

ResultsStore::~ResultsStore() {
  if (!done_) finish(0);
  if (spool_lock_ >= 0) {
    ::unlink((options_.spool + ".lock").c_str());
    ::close(spool_lock_);
  }
}

void ResultsStore::push(Row row) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue_.push_back(std::move(row));
  if (queue_.size() >= kBatchRows) wake_.notify_one();
}

void ResultsStore::begin_run(const RunInfo& info) {
  run_ = new_run_id();
  io::JsonArray inputs;
  for (const auto& name : info.inputs) {
    std::string s;
    io::append_json_string(s, name);
    inputs.add_raw(s);
  }
  Row run;
  run.table = Table::Run;
  run.run = run_;
  run.text[0] = info.command;
  run.text[1] = inputs.str();
  run.text[2] = info.time_model;
  run.number[0] = wall_now();
  push(std::move(run));
  for (const auto& [name, spec] : info.properties) {
    Row p;
    p.table = Table::Property;
    p.run = run_;
    p.text[0] = name;
    p.text[1] = spec;
    push(std::move(p));
  }
}

void ResultsStore::on_message(std::string_view input, std::string_view payload, uint64_t position) {
  if (ring_.empty()) return;
  Witness& w = ring_[ring_next_];
  w.input.assign(input);  // assign: the ring's strings keep their capacity
  w.position = position;
  w.payload.assign(payload.substr(0, options_.max_witness_bytes + 1));
  ring_next_ = (ring_next_ + 1) % ring_.size();
  ring_size_ = std::min(ring_size_ + 1, ring_.size());
}

std::string ResultsStore::witness_json() const {
  io::JsonArray out;
  for (size_t k = 0; k < ring_size_; ++k) {
    const Witness& w = ring_[(ring_next_ + ring_.size() - ring_size_ + k) % ring_.size()];
    io::JsonObject o;
    o.add("input", w.input).add("seq", w.position);
    std::string_view text = w.payload;
    const bool truncated = text.size() > options_.max_witness_bytes;
    if (truncated) text = text.substr(0, options_.max_witness_bytes);
    // JSON payloads are text; a CDR sample (or text cut inside a character)
    // is not UTF-8 and is kept as hex, which every database stores as text.
    if (simdjson::validate_utf8(text.data(), text.size())) {
      o.add("payload", text);
    } else {
      static const char* digits = "0123456789abcdef";
      std::string hex;
      hex.reserve(text.size() * 2);
      for (unsigned char c : text) {
        hex += digits[c >> 4];
        hex += digits[c & 15];
      }
      o.add("payload_hex", hex);
    }
    if (truncated) o.add("truncated", true);
    out.add(o);
  }
  return out.str();
}

void ResultsStore::on_verdict(const std::string& property, double time, bool value,
                              const std::vector<std::string>* explanation) {
  auto [it, first] = last_value_.try_emplace(property, value ? 1 : 0);
  if (!first && it->second == (value ? 1 : 0)) return;
  it->second = value ? 1 : 0;
  const double wall = wall_now();
  Row v;
  v.table = Table::Verdict;
  v.run = run_;
  v.text[0] = property;
  v.number[0] = time;
  v.number[1] = wall;
  v.integer = value ? 1 : 0;
  push(std::move(v));
  if (!value) {
    Row violation;
    violation.table = Table::Violation;
    violation.run = run_;
    violation.text[0] = property;
    violation.text[1] = witness_json();
    if (explanation) {
      io::JsonArray sentences;
      for (const std::string& sentence : *explanation) {
        std::string quoted;
        io::append_json_string(quoted, sentence);
        sentences.add_raw(quoted);
      }
      violation.text[2] = sentences.str();
    }
    violation.number[0] = time;
    violation.number[1] = wall;
    push(std::move(violation));
  }
}

void ResultsStore::on_counters(std::string_view counters_json) {
  Row c;
  c.table = Table::Counters;
  c.run = run_;
  c.text[0] = std::string(counters_json);
  c.number[1] = wall_now();
  push(std::move(c));
}

bool ResultsStore::end_run(int exit_status, std::string_view reason, std::string_view final_counters) {
  Row end;
  end.table = Table::RunEnd;
  end.run = run_;
  end.text[0] = std::string(reason);
  end.text[1] = std::string(final_counters);
  end.number[1] = wall_now();
  end.integer = exit_status;
  push(std::move(end));
  return finish(options_.wait_seconds);
}

StoreStats ResultsStore::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

// Writer thread -------------------------------------------------------------

bool ResultsStore::write_batch(std::vector<Row>& batch) {
  if (batch.empty()) return true;
  try {
    db_->write(batch);
  } catch (const DbError& e) {
    if (!e.connection_lost()) {
      // The rows themselves were refused (one of them, most likely): retrying
      // the batch would refuse it forever and hold back everything behind it.
      write_one_by_one(batch);
      return connected_;
    }
    if (connected_)
      std::fprintf(stderr, "rvc: results database %s: %s; keeping results and retrying\n", description_.c_str(),
                   e.what());
    connected_ = false;
    return false;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.rows += batch.size();
  for (const Row& r : batch) {
    stats_.verdicts += r.table == Table::Verdict;
    stats_.violations += r.table == Table::Violation;
  }
  return true;
}

void ResultsStore::write_one_by_one(std::vector<Row>& batch) {
  std::vector<Row> rest;
  for (size_t i = 0; i < batch.size(); ++i) {
    try {
      db_->write({batch[i]});
      std::lock_guard<std::mutex> lock(mutex_);
      ++stats_.rows;
      stats_.verdicts += batch[i].table == Table::Verdict;
      stats_.violations += batch[i].table == Table::Violation;
    } catch (const DbError& e) {
      if (e.connection_lost()) {  // gone in the middle: the rest waits
        connected_ = false;
        rest.assign(std::make_move_iterator(batch.begin() + i), std::make_move_iterator(batch.end()));
        break;
      }
      uint64_t refused;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        refused = ++stats_.refused;
      }
      if (refused <= 10)
        std::fprintf(stderr, "rvc: results database %s refused a %s row of run %s: %s\n", description_.c_str(),
                     table_name(batch[i].table), batch[i].run.c_str(), e.what());
    }
  }
  batch = std::move(rest);
}

void ResultsStore::spill(std::vector<Row>& rows) {
  if (rows.empty()) return;
  std::ofstream out(options_.spool, std::ios::app);
  for (const Row& r : rows) out << to_spool_line(r) << '\n';
  out.flush();
  if (!out) {
    // No database and no disk: keep them in memory (the end reports them).
    std::fprintf(stderr, "rvc: cannot write the results spool %s: keeping %zu rows in memory\n",
                 options_.spool.c_str(), rows.size());
    pending_.insert(pending_.end(), rows.begin(), rows.end());
  } else {
    spooling_ = true;
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.spooled += rows.size();
  }
  rows.clear();
}

bool ResultsStore::drain_spool() {
  std::ifstream in(options_.spool);
  std::vector<Row> rows;
  std::string line, error;
  uint64_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    Row r;
    if (!from_spool_line(line, r, error)) {
      std::fprintf(stderr, "rvc: results spool %s line %llu: %s (line skipped)\n", options_.spool.c_str(),
                   static_cast<unsigned long long>(number), error.c_str());
      continue;
    }
    rows.push_back(std::move(r));
  }
  in.close();
  size_t done = 0;
  while (done < rows.size()) {
    const size_t n = std::min(kBatchRows, rows.size() - done);
    std::vector<Row> batch(std::make_move_iterator(rows.begin() + done), std::make_move_iterator(rows.begin() + done + n));
    if (!write_batch(batch)) {
      // Keep what is not written yet, and only that: a later drain must not
      // write the committed batches twice.
      // (write_batch may have kept only the rows after a lost connection.)
      const size_t kept_from = done + n - batch.size();
      for (size_t i = 0; i < batch.size(); ++i) rows[kept_from + i] = std::move(batch[i]);
      const std::string next = options_.spool + ".next";
      {
        std::ofstream out(next, std::ios::trunc);
        for (size_t i = kept_from; i < rows.size(); ++i) out << to_spool_line(rows[i]) << '\n';
      }
      std::rename(next.c_str(), options_.spool.c_str());  // atomic: a crash leaves the old or the new spool
      return false;
    }
    done += n;
  }
  std::remove(options_.spool.c_str());
  spooling_ = false;
  return true;
}

void ResultsStore::writer_loop() {
  double backoff = options_.retry_interval;
  auto next_attempt = Clock::now();
  std::vector<Row> batch;
  for (;;) {
    bool stopping;
    Clock::time_point deadline;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      // While stopping with the database away there is nothing to do until
      // the next attempt: wait without the stopping_ predicate (no spinning).
      if (stopping_ && !connected_)
        wake_.wait_for(lock, std::chrono::milliseconds(50));
      else
        wake_.wait_for(lock, std::chrono::duration<double>(options_.flush_interval),
                       [this] { return stopping_ || queue_.size() >= kBatchRows; });
      batch.swap(queue_);
      stopping = stopping_;
      deadline = deadline_;
    }
    const auto now = Clock::now();
    if (!connected_ && now >= next_attempt) {
      if (db_->reconnect()) {
        connected_ = true;
        backoff = options_.retry_interval;
        std::fprintf(stderr, "rvc: results database %s is back: writing what was kept\n", description_.c_str());
        std::lock_guard<std::mutex> lock(mutex_);
        ++stats_.reconnects;
      } else {
        next_attempt = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(backoff));
        backoff = std::min(backoff * 2, 5.0);
      }
    }
    // Oldest first: the spool, then rows kept in memory, then this batch.
    if (connected_ && spooling_) drain_spool();
    if (connected_ && !spooling_ && !pending_.empty()) {
      std::vector<Row> kept(std::make_move_iterator(pending_.begin()), std::make_move_iterator(pending_.end()));
      pending_.clear();
      if (!write_batch(kept)) pending_.assign(std::make_move_iterator(kept.begin()), std::make_move_iterator(kept.end()));
    }
    if (connected_ && !spooling_ && pending_.empty()) {
      if (!write_batch(batch)) pending_.assign(std::make_move_iterator(batch.begin()), std::make_move_iterator(batch.end()));
    } else if (spooling_) {
      spill(batch);  // behind what is already spooled
    } else {
      pending_.insert(pending_.end(), std::make_move_iterator(batch.begin()), std::make_move_iterator(batch.end()));
    }
    batch.clear();
    if (pending_.size() > options_.memory_rows) {
      std::vector<Row> all(std::make_move_iterator(pending_.begin()), std::make_move_iterator(pending_.end()));
      pending_.clear();
      spill(all);
    }
    if (stopping) {
      bool empty;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        empty = queue_.empty();
      }
      if (empty && pending_.empty() && !spooling_) {
        std::lock_guard<std::mutex> lock(mutex_);
        flushed_ = true;
        break;
      }
      if (empty && Clock::now() >= deadline) {
        std::vector<Row> all(std::make_move_iterator(pending_.begin()), std::make_move_iterator(pending_.end()));
        pending_.clear();
        spill(all);
        break;
      }
    }
  }
}

bool ResultsStore::finish(double wait_seconds) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    deadline_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait_seconds));
  }
  wake_.notify_one();
  if (writer_.joinable()) writer_.join();
  done_ = true;
  if (flushed_) return true;
  uint64_t left = 0;
  std::ifstream in(options_.spool);
  std::string line;
  while (std::getline(in, line)) left += !line.empty();
  left += pending_.size();
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.left_in_spool = left;
  std::fprintf(stderr,
               "rvc: results database %s did not come back within %.1f s: %llu rows kept in %s (the next run with this "
               "spool writes them)\n",
               description_.c_str(), wait_seconds, static_cast<unsigned long long>(left), options_.spool.c_str());
  return false;
}

}  // namespace rvc::store
