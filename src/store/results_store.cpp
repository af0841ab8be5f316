#include "store/results_store.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <simdjson.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
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

// Why `path` cannot be used as a spool, or "" if it can: it does not exist
// yet, or it is a regular file that starts with rvc's spool header (or, as
// spools written before the header, with a spooled row).
std::string not_a_spool(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return errno == ENOENT ? "" : std::strerror(errno);
  if (!S_ISREG(st.st_mode)) return "it is not a regular file";
  if (st.st_size == 0) return "it is an empty file that rvc did not write";
  std::ifstream in(path);
  std::string first, error;
  std::getline(in, first);
  Row row;
  if (first == kSpoolHeader || from_spool_line(first, row, error)) return "";
  return std::string("its first line is not rvc's spool header ") + kSpoolHeader;
}

}  // namespace

ResultsStore::ResultsStore(std::unique_ptr<Database> db, StoreOptions options)
    : db_(std::move(db)), options_(std::move(options)), description_(db_->describe()) {
  if (options_.spool.empty()) options_.spool = default_spool(description_);
  // A spool is read, cut and deleted: a file that is not one is refused as
  // it is (an input named by mistake, the database itself).
  if (const std::string why = not_a_spool(options_.spool); !why.empty())
    throw DbError("results spool '" + options_.spool + "' cannot be used: " + why +
                  " (name a new file with --spool, or remove it)");
  // Two processes must not append to, drain and cut the same spool: the
  // second one on a spool that is taken uses its own.
  for (int attempt = 0; attempt < 2; ++attempt) {
    const std::string lock = options_.spool + ".lock";
    spool_lock_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    lock_created_ = spool_lock_ >= 0;
    if (spool_lock_ < 0) spool_lock_ = ::open(lock.c_str(), O_RDWR | O_CLOEXEC);  // rvc's or another's: kept
    if (spool_lock_ >= 0 && ::flock(spool_lock_, LOCK_EX | LOCK_NB) == 0) break;
    if (spool_lock_ >= 0) ::close(spool_lock_);
    if (lock_created_) ::unlink(lock.c_str());
    spool_lock_ = -1;
    lock_created_ = false;
    if (attempt == 0) {
      const std::string own = options_.spool + "." + std::to_string(::getpid());
      std::fprintf(stderr, "rvc: results spool %s is in use by another rvc: using %s\n", options_.spool.c_str(),
                   own.c_str());
      options_.spool = own;
      if (const std::string why = not_a_spool(own); !why.empty())
        throw DbError("results spool '" + own + "' cannot be used: " + why + " (remove it)");
    }
  }
  ring_.resize(options_.witness);
  // An earlier run's spool is written before anything of this run.
  struct stat st {};
  if (::stat(options_.spool.c_str(), &st) == 0) spooling_ = true;
}

ResultsStore::~ResultsStore() {
  if (!done_) finish(0);
  if (spool_lock_ >= 0) {
    if (lock_created_) ::unlink((options_.spool + ".lock").c_str());
    ::close(spool_lock_);
  }
}

void ResultsStore::push(Row row) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue_.push_back(std::move(row));
  if (queue_.size() >= kBatchRows) wake_.notify_one();
}

void ResultsStore::begin_run(const RunInfo& info) {
  for (const std::string& uri : info.inputs) {
    std::string path = uri;
    for (const char* scheme : {"file:", "mcap:"})
      if (path.rfind(scheme, 0) == 0) path = path.substr(std::strlen(scheme));
    struct stat a {}, b {};
    if (path != "-" && ::stat(path.c_str(), &a) == 0 && ::stat(options_.spool.c_str(), &b) == 0 &&
        a.st_dev == b.st_dev && a.st_ino == b.st_ino)
      throw DbError("results spool '" + options_.spool + "' is the input '" + uri +
                    "': it would be read as a spool, then deleted (name another file with --spool)");
  }
  if (!started_) {
    // The writer never takes a stop signal: it goes to the thread that
    // reads, whose read it ends (cli/signals.hpp).
    sigset_t block, saved;
    sigemptyset(&block);
    for (int sig : {SIGINT, SIGTERM, SIGUSR1, SIGHUP}) sigaddset(&block, sig);
    pthread_sigmask(SIG_BLOCK, &block, &saved);
    writer_ = std::thread([this] { writer_loop(); });
    pthread_sigmask(SIG_SETMASK, &saved, nullptr);
    started_ = true;
  }
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
                              const std::vector<std::string>* explanation, double known_at) {
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
  v.known_at = known_at;
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
    violation.known_at = known_at;
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
  // Stopped by a signal: whatever waits for the database goes to the spool
  // now (docker's grace period is short, and a second signal is a SIGKILL).
  const bool stopped = options_.stop_signals && options_.stop_signals() > 0;
  return finish(stopped ? 0 : options_.wait_seconds);
}

