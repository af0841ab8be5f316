// file: endpoints: the source reads lines into frames and can be stopped
// while it waits for input that never comes; the sink reports write errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "transport/file_endpoint.hpp"

namespace rvc::transport {
namespace {

struct Collected {
  std::mutex m;
  std::vector<std::pair<uint64_t, std::string>> frames;  // seq, payload ("<eos>" for the marker)
  void add(const Frame& f) {
    std::lock_guard<std::mutex> lock(m);
    frames.emplace_back(f.seq, f.eos ? std::string("<eos>") : std::string(f.payload));
  }
};

// Runs a FileSource on the read end of a pipe; `fd_swap` makes it read /dev/fd/N.
class PipeSource {
 public:
  PipeSource() {
    EXPECT_EQ(::pipe(fds_), 0);
    source_ = std::make_unique<FileSource>("/dev/fd/" + std::to_string(fds_[0]));
  }
  ~PipeSource() {
    source_.reset();
    ::close(fds_[0]);
    if (fds_[1] >= 0) ::close(fds_[1]);
  }
  void write(const std::string& s) { ASSERT_EQ(::write(fds_[1], s.data(), s.size()), static_cast<ssize_t>(s.size())); }
  void close_writer() {
    ::close(fds_[1]);
    fds_[1] = -1;
  }
  FileSource& source() { return *source_; }

 private:
  int fds_[2] = {-1, -1};
  std::unique_ptr<FileSource> source_;
};

TEST(FileSource, StopReturnsWhileNoInputComes) {
  PipeSource p;
  Collected c;
  p.source().start([&](const Frame& f) { c.add(f); });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  auto t0 = std::chrono::steady_clock::now();
  p.source().stop();  // the writer is still open and silent: the old reader blocked here forever
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
  EXPECT_TRUE(c.frames.empty());  // stopped: no end-of-stream marker
}

TEST(FileSource, LinesBlankLinesLongLinesAndTheEnd) {
  PipeSource p;
  Collected c;
  const std::string long_line = "{\"pad\":\"" + std::string(100000, 'x') + "\"}";
  p.source().start([&](const Frame& f) { c.add(f); });
  p.write("\xEF\xBB\xBF{\"a\":1}\r\n\n");
  p.write(long_line.substr(0, 70000));
  p.write(long_line.substr(70000) + "\n{\"a\":2}");  // the last line has no newline
  p.close_writer();
  for (int i = 0; i < 500; ++i) {
    {
      std::lock_guard<std::mutex> lock(c.m);
      if (!c.frames.empty() && c.frames.back().second == "<eos>") break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  p.source().stop();
  using F = std::pair<uint64_t, std::string>;
  // Line 1 without its CR (the byte-order mark is the runtime's to handle); line 2 blank: no frame;
  // EOS carries the last line number.
  EXPECT_EQ(c.frames, (std::vector<F>{{1, "\xEF\xBB\xBF{\"a\":1}"}, {3, long_line}, {4, "{\"a\":2}"}, {4, "<eos>"}}));
}

// pull(): the same frames, one per call on the caller's thread (how several
// files are read in stamp order); a quiet pipe says Wait, not End.
TEST(FileSource, PullGivesTheSameFramesOnTheCallersThread) {
  PipeSource p;
  const std::string long_line = "{\"pad\":\"" + std::string(100000, 'x') + "\"}";
  using F = std::pair<uint64_t, std::string>;
  std::vector<F> frames;
  Frame f;
  ASSERT_TRUE(p.source().pullable());
  EXPECT_EQ(p.source().pull(f), PullResult::Wait);  // nothing written yet
  // Written by another thread: the pipe holds less than the long line.
  std::thread writer([&] {
    p.write("{\"a\":1}\r\n\n");
    p.write(long_line.substr(0, 70000));
    p.write(long_line.substr(70000) + "\n{\"a\":2}");
    p.close_writer();
  });
  for (int i = 0; i < 1000; ++i) {
    const PullResult r = p.source().pull(f);
    if (r == PullResult::End) break;
    if (r == PullResult::Frame) frames.emplace_back(f.seq, f.eos ? std::string("<eos>") : std::string(f.payload));
  }
  writer.join();
  EXPECT_EQ(frames, (std::vector<F>{{1, "{\"a\":1}"}, {3, long_line}, {4, "{\"a\":2}"}, {4, "<eos>"}}));
  EXPECT_EQ(p.source().pull(f), PullResult::End);
}

TEST(FileSink, WriteErrorsAreReported) {
  FileSink sink("/dev/full");
  // stdio buffers the first lines; the error shows at the latest on flush.
  EXPECT_THROW(
      {
        for (int i = 0; i < 100000; ++i) sink.put("{\"time\":0,\"property\":\"p\",\"value\":true}", i);
        sink.flush();
      },
      std::runtime_error);
}

}  // namespace
}  // namespace rvc::transport
