// zstd as rosbag2 writes it (metadata.yaml compression_format: zstd):
// compression_mode FILE compresses each storage file whole (bag_0.db3.zstd),
// MESSAGE compresses each message's serialized data on its own. Both are
// recognized by the zstd frame's magic number, never by a name: a ROS 2 CDR
// sample starts with its encapsulation header (00 0x), JSON with text.
#pragma once

#include <string>
#include <string_view>

namespace rvc::transport {

// Whether these bytes start a zstd frame.
bool is_zstd_frame(std::string_view bytes);

// Decompresses one message (a whole zstd frame, or several in a row) into
// `out`, streamed: never more than `max_out` bytes are produced (a 45 KB
// frame may expand to gigabytes). False with the reason in `error` for data
// that is not whole or that would decompress to more than `max_out`
// (`too_large` then set).
bool zstd_decompress(std::string_view in, std::string& out, std::string& error, size_t max_out = size_t{256} << 20,
                     bool* too_large = nullptr);

// A storage file compressed whole, decompressed to a temporary file that rvc
// creates (mkstemp in $TMPDIR, else /tmp) and removes when this is destroyed:
// SQLite and the MCAP reader read files. Throws BagError naming the file and
// the byte offset where the data ends or goes bad.
class ZstdFileCopy {
 public:
  explicit ZstdFileCopy(const std::string& compressed);
  ~ZstdFileCopy();
  ZstdFileCopy(const ZstdFileCopy&) = delete;
  ZstdFileCopy& operator=(const ZstdFileCopy&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace rvc::transport
