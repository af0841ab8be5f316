// A rosbag2 bag folder: metadata.yaml (rosbag2_bagfile_information) and the
// storage files it lists in relative_file_paths (a split bag has several),
// MCAP or sqlite3. Read as one bag: the files' messages merged by log time
// (a k-way merge; equal times keep the files' order), indexes over the bag.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "transport/rosbag2/bag_reader.hpp"

namespace rvc::transport {

struct BagMetadata {
  std::string storage;  // storage_identifier
  std::string compression_format, compression_mode;
  std::vector<std::string> files;    // full paths, in the bag's order
  std::vector<BagTopicInfo> topics;  // topics_with_message_count (names, types, counts)
};

// Whether a folder holds an entry of this name (a symlink loop or a dangling
// link counts: it is reported as what it is, not as missing). Never throws.
bool names_entry(const std::string& path);

// Reads DIR/metadata.yaml; throws BagError naming the file, line and what is
// wrong (a symlink loop, a folder where the file should be, ...).
BagMetadata read_bag_metadata(const std::string& dir);

// Merges several readers (each in log-time order) into one, in log-time order.
class MergedBag : public BagReader {
 public:
  MergedBag(const std::string& path, std::vector<std::unique_ptr<BagReader>> parts);
  bool next(BagMessage& m) override;

 private:
  struct Part {
    std::unique_ptr<BagReader> reader;
    BagMessage head;
    bool has = false, started = false;
  };
  std::vector<Part> parts_;
  size_t last_ = SIZE_MAX;  // the part whose head was returned last: advanced first next time
  uint64_t index_ = 0;
};

}  // namespace rvc::transport