StoreStats ResultsStore::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

// Writer thread -------------------------------------------------------------

namespace {
constexpr uint64_t kReportedOutages = 3;  // then counted, and summed up at the end
}

void ResultsStore::went_away(const std::string& why) {
  connected_ = false;
  if (away_) return;
  away_ = true;
  uint64_t outages;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    outages = ++stats_.outages;
  }
  if (outages <= kReportedOutages)
    std::fprintf(stderr, "rvc: results database %s: %s; keeping results and retrying\n", description_.c_str(),
                 why.c_str());
  if (outages == kReportedOutages)
    std::fprintf(stderr, "rvc: results database %s keeps going away: further outages are counted, not printed\n",
                 description_.c_str());
}

// "Back" only once a write went through: a database that accepts the
// reconnection and fails the next write (a full disk) stays away, silently.
void ResultsStore::wrote() {
  if (!away_) return;
  away_ = false;
  uint64_t outages;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    outages = stats_.outages;
    ++stats_.reconnects;
  }
  if (outages <= kReportedOutages)
    std::fprintf(stderr, "rvc: results database %s is back: writing what was kept\n", description_.c_str());
}

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
    went_away(e.what());
    return false;
  }
  wrote();
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
      wrote();
      std::lock_guard<std::mutex> lock(mutex_);
      ++stats_.rows;
      stats_.verdicts += batch[i].table == Table::Verdict;
      stats_.violations += batch[i].table == Table::Violation;
    } catch (const DbError& e) {
      if (e.connection_lost()) {  // gone in the middle: the rest waits
        went_away(e.what());
        rest.assign(std::make_move_iterator(batch.begin() + i), std::make_move_iterator(batch.end()));
        break;
      }
      uint64_t refused;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        refused = ++stats_.refused;
        if (refused == 1) stats_.first_refusal = std::string("a ") + table_name(batch[i].table) + " row: " + e.what();
      }
      if (refused <= 10)
        std::fprintf(stderr, "rvc: results database %s refused a %s row of run %s: %s\n", description_.c_str(),
                     table_name(batch[i].table), batch[i].run.c_str(), e.what());
    }
  }
  batch = std::move(rest);
}

// Appends the rows (after the header, in a new spool) and makes sure they
// are there: written whole, synced to the disk, and the file grown by exactly
// their size. On any failure the file is cut back to where it was (no half
// row), and removed if this call created it.
bool ResultsStore::append_to_spool(const std::vector<Row>& rows, std::string& error) {
  struct stat st {};
  const bool fresh = ::stat(options_.spool.c_str(), &st) != 0;
  const int fd = ::open(options_.spool.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) {
    error = std::strerror(errno);
    return false;
  }
  off_t before = 0;
  if (::fstat(fd, &st) == 0) before = st.st_size;
  std::string text;
  if (before == 0) text = std::string(kSpoolHeader) + '\n';
  for (const Row& r : rows) text += to_spool_line(r) + '\n';
  bool ok = true;
  for (size_t done = 0; ok && done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = n < 0 ? std::strerror(errno) : "nothing written";
      ok = false;
    } else {
      done += static_cast<size_t>(n);
    }
  }
  if (ok && ::fsync(fd) != 0) {
    error = std::string("fsync: ") + std::strerror(errno);
    ok = false;
  }
  if (ok && (::fstat(fd, &st) != 0 || st.st_size != before + static_cast<off_t>(text.size()))) {
    error = "the file did not grow by the rows written";
    ok = false;
  }
  if (!ok) {
    if (::ftruncate(fd, before) == 0 && before == 0 && fresh) ::unlink(options_.spool.c_str());
  }
  ::close(fd);
  return ok;
}

bool ResultsStore::spill(std::vector<Row>& rows) {
  if (rows.empty()) return true;
  std::string error;
  if (!append_to_spool(rows, error)) {
    // No database and no disk: the rows stay in memory; the end says
    // truthfully where each row is.
    if (!spool_failing_)
      std::fprintf(stderr, "rvc: cannot write the results spool %s: %s; keeping %zu rows in memory\n",
                   options_.spool.c_str(), error.c_str(), rows.size());
    spool_failing_ = true;
    spool_error_ = error;
    spool_retry_ = Clock::now() + std::chrono::seconds(1);
    pending_.insert(pending_.end(), std::make_move_iterator(rows.begin()), std::make_move_iterator(rows.end()));
    rows.clear();
    return false;
  }
  if (spool_failing_)
    std::fprintf(stderr, "rvc: the results spool %s takes rows again\n", options_.spool.c_str());
  spool_failing_ = false;
  spooling_ = true;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.spooled += rows.size();
  }
  rows.clear();
  return true;
}

