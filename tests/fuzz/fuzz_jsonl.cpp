// libFuzzer harness: JSON-lines reader + decoder + engine (src/io, src/runtime).
//
// Input: one options byte, then the JSON-lines text. Beyond crashes (ASan,
// UBSan), two oracles turn wrong results into crashes:
//  1. property independence: property "a" gets the same verdicts, and the
//     same messages are accepted/rejected, whether or not property "b"
//     (reading other fields) runs beside it — malformed JSON must be rejected
//     whatever the properties read;
//  2. file vs topic: the chunked file reader (`rvc check`) and one payload per
//     line (`rvc monitor --input file:`) accept and reject the same messages;
//  3. layouts vs simdjson: reading lines by their learned layout
//     (io/json_layout.hpp) gives the verdicts, the robustness values (bit for
//     bit) and the counts that parsing every line with simdjson gives.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "runtime/pipeline.hpp"
#include "spec/spec_error.hpp"

namespace {

using rvc::engine::PropertySpec;
using rvc::runtime::Pipeline;
using rvc::runtime::PipelineOptions;

struct Result {
  std::vector<std::pair<double, bool>> verdicts;  // property "a"
  std::vector<uint64_t> robustness;               // its robustness values' bits (with robustness)
  uint64_t accepted = 0, rejected = 0, warnings = 0;
};

void record(Result& r, const rvc::engine::Verdict& v) {
  if (v.property != "a") return;
  r.verdicts.emplace_back(v.time, v.value);
  uint64_t bits;
  std::memcpy(&bits, &v.robustness, sizeof bits);
  r.robustness.push_back(bits);
}

Result run_file(const std::vector<PropertySpec>& props, const PipelineOptions& o, const std::string& text,
                size_t chunk) {
  Result r;
  Pipeline p(props, o, [&](const rvc::engine::Verdict& v) { record(r, v); });
  int fd = memfd_create("fuzz", 0);
  if (fd < 0 || write(fd, text.data(), text.size()) != static_cast<ssize_t>(text.size())) std::abort();
  lseek(fd, 0, SEEK_SET);
  rvc::io::ReaderOptions ro;
  ro.chunk_bytes = chunk;
  ro.max_line_bytes = o.max_message_size;
  std::string error;
  if (!rvc::io::read_jsonl(fd, p, ro, error)) std::abort();
  close(fd);
  r.accepted = p.stats().accepted;
  r.rejected = p.stats().rejected;
  r.warnings = p.stats().warnings;
  return r;
}

// As `rvc monitor --input file:` sees a file (FileSource, then MonitorLoop):
// one payload per line, trailing CRs dropped, blank lines skipped, a
// byte-order mark at the start skipped.
Result run_payloads(const std::vector<PropertySpec>& props, const PipelineOptions& o, const std::string& text) {
  Result r;
  PipelineOptions po = o;
  po.position_name = "seq";
  Pipeline p(props, po, [&](const rvc::engine::Verdict& v) { record(r, v); });
  uint64_t line = 0;
  for (size_t at = 0; at < text.size();) {
    size_t nl = text.find('\n', at);
    if (nl == std::string::npos) nl = text.size();
    std::string_view payload(text.data() + at, nl - at);
    at = nl + 1;
    ++line;
    while (!payload.empty() && payload.back() == '\r') payload.remove_suffix(1);
    if (payload.find_first_not_of(" \t\r") == std::string_view::npos) continue;  // blank: FileSource skips it
    if (line == 1 && payload.substr(0, 3) == rvc::io::kUtf8Bom) {  // MonitorLoop drops a file's mark
      payload.remove_prefix(3);
      if (payload.find_first_not_of(" \t\r") == std::string_view::npos) continue;
    }
    p.feed(payload, line);
  }
  r.accepted = p.stats().accepted;
  r.rejected = p.stats().rejected;
  r.warnings = p.stats().warnings;
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t flags = data[0];
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  PipelineOptions o;
  o.emit_all = true;
  o.max_reported = 0;  // the pipeline reports nothing: keep the fuzzer's output readable
  o.model = (flags & 1) ? rvc::engine::TimeModel::Dense : rvc::engine::TimeModel::Discrete;
  o.strict = (flags & 2) != 0;
  o.max_message_size = (flags & 4) ? 24 : 1 << 20;
  const size_t chunk = (flags & 8) ? 16 : 1 << 20;
  const std::vector<PropertySpec> alone = {{"a", "{x > 0} since ({y} or {s == \"w\"})"}};
  const std::vector<PropertySpec> both = {{"a", "{x > 0} since ({y} or {s == \"w\"})"},
                                          {"b", "once[1:3] ({u.v == \"w\"} or {z} or {u.k: *} or {r[1] > 2} or {u.l[0].m})"}};
  Result a = run_file(alone, o, text, chunk);
  Result b = run_file(both, o, text, chunk);
  // Strict mode rejects messages that lack a tested field: then the property
  // set decides what is rejected, by design.
  if (!o.strict && (a.verdicts != b.verdicts || a.accepted != b.accepted || a.rejected != b.rejected)) std::abort();
  Result c = run_payloads(alone, o, text);
  if (a.accepted != c.accepted || a.rejected != c.rejected || a.verdicts != c.verdicts) std::abort();
  // 3: the same runs with every line parsed by simdjson, and with robustness
  // values (flag 16), where a number read one bit differently shows.
  PipelineOptions slow = o;
  slow.layouts = false;
  if (flags & 16) {
    o.robustness = slow.robustness = true;
    a = run_file(alone, o, text, chunk);
  }
  const auto same = [](const Result& x, const Result& y) {
    return x.verdicts == y.verdicts && x.robustness == y.robustness && x.accepted == y.accepted &&
           x.rejected == y.rejected && x.warnings == y.warnings;
  };
  if (!same(a, run_file(alone, slow, text, chunk))) std::abort();
  if (!same(run_payloads(alone, o, text), run_payloads(alone, slow, text))) std::abort();
  return 0;
}
