// file:PATH endpoints: JSON lines. As a source, each non-blank line is one
// frame (seq = line number) followed by an end-of-stream frame at the end of
// the file, delivered by a thread of its own (start) or one by one to the
// caller (pull); as a sink, each payload is written as one line.
#pragma once

#include <atomic>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "transport/endpoint.hpp"

namespace rvc::transport {

class FileSource final : public Source {
 public:
  explicit FileSource(std::string path);  // "-" is stdin; throws if unreadable
  ~FileSource() override;
  void start(FrameHandler handler) override;
  // Returns promptly even while the reader waits for input that never comes
  // (stdin, a pipe): the reader polls and checks the flag between waits.
  void stop() override;
  bool pullable() const override { return true; }
  PullResult pull(Frame& frame) override;

 private:
  void read_all(const FrameHandler& handler);
  bool line_frame(size_t begin, size_t end, Frame& frame);  // false: a blank line, no frame

  std::string path_;
  int fd_ = -1;
  std::string buf_;       // bytes read: buf_[begin_, size) not yet delivered
  size_t begin_ = 0;
  size_t scanned_ = 0;    // buf_[begin_, scanned_) holds no newline
  uint64_t line_ = 0;
  bool at_end_ = false, eos_sent_ = false;
  std::thread reader_;
  std::atomic<bool> stop_{false};
};

class FileSink final : public Sink {
 public:
  explicit FileSink(std::string path);  // "-" is stdout; throws if unwritable
  ~FileSink() override;                 // best-effort flush; never throws
  // put/flush throw std::runtime_error naming the file when a write fails
  // (a full disk, a closed pipe): verdicts are never dropped silently.
  void put(std::string_view payload, uint64_t seq) override;
  void put_eos(uint64_t last_seq) override { flush(); }
  void flush() override;
  void idle() override {
    if (dirty_) flush();
  }

 private:
  [[noreturn]] void fail(int error) const;

  std::string path_;
  std::FILE* file_ = nullptr;
  bool dirty_ = false;
  bool owned_ = false;
  bool line_buffered_ = false;
};

}  // namespace rvc::transport
