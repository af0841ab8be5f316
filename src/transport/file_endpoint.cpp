#include "transport/file_endpoint.hpp"

#include <unistd.h>

#include <stdexcept>

namespace rvc::transport {

FileSource::FileSource(std::string path) : path_(std::move(path)) {
  file_ = path_ == "-" ? stdin : std::fopen(path_.c_str(), "r");
  if (!file_) throw std::invalid_argument("cannot open '" + path_ + "' for reading");
}

FileSource::~FileSource() {
  stop();
  if (file_ && file_ != stdin) std::fclose(file_);
}

void FileSource::start(FrameHandler handler) {
  reader_ = std::thread([this, handler = std::move(handler)] {
    char* line = nullptr;
    size_t cap = 0;
    uint64_t seq = 0;
    ssize_t n;
    while (!stop_ && (n = ::getline(&line, &cap, file_)) >= 0) {
      size_t len = static_cast<size_t>(n);
      while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) --len;
      ++seq;
      if (len == 0) continue;  // blank lines are not messages
      handler(Frame{std::string_view(line, len), seq, false});
    }
    std::free(line);
    if (!stop_) handler(Frame{{}, seq, true});
  });
}

void FileSource::stop() {
  stop_ = true;
  if (reader_.joinable()) reader_.join();
}

FileSink::FileSink(std::string path) {
  if (path == "-") {
    file_ = stdout;
    line_buffered_ = isatty(1);
  } else {
    file_ = std::fopen(path.c_str(), "w");
    owned_ = true;
  }
  if (!file_) throw std::invalid_argument("cannot open '" + path + "' for writing");
}

FileSink::~FileSink() {
  flush();
  if (owned_) std::fclose(file_);
}

void FileSink::put(std::string_view payload, uint64_t) {
  std::fwrite(payload.data(), 1, payload.size(), file_);
  std::fputc('\n', file_);
  if (line_buffered_) std::fflush(file_);
  else dirty_ = true;
}

void FileSink::flush() {
  std::fflush(file_);
  dirty_ = false;
}

}  // namespace rvc::transport
