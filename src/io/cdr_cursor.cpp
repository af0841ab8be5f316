#include "io/cdr_cursor.hpp"

namespace rvc::io {

bool CdrCursor::open(std::string_view sample) {
  if (sample.size() < kHeader) {
    error_ = {"sample of " + std::to_string(sample.size()) + " bytes has no 4-byte CDR header", 0};
    return false;
  }
  const auto b0 = static_cast<unsigned char>(sample[0]), b1 = static_cast<unsigned char>(sample[1]);
  if (sample.compare(0, 4, "\x28\xb5\x2f\xfd") == 0) {  // zstd's frame magic, where CDR's header would be
    error_ = {"this message is zstd-compressed (rosbag2 per-message compression; rvc reads uncompressed "
              "samples: write the bag again without compression, e.g. with ros2 bag convert)",
              0};
    return false;
  }
  if (b0 != 0 || b1 > 1) {
    const char* what = b0 == 0 && (b1 == 2 || b1 == 3)   ? " (parameter-list CDR)"
                       : b0 == 0 && b1 >= 6 && b1 <= 11 ? " (XCDR2, not ROS 2's plain CDR)"
                                                        : "";
    static const char hex[] = "0123456789abcdef";
    error_ = {std::string("unsupported CDR representation 0x") + hex[b0 >> 4] + hex[b0 & 15] + hex[b1 >> 4] +
                  hex[b1 & 15] + what,
              0};
    return false;
  }
  constexpr bool host_little = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
  data_ = reinterpret_cast<const unsigned char*>(sample.data()) + kHeader;
  size_ = sample.size() - kHeader;
  pos_ = 0;
  depth_ = 0;
  swap_ = (b1 == 1) != host_little;
  return true;
}

bool CdrCursor::string_too_long(uint32_t len) {
  const std::string p = path();
  error_ = {(p.empty() ? std::string("a string") : "string field '" + p + "'") + " claims " + std::to_string(len) +
                " bytes, the sample has " + std::to_string(size_ - pos_ - 4) + " left",
            pos_ + kHeader};
  return false;
}

std::string CdrCursor::path() const {
  std::string p;
  for (size_t i = 0; i < std::min(depth_, kMaxPath); ++i) {
    if (path_[i].name) {
      if (!p.empty()) p += '.';
      p += *path_[i].name;
    } else {
      p += '[' + std::to_string(path_[i].index) + ']';
    }
  }
  if (depth_ > kMaxPath) p += "...";
  return p;
}

}  // namespace rvc::io
