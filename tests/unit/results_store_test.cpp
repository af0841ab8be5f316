// The results store (src/store): verdict changes and violations with their
// witness windows, and no lost row when the database goes away — checked
// with a database whose outages the test switches on and off, and with a
// real SQLite file.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include "store/database.hpp"
#include "store/results_store.hpp"
#include "store/schema.hpp"

namespace rvc::store {
namespace {

// Keeps rows in memory; while `down`, every write fails as a lost connection.
struct FlakyDb : Database {
  struct Shared {
    std::mutex mutex;
    std::vector<Row> rows;
    std::atomic<bool> down{false};
    std::atomic<int> failed_writes{0};
    std::atomic<int> write_ms{0};  // a slow database: each write takes this long
    std::atomic<int> writes{0};    // writes begun
  };
  explicit FlakyDb(std::shared_ptr<Shared> s) : s(std::move(s)) {}
  void ensure_schema() override {}
  void write(const std::vector<Row>& rows) override {
    ++s->writes;
    if (s->down) {
      ++s->failed_writes;
      throw DbError("server closed the connection", true);
    }
    for (const Row& r : rows)
      if (r.text[0] == "refused") throw DbError("invalid input syntax", false);  // the whole batch rolls back
    if (s->write_ms) std::this_thread::sleep_for(std::chrono::milliseconds(s->write_ms.load()));
    std::lock_guard<std::mutex> lock(s->mutex);
    s->rows.insert(s->rows.end(), rows.begin(), rows.end());
  }
  bool reconnect() override { return !s->down; }
  QueryResult query(const std::string&, const std::vector<std::string>&) override { return {}; }
  std::string describe() const override { return "flaky"; }
  std::shared_ptr<Shared> s;
};

StoreOptions fast_options(const std::string& spool) {
  StoreOptions o;
  o.spool = spool;
  o.flush_interval = 0.01;
  o.retry_interval = 0.01;
  o.wait_seconds = 5;
  o.witness = 2;
  return o;
}

std::vector<std::string> summary(const std::vector<Row>& rows) {
  std::vector<std::string> out;
  for (const Row& r : rows) {
    std::string s = table_name(r.table);
    if (r.table == Table::Verdict) s += " " + r.text[0] + "@" + std::to_string(int(r.number[0])) + "=" + std::to_string(r.integer);
    if (r.table == Table::Violation) s += " " + r.text[0] + "@" + std::to_string(int(r.number[0])) + " " + r.text[1];
    out.push_back(s);
  }
  return out;
}

std::string temp_path(const std::string& name) {
  auto dir = std::filesystem::temp_directory_path() / ("rvc_store_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::filesystem::remove(dir / name);
  return (dir / name).string();
}

TEST(ResultsStore, StoresChangesAndViolationsWithTheirWitness) {
  auto shared = std::make_shared<FlakyDb::Shared>();
  ResultsStore store(std::make_unique<FlakyDb>(shared), fast_options(temp_path("a.spool")));
  store.begin_run({"rvc check", {"in"}, "discrete", {{"p1", "{a}"}}});
  const bool a[] = {true, true, false, false, true, false};
  for (int i = 0; i < 6; ++i) {
    store.on_message("in", a[i] ? "{\"a\":true}" : "{\"a\":false}", i + 1);
    store.on_verdict("p1", i, a[i]);
  }
  ASSERT_TRUE(store.end_run(1, "end of input", "{}"));
  EXPECT_EQ(summary(shared->rows),
            (std::vector<std::string>{
                "run", "property", "verdict p1@0=1", "verdict p1@2=0",
                R"(violation p1@2 [{"input":"in","seq":2,"payload":"{\"a\":true}"},{"input":"in","seq":3,"payload":"{\"a\":false}"}])",
                "verdict p1@4=1", "verdict p1@5=0",
                R"(violation p1@5 [{"input":"in","seq":5,"payload":"{\"a\":true}"},{"input":"in","seq":6,"payload":"{\"a\":false}"}])",
                "run_end"}));
  EXPECT_EQ(store.stats().verdicts, 4u);
  EXPECT_EQ(store.stats().violations, 2u);
}

TEST(ResultsStore, BinaryPayloadsAreKeptAsHex) {
  auto shared = std::make_shared<FlakyDb::Shared>();
  ResultsStore store(std::make_unique<FlakyDb>(shared), fast_options(temp_path("b.spool")));
  store.begin_run({"rvc monitor", {"dds:x"}, "discrete", {{"p1", "{a}"}}});
  store.on_message("dds:x", std::string_view("\x00\x01\xff", 3), 7);
  store.on_verdict("p1", 0, false);
  ASSERT_TRUE(store.end_run(1, "eos", "{}"));
  EXPECT_EQ(shared->rows[3].text[1], R"([{"input":"dds:x","seq":7,"payload_hex":"0001ff"}])");
}

