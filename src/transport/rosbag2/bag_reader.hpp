// One interface over every ROS 2 bag rvc reads, so `rvc check`, `rvc monitor
// --input`, `rvc echo` and `rvc bag info` share one path whatever the storage:
//   - an MCAP file (rosbag2's default since Iron), read by rust/rvc-zenoh;
//   - a rosbag2 sqlite3 file (.db3, the default up to Humble), read with SQLite
//     opened read-only and immutable (rvc never modifies a file it did not create);
//   - a bag folder (metadata.yaml + one or more of those files, as `ros2 bag
//     record` writes it, split or not): its files merged in log-time order, and
//     zstd compression per file or per message undone as metadata.yaml says.
// A bag's messages come in log-time order (MCAP: file order, which rosbag2
// writes in log-time order), each with its 1-based index over all topics.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rvc::transport {

// A bag that cannot be opened or read on: names the file and what is wrong.
// A usage error for the CLI (exit 2) when it happens before anything ran.
class BagError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct BagMessage {
  std::string_view topic, data;  // valid until the next call to next()
  uint64_t log_time = 0;         // ns
  uint64_t index = 0;            // 1-based over all topics of the bag
};

// A topic as the bag records it.
struct BagTopicInfo {
  std::string name;
  std::string type;                 // "pkg/msg/Name"; "" when the bag does not say
  std::string encoding;             // serialization format: "cdr" for ROS 2, "json", ...
  std::string definition_encoding;  // "ros2msg", "ros2idl", or "" (the bag carries no definition)
  std::string definition;           // the type's definition as the bag carries it (may be empty)
  uint64_t messages = 0;
  uint64_t first_time = 0, last_time = 0;  // log times (ns) of its first and last message
};

class BagReader {
 public:
  virtual ~BagReader() = default;
  // False at the end; throws BagError when reading cannot go on (a file cut
  // short, a database page that is corrupt). A record that is bad on its own
  // is skipped: on_skip gets the reason and reading goes on.
  virtual bool next(BagMessage& m) = 0;
  void on_skip(std::function<void(const std::string&)> f) { on_skip_ = std::move(f); }
  const std::string& path() const { return path_; }

 protected:
  explicit BagReader(std::string path) : path_(std::move(path)) {}
  void skipped(const std::string& reason) const {
    if (on_skip_) on_skip_(reason);
  }
  std::string path_;
  std::function<void(const std::string&)> on_skip_;
};

// What `rvc bag info` shows, and what the runtime needs to pick a topic.
struct BagSummary {
  std::string path;
  std::string storage;             // "mcap" or "sqlite3"
  std::string compression_format;  // "" or "zstd"
  std::string compression_mode;    // "", "file" or "message"
  std::vector<std::string> files;  // the storage files, in the bag's order
  std::vector<BagTopicInfo> topics;  // sorted by name; topics with no message included
  uint64_t messages = 0;
  uint64_t start = 0, end = 0;  // earliest and latest log time (ns); 0 when empty
  std::string broken;           // why reading stopped early, if it did
  std::string first_skipped;    // why the first record skipped was, if any

  const BagTopicInfo* topic(std::string_view name) const;
};

// The kind of a path, from its first bytes (never from its name): an MCAP or
// a SQLite file, a bag folder (one holding metadata.yaml), or a zstd frame.
enum class BagKind { None, Mcap, Sqlite, Folder };
BagKind bag_kind(const std::string& path);
inline bool is_bag(const std::string& path) { return bag_kind(path) != BagKind::None; }

// What a file that is not text is ("a SQLite database", "a gzip file", ...),
// from its first bytes; "" when it may be text (JSON lines). For a clear
// refusal where JSON lines are expected, instead of an error per line.
std::string binary_signature(const std::string& path);

// What a run reads of a bag.
struct BagReadOptions {
  // Per-message compression: a message is decompressed (streamed) only up
  // to this many bytes; a larger one is skipped, named with its index, so
  // a zstd bomb costs no more memory than this.
  size_t max_message_size = size_t{256} << 20;
  // The topics the run reads (empty: all). Compressed messages of other
  // topics are handed on as they are stored, never decompressed.
  std::vector<std::string> topics;
};

// For a regular file whose name says it is a bag (.mcap, .db3, with or
// without .zstd) but whose bytes are not one because they stop short of the
// storage's magic (an empty file, a recording cut short at its start): what
// it is, e.g. "an empty file (0 bytes), not an MCAP file: a recording cut
// short?". "" otherwise.
std::string truncated_bag(const std::string& path);

// Opens a bag (throws BagError for what is no bag, naming what it is).
std::unique_ptr<BagReader> open_bag(const std::string& path, const BagReadOptions& options = {});

// The bag's topics, types, counts and time span. MCAP: from one pass over
// its messages; sqlite3: from the database's tables (no pass over the
// messages); a folder: both, over its files.
BagSummary summarize_bag(const std::string& path);

}  // namespace rvc::transport
