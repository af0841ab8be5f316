// The k-way merge of a split bag's files (transport/rosbag2/bag_folder.hpp)
// and zstd per message (zstd_bag.hpp), on readers made here: hand-computed
// orders, indexes and reasons, no files.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "transport/rosbag2/bag_folder.hpp"
#include "transport/rosbag2/zstd_bag.hpp"

namespace rvc::transport {
namespace {

// A storage file of (log time, payload) messages, one skipped record after
// the message at `skip_after` (0: none).
class ListBag : public BagReader {
 public:
  ListBag(std::string path, std::vector<std::pair<uint64_t, std::string>> msgs, size_t skip_after = 0)
      : BagReader(std::move(path)), msgs_(std::move(msgs)), skip_after_(skip_after) {}
  bool next(BagMessage& m) override {
    if (skip_after_ && i_ == skip_after_ && !skipped_) {
      skipped_ = true;
      skipped("message " + std::to_string(i_ + 1) + ": bad (skipped)");
    }
    if (i_ >= msgs_.size()) return false;
    m.topic = "/t";
    m.log_time = msgs_[i_].first;
    m.data = msgs_[i_].second;
    m.index = ++i_;
    return true;
  }

 private:
  std::vector<std::pair<uint64_t, std::string>> msgs_;
  size_t i_ = 0, skip_after_;
  bool skipped_ = false;
};

std::vector<std::string> read_all(BagReader& bag, std::vector<uint64_t>* indexes = nullptr) {
  std::vector<std::string> out;
  BagMessage m;
  while (bag.next(m)) {
    out.emplace_back(m.data);
    if (indexes) indexes->push_back(m.index);
  }
  return out;
}

TEST(Rosbag2Merge, InterleavedFilesComeInLogTimeOrderWithIndexesOverTheBag) {
  std::vector<std::unique_ptr<BagReader>> parts;
  parts.push_back(std::make_unique<ListBag>("b/bag_0.db3", std::vector<std::pair<uint64_t, std::string>>{
                                                               {10, "a"}, {30, "c"}, {50, "e"}}));
  parts.push_back(std::make_unique<ListBag>("b/bag_1.db3", std::vector<std::pair<uint64_t, std::string>>{
                                                               {20, "b"}, {40, "d"}, {60, "f"}, {70, "g"}}));
  MergedBag bag("b", std::move(parts));
  std::vector<uint64_t> idx;
  EXPECT_EQ(read_all(bag, &idx), (std::vector<std::string>{"a", "b", "c", "d", "e", "f", "g"}));
  EXPECT_EQ(idx, (std::vector<uint64_t>{1, 2, 3, 4, 5, 6, 7}));
  BagMessage m;
  EXPECT_FALSE(bag.next(m));  // and stays at its end
}

TEST(Rosbag2Merge, EqualTimesKeepTheFilesOrder) {
  std::vector<std::unique_ptr<BagReader>> parts;
  parts.push_back(std::make_unique<ListBag>("0", std::vector<std::pair<uint64_t, std::string>>{{5, "x0"}, {5, "y0"}}));
  parts.push_back(std::make_unique<ListBag>("1", std::vector<std::pair<uint64_t, std::string>>{{5, "x1"}}));
  parts.push_back(std::make_unique<ListBag>("2", std::vector<std::pair<uint64_t, std::string>>{}));
  MergedBag bag("b", std::move(parts));
  EXPECT_EQ(read_all(bag), (std::vector<std::string>{"x0", "y0", "x1"}));
}

TEST(Rosbag2Merge, ASkippedRecordNamesItsFile) {
  std::vector<std::unique_ptr<BagReader>> parts;
  parts.push_back(std::make_unique<ListBag>("dir/bag_0.db3",
                                            std::vector<std::pair<uint64_t, std::string>>{{1, "a"}, {3, "c"}}, 1));
  parts.push_back(std::make_unique<ListBag>("dir/bag_1.db3", std::vector<std::pair<uint64_t, std::string>>{{2, "b"}}));
  MergedBag bag("dir", std::move(parts));
  std::vector<std::string> reasons;
  bag.on_skip([&](const std::string& r) { reasons.push_back(r); });
  EXPECT_EQ(read_all(bag), (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(reasons, (std::vector<std::string>{"bag_0.db3: message 2: bad (skipped)"}));
}

TEST(Rosbag2Zstd, FramesAreToldFromCdrAndCutFramesAreRefused) {
  // `printf hello | zstd --no-check`: magic, frame header (window descriptor),
  // one raw block of 5 bytes, the last.
  const std::string frame("\x28\xb5\x2f\xfd\x00\x58\x29\x00\x00hello", 14);
  EXPECT_TRUE(is_zstd_frame(frame));
  EXPECT_FALSE(is_zstd_frame(std::string("\x00\x01\x00\x00", 4)));  // a CDR encapsulation header
  std::string out, error;
  ASSERT_TRUE(zstd_decompress(frame, out, error, 1 << 20)) << error;
  EXPECT_EQ(out, "hello");
  EXPECT_FALSE(zstd_decompress(frame.substr(0, 11), out, error, 1 << 20));
  EXPECT_NE(error.find("cut short"), std::string::npos) << error;
}

TEST(Rosbag2Zstd, OutputStopsAtTheCap) {
  // The same "hello" frame: a cap of 4 bytes refuses it, streamed (no size
  // declared: stopped at the cap), naming --max-message-size; 5 reads it.
  const std::string frame("\x28\xb5\x2f\xfd\x00\x58\x29\x00\x00hello", 14);
  std::string out, error;
  bool too_large = false;
  EXPECT_FALSE(zstd_decompress(frame, out, error, 4, &too_large));
  EXPECT_TRUE(too_large);
  EXPECT_TRUE(out.empty());
  EXPECT_NE(error.find("more than the limit of 4 bytes"), std::string::npos) << error;
  EXPECT_NE(error.find("--max-message-size"), std::string::npos) << error;
  ASSERT_TRUE(zstd_decompress(frame, out, error, 5, &too_large)) << error;
  EXPECT_EQ(out, "hello");
  EXPECT_FALSE(too_large);
  // A frame whose header declares 1048740 bytes and whose one (last, raw)
  // block holds none: damaged. zstd's streaming decoder let it through, its
  // one-shot decoder does not (found by fuzz_zstd).
  const std::string lying("\x28\xb5\x2f\xfd\x80\x68\xa4\x00\x10\x00\x01\x00\x00", 13);
  EXPECT_FALSE(zstd_decompress(lying, out, error, 2 << 20));
  EXPECT_NE(error.find("declares 1048740 bytes decompressed, its blocks hold 0"), std::string::npos) << error;
}

}  // namespace
}  // namespace rvc::transport
