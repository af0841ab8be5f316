#include "transport/rosbag2/bag_reader.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "transport/rosbag2/bag_folder.hpp"
#include "transport/rosbag2/sqlite_bag.hpp"
#include "transport/rosbag2/zstd_bag.hpp"
#ifdef RVC_HAVE_MCAP
#include "transport/mcap/mcap_bag.hpp"
#endif

namespace rvc::transport {

namespace {

constexpr char kMcapMagic[] = "\x89MCAP0\r\n";
constexpr char kSqliteMagic[] = "SQLite format 3";  // and a NUL: the file's first 16 bytes

// The first bytes of a regular file; "" for anything else: a pipe or a
// device (/dev/stdin) is never read here, its bytes belong to the run.
std::string head_of(const std::string& path, size_t n) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return "";
  std::ifstream in(path, std::ios::binary);
  std::string head(n, '\0');
  in.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<size_t>(std::max<std::streamsize>(0, in.gcount())));
  return head;
}

bool starts(const std::string& head, const char* magic, size_t n) {
  return head.size() >= n && std::memcmp(head.data(), magic, n) == 0;
}

bool is_dir(const std::string& path) {
  struct stat st{};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

BagKind file_kind(const std::string& head) {
  if (starts(head, kMcapMagic, 8)) return BagKind::Mcap;
  if (starts(head, kSqliteMagic, 16)) return BagKind::Sqlite;
  return BagKind::None;
}

void merge_topic(std::map<std::string, BagTopicInfo>& into, const BagTopicInfo& t) {
  BagTopicInfo& m = into[t.name];
  if (m.name.empty()) {
    m = t;
    return;
  }
  if (t.messages) {
    m.first_time = m.messages ? std::min(m.first_time, t.first_time) : t.first_time;
    m.last_time = m.messages ? std::max(m.last_time, t.last_time) : t.last_time;
    m.messages += t.messages;
  }
  if (m.type.empty()) m.type = t.type;
  if (m.encoding.empty()) m.encoding = t.encoding;
  if (m.definition.empty() && !t.definition.empty()) {
    m.definition = t.definition;
    m.definition_encoding = t.definition_encoding;
  }
}

// Undoes rosbag2's per-message compression (compression_mode: message):
// a message whose data is a zstd frame is given decompressed.
class DecompressingBag : public BagReader {
 public:
  DecompressingBag(std::unique_ptr<BagReader> inner, const BagReadOptions& options)
      : BagReader(inner->path()), inner_(std::move(inner)), options_(options) {}
  bool next(BagMessage& m) override {
    inner_->on_skip(on_skip_);
    while (inner_->next(m)) {
      if (!is_zstd_frame(m.data) || !wanted(m.topic)) return true;
      std::string error;
      if (zstd_decompress(m.data, buffer_, error, options_.max_message_size)) {
        m.data = buffer_;
        return true;
      }
      skipped("message " + std::to_string(m.index) + " on " + std::string(m.topic) + ": " + error + " (skipped)");
    }
    return false;
  }

 private:
  bool wanted(std::string_view topic) const {
    return options_.topics.empty() ||
           std::find(options_.topics.begin(), options_.topics.end(), topic) != options_.topics.end();
  }
  std::unique_ptr<BagReader> inner_;
  BagReadOptions options_;
  std::string buffer_;
};

#ifdef RVC_HAVE_MCAP
class McapBagReader : public BagReader {
 public:
  explicit McapBagReader(const std::string& path) : BagReader(path), bag_(path) {}
  bool next(BagMessage& m) override {
    bag_.on_skip(on_skip_);
    McapMessage raw;
    try {
      if (!bag_.next(raw)) return false;
    } catch (const McapError& e) {
      throw BagError(e.what());
    }
    m.topic = raw.topic;
    m.data = raw.data;
    m.log_time = raw.log_time;
    m.index = raw.index;
    return true;
  }

 private:
  McapBag bag_;
};

// One MCAP file's topics: one pass over its messages (counts, times and
// schemas live in its messages' channels, per-message zstd undone first).
void summarize_mcap(const std::string& file, const std::string& shown, BagSummary& s,
                    std::map<std::string, BagTopicInfo>& topics) {
  BagContents contents;
  try {
    contents = bag_topics(file, shown);
  } catch (const McapError& e) {
    throw BagError(e.what());
  }
  if (s.first_skipped.empty()) s.first_skipped = contents.first_skipped;
  if (s.broken.empty()) s.broken = contents.broken;
  for (const auto& [name, c] : contents.topics) {
    BagTopicInfo t;
    t.name = name;
    t.type = c.schema_name;
    t.encoding = c.message_encoding;
    t.definition_encoding = c.schema_encoding;
    t.definition = c.schema;
    t.messages = c.messages;
    t.first_time = c.first_time;
    t.last_time = c.last_time;
    merge_topic(topics, t);
  }
}
#endif

// A storage file compressed whole: read from a decompressed copy that lives
// as long as the reader.
class CopiedBag : public BagReader {
 public:
  CopiedBag(const std::string& path, std::unique_ptr<ZstdFileCopy> copy, std::unique_ptr<BagReader> inner)
      : BagReader(path), copy_(std::move(copy)), inner_(std::move(inner)) {}
  bool next(BagMessage& m) override {
    inner_->on_skip(on_skip_);
    return inner_->next(m);
  }

 private:
  std::unique_ptr<ZstdFileCopy> copy_;
  std::unique_ptr<BagReader> inner_;
};

std::unique_ptr<BagReader> open_storage_file(const std::string& path, const std::string& shown) {
  const std::string head = head_of(path, 16);
  switch (file_kind(head)) {
    case BagKind::Sqlite: return std::make_unique<SqliteBag>(path);
    case BagKind::Mcap:
#ifdef RVC_HAVE_MCAP
      try {
        return std::make_unique<McapBagReader>(path);
      } catch (const McapError& e) {
        throw BagError(e.what());
      }
#else
      throw BagError("bag '" + shown + "' is MCAP, and this rvc was built without MCAP (RVC_WITH_ZENOH=OFF)");
#endif
    default: break;
  }
  if (const std::string cut = truncated_bag(shown); !cut.empty()) throw BagError("bag '" + shown + "' is " + cut);
  const std::string what = binary_signature(shown);
  throw BagError("'" + shown + "' is not a ROS 2 bag (MCAP, rosbag2 sqlite3 or a bag folder)" +
                 (what.empty() ? std::string() : ": it is " + what));
}

// One storage file, decompressed first if rosbag2 compressed it whole.
std::unique_ptr<BagReader> open_file(const std::string& path, const BagReadOptions& options) {
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw BagError("bag '" + path + "': cannot open it (" + std::strerror(errno) + ")");
  if (is_zstd_frame(head_of(path, 4))) {
    auto copy = std::make_unique<ZstdFileCopy>(path);
    auto inner = open_storage_file(copy->path(), path);
    return std::make_unique<CopiedBag>(path, std::move(copy), std::move(inner));
  }
  return std::make_unique<DecompressingBag>(open_storage_file(path, path), options);
}


// One storage file's topics: sqlite3 from its tables, MCAP from one pass.
void summarize_file(const std::string& path, BagSummary& s, std::map<std::string, BagTopicInfo>& topics) {
  std::unique_ptr<ZstdFileCopy> copy;
  std::string file = path;
  if (is_zstd_frame(head_of(path, 4))) {
    copy = std::make_unique<ZstdFileCopy>(path);
    file = copy->path();
  }
  if (copy && s.compression_format.empty()) {  // a compressed file given alone: no metadata.yaml says so
    s.compression_format = "zstd";
    s.compression_mode = "file";
  }
  switch (file_kind(head_of(file, 16))) {
    case BagKind::Sqlite: {
      BagSummary one;
      SqliteBag(file).summarize(one);
      if (s.storage.empty()) s.storage = "sqlite3";
      if (s.broken.empty() && !one.broken.empty()) s.broken = one.broken;
      if (s.first_skipped.empty() && !one.first_skipped.empty()) s.first_skipped = one.first_skipped;
      for (const auto& t : one.topics) merge_topic(topics, t);
      return;
    }
#ifdef RVC_HAVE_MCAP
    case BagKind::Mcap:
      if (s.storage.empty()) s.storage = "mcap";
      summarize_mcap(file, path, s, topics);
      return;
#endif
    default: open_storage_file(file, path);  // throws, naming what the file is
  }
}

}  // namespace

