// The parse-only floor for the Timescales benchmark: the same chunked
// simdjson reader `rvc check` uses, visiting every field of every message,
// with no monitor. Plain, it reads Booleans and leaves numbers and strings
// unread (simdjson skips them without checking them); --validate reads every
// scalar by its type, the least a reader must do that rejects malformed
// values anywhere in a message, as rvc does.
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>

#include "io/jsonl_reader.hpp"

namespace {

struct Floor final : rvc::io::JsonlHandler {
  explicit Floor(bool validate) : validate(validate) {}
  const bool validate;
  uint64_t messages = 0, trues = 0, errors = 0;
  double sum = 0;
  rvc::io::ReadResult on_object(const rvc::io::Position&, simdjson::ondemand::object object) override {
    ++messages;
    for (auto field : object) {
      std::string_view key;
      if (field.unescaped_key().get(key)) return rvc::io::ReadResult::Malformed;
      simdjson::ondemand::value v;
      if (field.value().get(v)) return rvc::io::ReadResult::Malformed;
      bool b;
      if (!v.get_bool().get(b)) {
        trues += b;
        continue;
      }
      if (!validate) continue;  // a number or string is left unread: simdjson skips it unchecked
      // --validate: every scalar read by its type, as a reader that must reject
      // malformed values (rvc: issue 10) has to, even in fields nothing tests.
      simdjson::ondemand::json_type type;
      if (v.type().get(type)) return rvc::io::ReadResult::Malformed;
      if (type == simdjson::ondemand::json_type::number) {
        double d;
        if (v.get_double().get(d)) return rvc::io::ReadResult::Malformed;
        sum += d;
      } else if (type == simdjson::ondemand::json_type::string) {
        std::string_view s;
        if (v.get_string().get(s)) return rvc::io::ReadResult::Malformed;
      }
    }
    return rvc::io::ReadResult::Pending;
  }
  void on_error(const rvc::io::LineError&) override { ++errors; }
};

}  // namespace

int main(int argc, char** argv) {
  const bool validate = argc == 3 && std::strcmp(argv[1], "--validate") == 0;
  if (argc != 2 && !validate) {
    std::fprintf(stderr, "usage: rvc_parse_floor [--validate] TRACE.jsonl\n");
    return 2;
  }
  const char* path = argv[argc - 1];
  int fd = ::open(path, O_RDONLY);
  if (fd < 0) {
    std::perror(path);
    return 2;
  }
  Floor floor(validate);
  std::string error;
  rvc::io::ReaderOptions options;
  bool ok = rvc::io::read_jsonl(fd, floor, options, error);
  std::printf("{\"messages\":%llu,\"true_values\":%llu,\"errors\":%llu}\n",
              static_cast<unsigned long long>(floor.messages), static_cast<unsigned long long>(floor.trues),
              static_cast<unsigned long long>(floor.errors));
  return ok ? 0 : 1;
}
