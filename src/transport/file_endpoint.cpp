#include "transport/file_endpoint.hpp"

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
  std::string buf;       // bytes read, not yet split into lines
  size_t scanned = 0;    // buf[0, scanned) holds no newline
  uint64_t line = 0;
  auto deliver = [&](size_t begin, size_t end) {
    size_t len = end - begin;
    while (len > 0 && buf[begin + len - 1] == '\r') --len;
    ++line;
    // Blank lines (nothing, or only spaces, tabs and CRs) are not messages,
    // as in `rvc check`.
    std::string_view text(buf.data() + begin, len);
    if (text.find_first_not_of(" \t\r") != std::string_view::npos) {
      Frame f;
      f.payload = text;
      f.seq = line;
      handler(f);
    }
  };
  char chunk[1 << 16];
  for (;;) {
    if (stop_.load(std::memory_order_relaxed)) return;
    pollfd p{fd_, POLLIN, 0};
    int ready = ::poll(&p, 1, 100);  // wake up now and then to see stop()
    if (ready < 0 && errno != EINTR) break;
    if (ready <= 0) continue;
    ssize_t n = ::read(fd_, chunk, sizeof chunk);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      break;  // a read error ends the input like its end would
    }
    if (n == 0) break;
    buf.append(chunk, static_cast<size_t>(n));
    size_t begin = 0;
    for (;;) {
      const void* nl = std::memchr(buf.data() + scanned, '\n', buf.size() - scanned);
      if (!nl) break;
      size_t end = static_cast<size_t>(static_cast<const char*>(nl) - buf.data());
      deliver(begin, end);
      begin = scanned = end + 1;
    }
    buf.erase(0, begin);
    scanned = buf.size();
  }
  if (!buf.empty()) deliver(0, buf.size());  // a last line without its newline
  if (!stop_.load()) {
    Frame eos;
    eos.seq = line;
    eos.eos = true;
    handler(eos);
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
    file_ = std::fopen(path_.c_str(), "w");
    owned_ = true;
  }
  if (!file_) throw std::invalid_argument("cannot open '" + path_ + "' for writing: " + std::strerror(errno));
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
