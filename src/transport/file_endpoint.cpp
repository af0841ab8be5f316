#include "transport/file_endpoint.hpp"

#include "transport/output_file.hpp"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace rvc::transport {

FileSource::FileSource(std::string path) : path_(std::move(path)) {
  fd_ = path_ == "-" ? 0 : ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw std::invalid_argument("cannot open '" + path_ + "' for reading: " + std::strerror(errno));
}

FileSource::~FileSource() {
  stop();
  if (fd_ > 0) ::close(fd_);
}

void FileSource::start(FrameHandler handler) {
  reader_ = std::thread([this, handler = std::move(handler)] { read_all(handler); });
}

void FileSource::read_all(const FrameHandler& handler) {
  Frame f;
  for (;;) {
    if (stop_.load(std::memory_order_relaxed)) return;
    const PullResult r = pull(f);
    if (r == PullResult::End) return;
    if (r == PullResult::Wait) continue;  // pull waited ~100 ms: look at stop_ again
    if (f.eos && stop_.load()) return;
    handler(f);
    if (f.eos) return;
  }
}

bool FileSource::line_frame(size_t begin, size_t end, Frame& f) {
  size_t len = end - begin;
  while (len > 0 && buf_[begin + len - 1] == '\r') --len;
  ++line_;
  // Blank lines (nothing, or only spaces, tabs and CRs) are not messages,
  // as in `rvc check`.
  std::string_view text(buf_.data() + begin, len);
  if (text.find_first_not_of(" \t\r") == std::string_view::npos) return false;
  f = Frame{};
  f.payload = text;
  f.seq = line_;
  return true;
}

PullResult FileSource::pull(Frame& f) {
  for (;;) {
    if (const void* nl = std::memchr(buf_.data() + scanned_, '\n', buf_.size() - scanned_)) {
      const size_t end = static_cast<size_t>(static_cast<const char*>(nl) - buf_.data());
      const size_t begin = begin_;
      begin_ = scanned_ = end + 1;
      if (line_frame(begin, end, f)) return PullResult::Frame;
      continue;
    }
    scanned_ = buf_.size();
    if (at_end_) {
      if (begin_ < buf_.size()) {  // a last line without its newline
        const size_t begin = begin_;
        begin_ = scanned_ = buf_.size();
        if (line_frame(begin, buf_.size(), f)) return PullResult::Frame;
      }
      if (eos_sent_) return PullResult::End;
      eos_sent_ = true;
      f = Frame{};
      f.seq = line_;
      f.eos = true;
      return PullResult::Frame;
    }
    // More bytes are needed: drop what was delivered (the frame returned by
    // the previous pull goes with it), then wait for the next chunk.
    buf_.erase(0, begin_);
    scanned_ -= begin_;
    begin_ = 0;
    pollfd p{fd_, POLLIN, 0};
    const int ready = ::poll(&p, 1, 100);  // wake up now and then: the caller may want to stop
    if (ready < 0 && errno != EINTR) {
      at_end_ = true;  // a read error ends the input like its end would
      continue;
    }
    if (ready <= 0) return PullResult::Wait;
    char chunk[1 << 16];
    const ssize_t n = ::read(fd_, chunk, sizeof chunk);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) return PullResult::Wait;
      at_end_ = true;
      continue;
    }
    if (n == 0) at_end_ = true;
    else buf_.append(chunk, static_cast<size_t>(n));
  }
}

void FileSource::stop() {
  stop_ = true;
  if (reader_.joinable()) reader_.join();
}

FileSink::FileSink(std::string path) : path_(std::move(path)) {
  if (path_ == "-") {
    file_ = stdout;
    line_buffered_ = isatty(1);
  } else {
    file_ = open_output_file(path_);  // refuses a file rvc did not write
    owned_ = true;
  }
}

FileSink::~FileSink() {
  std::fflush(file_);  // errors were reported by flush(), which the owners call at the end
  if (owned_) std::fclose(file_);
}

void FileSink::fail(int error) const {
  throw std::runtime_error("cannot write '" + (path_ == "-" ? std::string("stdout") : path_) +
                           "': " + std::strerror(error));
}

void FileSink::put(std::string_view payload, uint64_t) {
  if (std::fwrite(payload.data(), 1, payload.size(), file_) != payload.size() || std::fputc('\n', file_) == EOF)
    fail(errno);
  if (line_buffered_) flush();
  else dirty_ = true;
}

void FileSink::flush() {
  dirty_ = false;
  if (std::fflush(file_) != 0 || std::ferror(file_)) fail(errno ? errno : EIO);
}

}  // namespace rvc::transport
