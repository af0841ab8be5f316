// The parse-only floor for the Timescales benchmark: the same chunked
// simdjson reader `rvc check` uses, visiting every field of every message and
// reading its value, with no monitor. What rvc adds on top of this is the
// cost of monitoring.
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>

#include "io/jsonl_reader.hpp"

namespace {

struct Floor final : rvc::io::JsonlHandler {
  uint64_t messages = 0, trues = 0, errors = 0;
  rvc::io::ReadResult on_object(const rvc::io::Position&, simdjson::ondemand::object object) override {
    ++messages;
    for (auto field : object) {
      std::string_view key;
      if (field.unescaped_key().get(key)) return rvc::io::ReadResult::Malformed;
      simdjson::ondemand::value v;
      if (field.value().get(v)) return rvc::io::ReadResult::Malformed;
      bool b;
      if (!v.get_bool().get(b)) trues += b;
    }
    return rvc::io::ReadResult::Pending;
  }
  void on_error(const rvc::io::LineError&) override { ++errors; }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: rvc_parse_floor TRACE.jsonl\n");
    return 2;
  }
  int fd = ::open(argv[1], O_RDONLY);
  if (fd < 0) {
    std::perror(argv[1]);
    return 2;
  }
  Floor floor;
  std::string error;
  rvc::io::ReaderOptions options;
  bool ok = rvc::io::read_jsonl(fd, floor, options, error);
  std::printf("{\"messages\":%llu,\"true_values\":%llu,\"errors\":%llu}\n",
              static_cast<unsigned long long>(floor.messages), static_cast<unsigned long long>(floor.trues),
              static_cast<unsigned long long>(floor.errors));
  return ok ? 0 : 1;
}