bool ResultsStore::drain_spool() {
  std::ifstream in(options_.spool);
  std::vector<Row> rows;
  std::string line, error;
  uint64_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || (number == 1 && line == kSpoolHeader)) continue;
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
    // A second stop signal while the run ends: the rest stays in the spool.
    const bool cut = [this] {
      std::lock_guard<std::mutex> lock(mutex_);
      return stopping_;
    }() && cut_wait();
    if (cut || !write_batch(batch)) {
      // Keep what is not written yet, and only that: a later drain must not
      // write the committed batches twice.
      // (write_batch may have kept only the rows after a lost connection.)
      const size_t kept_from = done + n - batch.size();
      for (size_t i = 0; i < batch.size(); ++i) rows[kept_from + i] = std::move(batch[i]);
      // A new file beside it (a name no one else has), synced, then renamed
      // over it: a crash leaves the old or the new spool. If it cannot be
      // written, the old spool stays whole (its written rows come again).
      std::string next = options_.spool + ".XXXXXX";
      const int fd = ::mkstemp(next.data());
      if (fd < 0) return false;
      std::string text = std::string(kSpoolHeader) + '\n';
      for (size_t i = kept_from; i < rows.size(); ++i) text += to_spool_line(rows[i]) + '\n';
      bool ok = true;
      for (size_t off = 0; ok && off < text.size();) {
        const ssize_t w = ::write(fd, text.data() + off, text.size() - off);
        if (w < 0 && errno == EINTR) continue;
        ok = w > 0;
        if (ok) off += static_cast<size_t>(w);
      }
      ok = ok && ::fchmod(fd, 0644) == 0 && ::fsync(fd) == 0;
      ::close(fd);
      if (!ok || std::rename(next.c_str(), options_.spool.c_str()) != 0) ::unlink(next.c_str());
      return false;
    }
    done += n;
  }
  std::remove(options_.spool.c_str());  // rvc's own (it has the header, or this run wrote it)
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
    if (stopping && cut_wait()) {
      // A second stop signal: no more waiting for anything, everything kept
      // goes behind the spool as it is.
      std::vector<Row> all(std::make_move_iterator(pending_.begin()), std::make_move_iterator(pending_.end()));
      pending_.clear();
      all.insert(all.end(), std::make_move_iterator(batch.begin()), std::make_move_iterator(batch.end()));
      batch.clear();
      spill(all);
      break;
    }
    const bool late = stopping && now >= deadline;
    // Past the end's deadline no reconnection is tried (a host that does not
    // answer would hold the end for its connect timeout).
    if (!connected_ && !late && now >= next_attempt) {
      if (db_->reconnect()) {
        connected_ = true;
        backoff = options_.retry_interval;
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
    } else if (spooling_ && pending_.empty()) {
      spill(batch);  // behind what is already spooled
    } else {
      pending_.insert(pending_.end(), std::make_move_iterator(batch.begin()), std::make_move_iterator(batch.end()));
    }
    batch.clear();
    if (pending_.size() > options_.memory_rows && (!spool_failing_ || Clock::now() >= spool_retry_)) {
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
      if (empty && late && !connected_) {
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
  if (!started_ || flushed_) return true;
  // What the spool holds now (rows of earlier runs too), counted from the
  // file itself: the claim below is what is there.
  uint64_t kept = 0;
  {
    std::ifstream in(options_.spool);
    std::string line;
    for (uint64_t number = 1; std::getline(in, line); ++number)
      kept += !line.empty() && !(number == 1 && line == kSpoolHeader);
  }
  const uint64_t lost = pending_.size();
  if (kept == 0 && lost == 0) return true;
  StoreStats s;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.left_in_spool = kept;
    stats_.lost = lost;
    s = stats_;
  }
  const bool stopped = options_.stop_signals && options_.stop_signals() > 0;
  char waited[96];
  if (cut_wait())
    std::snprintf(waited, sizeof waited, "was still being written when a second stop signal cut the wait");
  else if (stopped)
    std::snprintf(waited, sizeof waited, "is away and the run was stopped by a signal (no waiting)");
  else
    std::snprintf(waited, sizeof waited, "did not come back within %.1f s", wait_seconds);
  if (kept)
    std::fprintf(stderr, "rvc: results database %s %s: %llu rows kept in %s (the next run with this spool writes them)\n",
                 description_.c_str(), waited, static_cast<unsigned long long>(kept), options_.spool.c_str());
  if (lost)
    std::fprintf(stderr,
                 "rvc: results database %s %s, and the spool %s cannot be written (%s): %llu rows of results are "
                 "lost\n",
                 description_.c_str(), waited, options_.spool.c_str(), spool_error_.c_str(),
                 static_cast<unsigned long long>(lost));
  if (s.outages > kReportedOutages)
    std::fprintf(stderr, "rvc: results database %s went away %llu times during the run\n", description_.c_str(),
                 static_cast<unsigned long long>(s.outages));
  return false;
}

}  // namespace rvc::store