const BagTopicInfo* BagSummary::topic(std::string_view name) const {
  for (const auto& t : topics)
    if (t.name == name) return &t;
  return nullptr;
}

BagKind bag_kind(const std::string& path) {
  if (is_dir(path))
    return names_entry((std::filesystem::path(path) / "metadata.yaml").string()) ? BagKind::Folder : BagKind::None;
  const std::string head = head_of(path, 16);
  if (is_zstd_frame(head)) {  // rosbag2's per-file compression: name says what is inside
    const std::string name = std::filesystem::path(path).filename().string();
    auto ends = [&](const char* suffix) {
      const size_t n = std::strlen(suffix);
      return name.size() > n && name.compare(name.size() - n, n, suffix) == 0;
    };
    if (ends(".db3.zstd")) return BagKind::Sqlite;
    if (ends(".mcap.zstd")) return BagKind::Mcap;
    return BagKind::None;
  }
  return file_kind(head);
}

std::string truncated_bag(const std::string& path) {
  const std::string name = std::filesystem::path(path).filename().string();
  auto ends = [&](const char* suffix) {
    const size_t n = std::strlen(suffix);
    return name.size() > n && name.compare(name.size() - n, n, suffix) == 0;
  };
  const bool zstd = ends(".zstd");
  const char* magic = nullptr;
  size_t magic_len = 0;
  std::string kind;
  if (ends(".mcap") || ends(".mcap.zstd")) magic = kMcapMagic, magic_len = 8, kind = "an MCAP file";
  else if (ends(".db3") || ends(".db3.zstd")) magic = kSqliteMagic, magic_len = 16, kind = "a rosbag2 sqlite3 file";
  else return "";
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return "";
  if (st.st_size == 0) return "an empty file (0 bytes), not " + kind + (zstd ? " compressed with zstd" : "") +
                              ": a recording cut short before its first byte?";
  if (zstd) return "";  // what a frame holds is told when it is decompressed
  const std::string head = head_of(path, magic_len);
  if (head.size() < magic_len && std::memcmp(head.data(), magic, head.size()) == 0)
    return "a truncated " + kind.substr(kind.find(' ') + 1) + ": " + std::to_string(head.size()) +
           " bytes, its " + std::to_string(magic_len) + "-byte magic cut short (a recording cut short?)";
  return "";
}

