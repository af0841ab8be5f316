// libFuzzer harness: a rosbag2 bag folder's metadata.yaml from bytes, beside
// one valid sqlite3 storage file (bag_0.db3, written at start), read as
// `rvc check DIR`, `rvc echo DIR` and `rvc bag info DIR` read it
// (transport/rosbag2/bag_folder.cpp: yaml-cpp, the files it lists, the merge
// of several files by log time).
//
// Findings: any crash or sanitizer report, an exception other than BagError
// (yaml-cpp's own exceptions, std::filesystem's, ... would end the CLI with
// "rvc: error: ..."), an allocation over the limits (tests/fuzz/resource_limits.hpp),
// a read that never ends. Oracles: the folder reads the same twice; message
// indexes only grow and log times never go back (the merge); a folder that
// reads without error lists the storage files it read.
#include <sqlite3.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "resource_limits.hpp"
#include "transport/rosbag2/bag_folder.hpp"
#include "transport/rosbag2/bag_reader.hpp"

namespace {

std::string dir;

// bag_0.db3: rosbag2's tables, one topic of std_msgs/msg/Float64, 20 messages.
void write_storage(const std::string& path) {
  sqlite3* db = nullptr;
  if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) __builtin_trap();
  const char* schema =
      "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
      "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
      "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, "
      "data BLOB NOT NULL);"
      "INSERT INTO topics VALUES (1, '/speed', 'std_msgs/msg/Float64', 'cdr', '');";
  if (sqlite3_exec(db, schema, nullptr, nullptr, nullptr) != SQLITE_OK) __builtin_trap();
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES (1, ?, ?)", -1, &st, nullptr);
  for (int i = 0; i < 20; ++i) {
    unsigned char sample[12] = {0, 1, 0, 0};  // CDR little-endian header, then a float64
    const double v = i;
    std::memcpy(sample + 4, &v, 8);
    sqlite3_bind_int64(st, 1, 1000 + i);
    sqlite3_bind_blob(st, 2, sample, sizeof sample, SQLITE_TRANSIENT);
    if (sqlite3_step(st) != SQLITE_DONE) __builtin_trap();
    sqlite3_reset(st);
  }
  sqlite3_finalize(st);
  sqlite3_close(db);
}

std::vector<std::string> read_all() {
  std::vector<std::string> events;
  try {
    auto bag = rvc::transport::open_bag(dir);
    bag->on_skip([&](const std::string& reason) { events.push_back("s " + reason); });
    rvc::transport::BagMessage m;
    uint64_t last_index = 0, last_time = 0;
    for (;;) {
      try {
        if (!bag->next(m)) break;
      } catch (const rvc::transport::BagError& e) {
        events.push_back(std::string("end ") + e.what());
        return events;
      }
      if (m.index <= last_index || m.log_time < last_time) __builtin_trap();  // merged in log-time order
      last_index = m.index;
      last_time = m.log_time;
      events.push_back("m " + std::string(m.topic) + " " + std::to_string(m.index) + " " + std::to_string(m.log_time));
    }
    events.push_back("end");
  } catch (const rvc::transport::BagError& e) {
    events.push_back(std::string("open ") + e.what());
  }
  return events;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rvc::fuzz::add_resource_limits(argc, argv);
  char tmpl[] = "/tmp/rvc-fuzz-folder-XXXXXX";
  if (!mkdtemp(tmpl)) __builtin_trap();
  dir = tmpl;
  write_storage(dir + "/bag_0.db3");
  // Files a metadata.yaml may list that are no bag: a folder, a symlink loop, a dangling link, itself.
  std::system(("mkdir -p " + dir + "/sub && ln -sf loop_b " + dir + "/loop_a && ln -sf loop_a " + dir +
               "/loop_b && ln -sf gone.db3 " + dir + "/dangling.db3 && cp " + dir + "/bag_0.db3 " + dir +
               "/bag_1.db3").c_str());
  // Relative names resolve inside the folder: the harness runs there.
  if (chdir(dir.c_str()) != 0) __builtin_trap();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FILE* f = std::fopen((dir + "/metadata.yaml").c_str(), "wb");
  if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) __builtin_trap();
  const std::vector<std::string> first = read_all(), second = read_all();
  if (first != second) __builtin_trap();  // reading is deterministic
  try {
    const rvc::transport::BagMetadata md = rvc::transport::read_bag_metadata(dir);
    if (md.files.empty()) __builtin_trap();  // "lists no storage file" is refused, never an empty bag
    const rvc::transport::BagSummary s = rvc::transport::summarize_bag(dir);
    if (s.files.size() != md.files.size()) __builtin_trap();
  } catch (const rvc::transport::BagError&) {
  }
  return 0;
}
