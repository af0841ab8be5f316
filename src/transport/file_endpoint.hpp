// file:PATH endpoints: JSON lines. As a source, each line is one frame (seq =
// line number) followed by an end-of-stream frame; as a sink, each payload is
// written as one line.
#pragma once

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
  void stop() override;

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::thread reader_;
  bool stop_ = false;
};

class FileSink final : public Sink {
 public:
  explicit FileSink(std::string path);  // "-" is stdout; throws if unwritable
  ~FileSink() override;
  void put(std::string_view payload, uint64_t seq) override;
  void put_eos(uint64_t last_seq) override { flush(); }
  void flush() override;
  void idle() override {
    if (dirty_) flush();
  }

 private:
  std::FILE* file_ = nullptr;
  bool dirty_ = false;
  bool owned_ = false;
  bool line_buffered_ = false;
};

}  // namespace rvc::transport
