// libFuzzer harness: a rosbag2 sqlite3 bag (.db3) from bytes, read as
// `rvc check bag.db3` and `rvc bag info` read it (transport/rosbag2:
// SqliteBag, SqliteRows' read around damaged pages, per-message zstd).
//
// Findings: any crash or sanitizer report, an exception other than BagError
// (the CLI would end with "rvc: error: ..."), an allocation over the limits
// (tests/fuzz/fuzz_db3.flags: an allocation sized by what the file declares
// rather than by the bytes it holds), a read that never ends (-timeout).
// Oracles: message indexes only grow; on a database whose integrity check
// passes, the bag reads the same twice (messages, skipped records, end) and
// a summary counts at least the messages the read pass returns per topic
// (it counts rows with a valid timestamp and topic, the read pass also
// skips rows whose data is no blob). On a damaged one SQLite may return
// garbage rows that differ between two opens.
//
// SQLite itself is the system's library, not instrumented: mutations are
// guided by rvc's side (the schema checks, the row checks, the scan).
#include <sqlite3.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "resource_limits.hpp"
#include "transport/rosbag2/bag_reader.hpp"

namespace {

// PRAGMA integrity_check: "ok" on a sound database.
bool sound(const std::string& path) {
  sqlite3* db = nullptr;
  bool ok = false;
  if (sqlite3_open_v2(("file:" + path + "?immutable=1").c_str(), &db, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI,
                      nullptr) == SQLITE_OK) {
    sqlite3_stmt* st = nullptr;
    if (sqlite3_prepare_v2(db, "PRAGMA integrity_check", -1, &st, nullptr) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW) {
      const unsigned char* t = sqlite3_column_text(st, 0);
      ok = t && std::string(reinterpret_cast<const char*>(t)) == "ok" && sqlite3_step(st) == SQLITE_DONE;
    }
    sqlite3_finalize(st);
  }
  sqlite3_close(db);
  return ok;
}

struct Pass {
  std::vector<std::string> events;
  std::map<std::string, uint64_t> per_topic;
};

Pass read_all(const std::string& path) {
  Pass p;
  rvc::transport::BagReadOptions options;
  options.max_message_size = 1 << 20;  // per-message zstd: decompressed at most this far
  try {
    auto bag = rvc::transport::open_bag(path, options);
    bag->on_skip([&](const std::string& reason) { p.events.push_back("s " + reason); });
    rvc::transport::BagMessage m;
    uint64_t last = 0;
    for (;;) {
      try {
        if (!bag->next(m)) break;
      } catch (const rvc::transport::BagError& e) {
        p.events.push_back(std::string("end ") + e.what());
        return p;
      }
      if (m.index <= last) __builtin_trap();  // positions only grow
      last = m.index;
      p.events.push_back("m " + std::string(m.topic) + " " + std::to_string(m.index) + " " +
                         std::to_string(m.log_time) + " " + std::to_string(m.data.size()));
      ++p.per_topic[std::string(m.topic)];
    }
    p.events.push_back("end");
  } catch (const rvc::transport::BagError& e) {
    p.events.push_back(std::string("open ") + e.what());
  }
  return p;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rvc::fuzz::add_resource_limits(argc, argv);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // A zstd frame is a file compressed whole, decompressed to a temporary file
  // (fuzz_zstd covers the decoder): not this harness's reader.
  if (size >= 4 && data[0] == 0x28 && data[1] == 0xB5 && data[2] == 0x2F && data[3] == 0xFD) return 0;
  // A real file, named .db3 (SQLite opens it by path, read-only, immutable).
  static const std::string path = [] {
    char dir[] = "/tmp/rvc-fuzz-db3-XXXXXX";
    if (!mkdtemp(dir)) __builtin_trap();
    return std::string(dir) + "/bag.db3";
  }();
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) __builtin_trap();
  const Pass first = read_all(path);
  const Pass second = read_all(path);
  // On a database SQLite finds sound, reading is deterministic and the
  // summary counts what the read pass returns. On a damaged one SQLite may
  // return garbage rows that differ between two opens (other row ids, other
  // words): there only rvc's own rules hold (no crash, no other exception,
  // limits, positions that grow, an end).
  const bool checked = sound(path);
  if (checked && first.events != second.events) __builtin_trap();
  try {
    const rvc::transport::BagSummary s = rvc::transport::summarize_bag(path);  // `rvc bag info`, damaged or not
    bool clean = !first.events.empty() && first.events.back() == "end";
    for (const auto& e : first.events) clean = clean && e.rfind("s ", 0) != 0;
    if (checked && clean && s.broken.empty() && s.first_skipped.empty())
      for (const auto& [topic, n] : first.per_topic) {
        const rvc::transport::BagTopicInfo* t = s.topic(topic);
        if (!t || t->messages < n) __builtin_trap();
      }
  } catch (const rvc::transport::BagError&) {  // refused: the read passes were refused too
    if (checked && (first.events.empty() || first.events.back().rfind("open ", 0) != 0)) __builtin_trap();
  }
  return 0;
}
