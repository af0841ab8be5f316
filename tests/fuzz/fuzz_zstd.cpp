// libFuzzer harness: one message of a bag with rosbag2's per-message
// compression (compression_mode: message), as transport/rosbag2 undoes it:
// zstd frames from bytes, decompressed streamed under a cap
// (transport::zstd_decompress, the cap being --max-message-size).
//
// Findings: any crash or sanitizer report, an allocation over the limits
// (tests/fuzz/resource_limits.hpp: a frame that declares or expands to
// gigabytes must cost no more than the cap), a run that never ends.
// Oracle: zstd's one-shot API (ZSTD_decompress into a buffer of the cap):
// what it decompresses within the cap, the streamed decoder gives byte for
// byte (unless the frame's window passes the streaming decoder's limit); what the streamed decoder gives, it gives too; output never passes
// the cap; a refusal for size names --max-message-size.
#include <zstd.h>
#include <zstd_errors.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "resource_limits.hpp"
#include "transport/rosbag2/zstd_bag.hpp"

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rvc::fuzz::add_resource_limits(argc, argv);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // The first byte picks the cap (64 B .. 8 MiB): small caps reach the
  // refusals, large ones let real frames through.
  if (size < 5) return 0;
  const size_t cap = size_t{64} << (data[0] % 18);
  const std::string_view in(reinterpret_cast<const char*>(data + 1), size - 1);
  if (!rvc::transport::is_zstd_frame(in)) return 0;  // the bag reader hands on such data as it is stored
  std::string out, error;
  bool too_large = false;
  const bool ok = rvc::transport::zstd_decompress(in, out, error, cap, &too_large);
  if (out.size() > cap) __builtin_trap();
  if (!ok && error.empty()) __builtin_trap();
  if (too_large && error.find("--max-message-size") == std::string::npos) __builtin_trap();
  if (!ok && !out.empty() && too_large) __builtin_trap();  // a refused bomb keeps nothing

  static std::vector<char> ref;
  ref.resize(cap);
  const size_t n = ZSTD_decompress(ref.data(), ref.size(), in.data(), in.size());
  // On invalid frames the two decoders differ either way (streamed: a window
  // over zstd's default limit of 128 MiB, a block larger than its frame's
  // window, refused; one-shot: an empty compressed block refused), so the
  // oracle holds where both read a frame: the same bytes. And the cap is
  // exact: what one-shot reads within the cap is never refused for size;
  // what is refused for size, one-shot cannot read within the cap.
  if (ok && !ZSTD_isError(n) && (n != out.size() || std::string_view(ref.data(), n) != out)) __builtin_trap();
  if (too_large && !ZSTD_isError(n)) __builtin_trap();
  return 0;
}