std::string binary_signature(const std::string& path) {
  const std::string h = head_of(path, 512);
  if (h.empty()) return "";
  if (starts(h, kMcapMagic, 8)) return "an MCAP file";
  if (starts(h, kSqliteMagic, 16)) return "a SQLite database";
  if (is_zstd_frame(h)) return "zstd-compressed data";
  if (starts(h, "#ROSBAG V2.0", 12)) return "a ROS 1 bag (rosbag v2.0), which rvc does not read";
  if (starts(h, "\x1f\x8b", 2)) return "a gzip file";
  if (starts(h, "BZh", 3)) return "a bzip2 file";
  if (starts(h, "\xfd" "7zXZ", 6)) return "an xz file";
  if (starts(h, "PK\x03\x04", 4)) return "a zip file";
  if (starts(h, "\x7f" "ELF", 4)) return "an ELF executable";
  if (starts(h, "\x89PNG", 4)) return "a PNG image";
  if (starts(h, "%PDF", 4)) return "a PDF document";
  if (starts(h, "\x04\x22\x4d\x18", 4)) return "an lz4 frame";
  if (std::memchr(h.data(), '\0', h.size())) return "binary data (NUL bytes in its first 512)";
  return "";
}

std::unique_ptr<BagReader> open_bag(const std::string& path, const BagReadOptions& options) {
  if (!is_dir(path)) return open_file(path, options);
  if (!names_entry((std::filesystem::path(path) / "metadata.yaml").string()))
    throw BagError("'" + path + "' is a folder without metadata.yaml: not a rosbag2 bag folder (give a .mcap or .db3 "
                   "file of it instead)");
  const BagMetadata md = read_bag_metadata(path);
  std::vector<std::unique_ptr<BagReader>> parts;
  for (const auto& f : md.files) parts.push_back(open_file(f, options));
  if (parts.size() == 1) return std::move(parts[0]);
  return std::make_unique<MergedBag>(path, std::move(parts));
}

BagSummary summarize_bag(const std::string& path) {
  BagSummary s;
  s.path = path;
  std::map<std::string, BagTopicInfo> topics;
  if (is_dir(path)) {
    if (!names_entry((std::filesystem::path(path) / "metadata.yaml").string())) open_bag(path);  // throws
    const BagMetadata md = read_bag_metadata(path);
    s.compression_format = md.compression_format;
    s.compression_mode = md.compression_mode;
    s.files = md.files;
    s.storage = md.storage;
    for (const auto& t : md.topics) {  // topics with no message yet are listed too
      BagTopicInfo empty = t;
      empty.messages = 0;
      merge_topic(topics, empty);
    }
  } else {
    s.files = {path};
  }
  for (const auto& f : s.files) summarize_file(f, s, topics);
  for (auto& [name, t] : topics) {
    if (t.messages) {
      s.start = s.messages ? std::min(s.start, t.first_time) : t.first_time;
      s.end = s.messages ? std::max(s.end, t.last_time) : t.last_time;
    }
    s.messages += t.messages;
    s.topics.push_back(std::move(t));
  }
  return s;
}

}  // namespace rvc::transport