// The database goes away mid-run, long enough for rows to pass through the
// spool file, and comes back: every row arrives once, in order.
TEST(ResultsStore, AnOutageLosesNothing) {
  auto shared = std::make_shared<FlakyDb::Shared>();
  StoreOptions o = fast_options(temp_path("c.spool"));
  o.memory_rows = 50;  // force the spool file
  ResultsStore store(std::make_unique<FlakyDb>(shared), o);
  store.begin_run({"rvc monitor", {"in"}, "discrete", {{"p1", "{a}"}}});
  int step = 0;
  auto feed = [&](int n) {
    for (int i = 0; i < n; ++i, ++step) store.on_verdict("p1", step, step % 2 == 0);
  };
  feed(100);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  shared->down = true;
  feed(500);
  for (int i = 0; i < 100 && shared->failed_writes == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_GT(shared->failed_writes.load(), 0);
  feed(400);
  shared->down = false;
  feed(100);
  ASSERT_TRUE(store.end_run(1, "eos", "{}"));
  EXPECT_GT(store.stats().spooled, 0u);
  EXPECT_EQ(store.stats().reconnects, 1u);
  std::vector<Row> verdicts;
  for (const Row& r : shared->rows)
    if (r.table == Table::Verdict) verdicts.push_back(r);
  ASSERT_EQ(verdicts.size(), 1100u);
  for (int i = 0; i < 1100; ++i) {
    ASSERT_EQ(verdicts[i].number[0], i);
    ASSERT_EQ(verdicts[i].integer, i % 2 == 0);
  }
  EXPECT_FALSE(std::filesystem::exists(o.spool));
}

// The database never comes back: the rows stay in the spool, and the next
// store on that spool writes them before its own.
TEST(ResultsStore, TheSpoolOutlivesTheRun) {
  const std::string spool = temp_path("d.spool");
  auto shared = std::make_shared<FlakyDb::Shared>();
  shared->down = true;
  StoreOptions o = fast_options(spool);
  o.wait_seconds = 0.05;
  {
    ResultsStore store(std::make_unique<FlakyDb>(shared), o);
    store.begin_run({"first", {"in"}, "discrete", {{"p1", "{a}"}}});
    store.on_verdict("p1", 0, false);
    EXPECT_FALSE(store.end_run(1, "eos", "{}"));
    EXPECT_EQ(store.stats().left_in_spool, 5u);  // run, property, verdict, violation, run end
  }
  ASSERT_TRUE(std::filesystem::exists(spool));
  shared->down = false;
  ResultsStore second(std::make_unique<FlakyDb>(shared), o);
  second.begin_run({"second", {"in"}, "discrete", {{"p1", "{a}"}}});
  ASSERT_TRUE(second.end_run(0, "eos", "{}"));
  ASSERT_EQ(shared->rows.size(), 8u);
  EXPECT_EQ(shared->rows[0].text[0], "first");
  EXPECT_EQ(shared->rows[5].text[0], "second");
  EXPECT_FALSE(std::filesystem::exists(spool));
}

// A second stop signal cuts the drain of a long spool into a slow database:
// the end returns at the next batch instead of after all of them, and every
// row is in the database or still in the spool, none in both.
TEST(ResultsStore, ASecondStopSignalCutsTheDrain) {
  const std::string spool = temp_path("g.spool");
  auto shared = std::make_shared<FlakyDb::Shared>();
  shared->down = true;
  StoreOptions o = fast_options(spool);
  o.wait_seconds = 0.05;
  o.memory_rows = 1000;
  constexpr int kVerdicts = 50000;  // five batches of the drain
  {
    ResultsStore first(std::make_unique<FlakyDb>(shared), o);
    first.begin_run({"first", {"in"}, "discrete", {{"p1", "{a}"}}});
    for (int i = 0; i < kVerdicts; ++i) first.on_verdict("p1", i, true), first.on_verdict("p1", i, i % 2 == 0);
    EXPECT_FALSE(first.end_run(0, "eos", "{}"));
  }
  const uint64_t spooled = [&] {
    std::ifstream in(spool);
    std::string line;
    uint64_t n = 0;
    while (std::getline(in, line)) ++n;
    return n - 1;  // the header
  }();
  ASSERT_GT(spooled, 40000u);
  shared->down = false;
  shared->write_ms = 300;
  std::atomic<int> signals{0};
  o.stop_signals = [&] { return signals.load(); };
  ResultsStore second(std::make_unique<FlakyDb>(shared), o);
  const int writes_before = shared->writes;
  second.begin_run({"second", {"in"}, "discrete", {}});  // the drain starts
  for (int i = 0; i < 1000 && shared->writes == writes_before; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_GT(shared->writes, writes_before);  // its first batch is being written
  signals = 2;  // `docker stop`, then again
  EXPECT_FALSE(second.end_run(0, "signal", "{}"));
  const StoreStats s = second.stats();
  // At most the batch being written when the signal came went in; without
  // the cut all eight would have (taking 2.4 s), leaving only this run's rows.
  EXPECT_GE(s.left_in_spool + 10000, spooled + 2);
  // Nothing lost, nothing twice: the database holds the spool's first rows,
  // the spool the rest and this run's three (run, its end).
  EXPECT_EQ(shared->rows.size() + s.left_in_spool, spooled + 2);
  EXPECT_EQ(s.lost, 0u);
}

// A row the database refuses as it is costs only itself: the rest of its
// batch, and everything after it, is written.
TEST(ResultsStore, ARefusedRowCostsOnlyItself) {
  auto shared = std::make_shared<FlakyDb::Shared>();
  ResultsStore store(std::make_unique<FlakyDb>(shared), fast_options(temp_path("f.spool")));
  store.begin_run({"rvc check", {"in"}, "discrete", {{"p1", "{a}"}, {"refused", "{b}"}}});
  store.on_verdict("p1", 0, true);
  store.on_verdict("refused", 0, true);
  store.on_verdict("p1", 1, false);
  ASSERT_TRUE(store.end_run(1, "end of input", "{}"));
  EXPECT_EQ(store.stats().refused, 2u);  // the property row and the verdict row
  std::vector<std::string> got = summary(shared->rows);
  EXPECT_EQ(got, (std::vector<std::string>{"run", "property", "verdict p1@0=1", "verdict p1@1=0",
                                           "violation p1@1 []", "run_end"}));
}

TEST(ResultsStore, PasswordsAreRedacted) {
  EXPECT_EQ(redact_password("postgresql://rv:s3cret@db.local:5432/rvc"), "postgresql://rv:***@db.local:5432/rvc");
  EXPECT_EQ(redact_password("postgresql:///rvc?host=/tmp/x&password=s3cret&user=u"),
            "postgresql:///rvc?host=/tmp/x&password=***&user=u");
  EXPECT_EQ(redact_password("postgresql://rv@db/rvc"), "postgresql://rv@db/rvc");
  EXPECT_EQ(redact_password("--spec"), "--spec");
}

TEST(ResultsStore, SpoolLinesRoundTrip) {
  Row r;
  r.table = Table::Violation;
  r.run = "run-1";
  r.text[0] = "p\"1";
  r.text[1] = "[{\"payload\":\"\\n\"}]";
  r.number[0] = 0.1;
  r.number[1] = 1795458069.90137;
  r.integer = -3;
  Row back;
  std::string error;
  ASSERT_TRUE(from_spool_line(to_spool_line(r), back, error)) << error;
  EXPECT_EQ(back.table, r.table);
  EXPECT_EQ(back.run, r.run);
  EXPECT_EQ(back.text[0], r.text[0]);
  EXPECT_EQ(back.text[1], r.text[1]);
  EXPECT_EQ(back.number[0], r.number[0]);
  EXPECT_EQ(back.number[1], r.number[1]);
  EXPECT_EQ(back.integer, r.integer);
  EXPECT_FALSE(from_spool_line("{\"table\":\"nope\",\"run\":\"r\",\"text\":[\"\",\"\",\"\"],\"number\":[0,0],\"integer\":0}",
                               back, error));
  EXPECT_EQ(error, "unknown table 'nope'");
  EXPECT_FALSE(from_spool_line("{", back, error));
}

TEST(ResultsStore, SqliteFileHoldsTheRun) {
  const std::string path = temp_path("r.db");
  {
    ResultsStore store(open_database("sqlite:" + path), fast_options(temp_path("e.spool")));
    store.begin_run({"rvc check", {"t.jsonl"}, "dense", {{"p1", "{a}"}}});
    store.on_message("t.jsonl", "{\"a\":false}", 1);
    store.on_verdict("p1", 0.5, false);
    ASSERT_TRUE(store.end_run(1, "end of input", "{\"checked\":1}"));
  }
  auto db = open_database("sqlite:" + path);
  auto runs = db->query("SELECT time_model, exit_status, end_reason, counters FROM runs");
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0], (std::vector<std::string>{"dense", "1", "end of input", "{\"checked\":1}"}));
  auto v = db->query("SELECT property, time, value FROM verdicts WHERE run = (SELECT run FROM runs)");
  EXPECT_EQ(v, (QueryResult{{"p1", "0.5", "0"}}));
  auto w = db->query("SELECT witness FROM violations");
  EXPECT_EQ(w, (QueryResult{{R"([{"input":"t.jsonl","seq":1,"payload":"{\"a\":false}"}])"}}));
  EXPECT_THROW(open_database("sqlite:/nonexistent-dir/x.db"), DbError);
  EXPECT_THROW(open_database("mysql://x"), DbError);
}

}  // namespace
}  // namespace rvc::store
