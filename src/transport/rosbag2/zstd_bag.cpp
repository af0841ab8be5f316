#include "transport/rosbag2/zstd_bag.hpp"

#include <sys/statvfs.h>
#include <unistd.h>
#include <zstd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <vector>

#include "transport/rosbag2/bag_reader.hpp"

namespace rvc::transport {

bool is_zstd_frame(std::string_view b) {
  return b.size() >= 4 && static_cast<unsigned char>(b[0]) == 0x28 && static_cast<unsigned char>(b[1]) == 0xB5 &&
         static_cast<unsigned char>(b[2]) == 0x2F && static_cast<unsigned char>(b[3]) == 0xFD;
}

namespace {
// What the frames' headers declare they decompress to, summed over the
// frames (a skippable frame declares 0); ZSTD_CONTENTSIZE_UNKNOWN if a
// frame does not say, or the frames cannot be told apart.
unsigned long long declared_size(std::string_view in) {
  unsigned long long total = 0;
  for (size_t pos = 0; pos < in.size();) {
    const size_t frame = ZSTD_findFrameCompressedSize(in.data() + pos, in.size() - pos);
    const unsigned long long content = ZSTD_getFrameContentSize(in.data() + pos, in.size() - pos);
    if (ZSTD_isError(frame) || content == ZSTD_CONTENTSIZE_UNKNOWN || content == ZSTD_CONTENTSIZE_ERROR ||
        total + content < total)
      return ZSTD_CONTENTSIZE_UNKNOWN;
    total += content;
    pos += frame;
  }
  return total;
}

struct DStream {
  ZSTD_DStream* s = ZSTD_createDStream();
  ~DStream() { ZSTD_freeDStream(s); }
};
}  // namespace

bool zstd_decompress(std::string_view in, std::string& out, std::string& error, size_t max_out, bool* too_large) {
  out.clear();
  if (too_large) *too_large = false;
  auto over = [&](const std::string& what) {
    out.clear();
    out.shrink_to_fit();  // a bomb's partial output is not kept for the next message
    if (too_large) *too_large = true;
    error = "zstd: " + what + " (--max-message-size)";
    return false;
  };
  // Frames that say their size up front are refused before any byte is made.
  const unsigned long long declared = declared_size(in);
  if (declared != ZSTD_CONTENTSIZE_UNKNOWN) {
    if (declared > max_out)
      return over("its frame declares " + std::to_string(declared) + " bytes decompressed, over the limit of " +
                  std::to_string(max_out));
    out.reserve(static_cast<size_t>(declared));
  }
  // One decoder and buffer per thread, reset per message: a bag of small
  // compressed messages allocates nothing per message (a DStream and its
  // window cost more than most messages).
  thread_local DStream d;
  thread_local std::vector<char> buf(ZSTD_DStreamOutSize());
  if (!d.s) {
    error = "zstd: out of memory";
    return false;
  }
  ZSTD_DCtx_reset(d.s, ZSTD_reset_session_only);
  ZSTD_inBuffer src{in.data(), in.size(), 0};
  size_t ret = 0;
  for (;;) {
    ZSTD_outBuffer dst{buf.data(), buf.size(), 0};
    ret = ZSTD_decompressStream(d.s, &dst, &src);
    if (ZSTD_isError(ret)) {
      error = std::string("zstd: ") + ZSTD_getErrorName(ret) + " near byte " + std::to_string(src.pos);
      return false;
    }
    if (dst.pos > max_out - out.size())  // streamed: memory stops at the cap, whatever the frame claims
      return over("it decompresses to more than the limit of " + std::to_string(max_out) +
                  " bytes (decompression stopped there)");
    out.append(buf.data(), dst.pos);
    if (src.pos == src.size && dst.pos < dst.size) break;  // all input read, nothing more held back
  }
  if (ret != 0) {
    error = "zstd: the compressed data is cut short after " + std::to_string(in.size()) + " bytes";
    return false;
  }
  // zstd's streaming decoder does not hold a frame to its declared size
  // (its one-shot decoder does): a frame whose blocks hold less or more is damaged.
  if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != out.size()) {
    error = "zstd: the frame declares " + std::to_string(declared) + " bytes decompressed, its blocks hold " +
            std::to_string(out.size()) + " (damaged)";
    out.clear();
    return false;
  }
  return true;
}

ZstdFileCopy::ZstdFileCopy(const std::string& compressed) {
  std::ifstream in(compressed, std::ios::binary);
  if (!in) throw BagError("bag '" + compressed + "': cannot open it");
  const char* tmp = std::getenv("TMPDIR");
  std::string templ = std::string(tmp && *tmp ? tmp : "/tmp") + "/rvc-bag-XXXXXX";
  const int fd = ::mkstemp(templ.data());
  if (fd < 0) throw BagError("bag '" + compressed + "': cannot create a temporary file to decompress it into");
  path_ = templ;
  std::unique_ptr<FILE, int (*)(FILE*)> out(::fdopen(fd, "wb"), &std::fclose);
  DStream d;
  std::vector<char> ibuf(ZSTD_DStreamInSize()), obuf(ZSTD_DStreamOutSize());
  uint64_t offset = 0, written = 0, checked_at = 0;
  size_t ret = 0;
  auto fail = [&](const std::string& why) {
    ::unlink(path_.c_str());
    throw BagError("bag '" + compressed + "': " + why);
  };
  while (in) {
    in.read(ibuf.data(), static_cast<std::streamsize>(ibuf.size()));
    ZSTD_inBuffer src{ibuf.data(), static_cast<size_t>(in.gcount()), 0};
    for (;;) {
      ZSTD_outBuffer dst{obuf.data(), obuf.size(), 0};
      ret = ZSTD_decompressStream(d.s, &dst, &src);
      if (ZSTD_isError(ret))
        fail(std::string("not a whole zstd file: ") + ZSTD_getErrorName(ret) + " near byte " +
             std::to_string(offset + src.pos));
      if (dst.pos && std::fwrite(obuf.data(), 1, dst.pos, out.get()) != dst.pos)
        fail("cannot write the decompressed copy to " + path_);
      written += dst.pos;
      // A frame of a few KB may expand to any size (RLE blocks): the copy
      // stops before it fills the disk, leaving 5% of it to everyone else.
      if (written - checked_at >= (uint64_t{64} << 20)) {
        checked_at = written;
        struct statvfs fs{};
        if (::fstatvfs(fd, &fs) == 0 &&
            static_cast<uint64_t>(fs.f_bavail) * fs.f_frsize < static_cast<uint64_t>(fs.f_blocks) * fs.f_frsize / 20)
          fail("its decompressed copy reached " + std::to_string(written) + " bytes in " + path_ +
               " and would leave less than 5% of that file system free: stopped there (set TMPDIR to a folder "
               "with more room)");
      }
      if (src.pos == src.size && dst.pos < dst.size) break;
    }
    offset += src.size;
  }
  if (ret != 0) fail("the zstd data is cut short after " + std::to_string(offset) + " bytes");
  if (std::fflush(out.get()) != 0) fail("cannot write the decompressed copy to " + path_);
}

ZstdFileCopy::~ZstdFileCopy() {
  if (!path_.empty()) ::unlink(path_.c_str());
}

}  // namespace rvc::transport
