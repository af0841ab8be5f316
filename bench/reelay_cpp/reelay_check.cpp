// reelay_check: Reelay 25's C++ discrete-time monitor fed by a simdjson JSON-lines reader.
//
//   reelay_check --spec FORMULA [--input dom|json] [--print] [--convert-only] FILE
//
// A stand-in for Reelay's own `ryjson` app (whose source is not in Reelay's PyPI sdist), written for
// rvc's benchmark (bench/timescales_bench.py) against Reelay's public C++ API only. It is compiled
// against the headers of the `reelay==25.0.0` sdist by bench/reelay_cpp/fetch.py; no Reelay code lives
// in this repository.
//
// Each line of FILE is one step (discrete time; a "time" field is passed on like any other field and
// ignored by the monitor, as in Reelay). The file is read in 4 MiB chunks; each chunk's complete lines
// are parsed by simdjson in one batch, and each line's object goes to
// reelay::discrete_timed_monitor<int64_t, INPUT, reelay::json, true>, which condenses its output: a
// non-empty object {"time":t,"value":b} at step 0 and whenever the verdict changes. INPUT is
//   --input dom (default): simdjson::dom::element, the parsed line itself, read by Reelay's atoms through
//     the datafield adapter below (Reelay's ryjson also feeds DOM elements to its monitors);
//   --input json: reelay::json (nlohmann), every field of the line converted (simdjson On Demand), one
//     object reused from line to line so that a scalar field costs no allocation.
//
// Prints {"messages":N,"verdicts":M,"false_verdicts":K} on stdout; with --print, each verdict change
// first, one JSON line {"time":t,"value":b} (used by the benchmark's correctness check). With
// --convert-only, lines are read, parsed (and converted) but not monitored (to see where the time goes).
#include <simdjson.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <algorithm>
#include <iterator>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "reelay/monitors.hpp"

namespace {

struct Failure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void check(simdjson::error_code e, const char* what) {
  if (e != simdjson::SUCCESS) throw Failure(std::string(what) + ": " + simdjson::error_message(e));
}

}  // namespace

// How Reelay's atoms read a field of a simdjson DOM element ({p}, {x > 3}, {s == "a"}, ...): the same
// interface as Reelay's datafield<reelay::json>; a wrong type throws, as nlohmann's conversions do.
namespace reelay {
template <>
struct datafield<simdjson::dom::element> {
  using input_t = simdjson::dom::element;
  static simdjson::dom::element field(const input_t& c, const std::string& key) {
    simdjson::dom::element e;
    check(c[key].get(e), "field");
    return e;
  }
  static simdjson::dom::element item(const input_t& c, std::size_t index) {
    simdjson::dom::element e;
    check(c.at(index).get(e), "array item");
    return e;
  }
  static bool contains(const input_t& c, const std::string& key) { return c[key].error() == simdjson::SUCCESS; }
  static bool as_bool(const input_t& c, const std::string& key) {
    bool b;
    check(field(c, key).get_bool().get(b), "bool");
    return b;
  }
  static int as_integer(const input_t& c, const std::string& key) {
    int64_t i;
    check(field(c, key).get_int64().get(i), "integer");
    return static_cast<int>(i);
  }
  static double as_floating(const input_t& c, const std::string& key) {
    double d;
    check(field(c, key).get_double().get(d), "number");
    return d;
  }
  static std::string as_string(const input_t& c, const std::string& key) {
    std::string_view s;
    check(field(c, key).get_string().get(s), "string");
    return std::string(s);
  }
  static bool contains(const input_t& c, std::size_t index) { return c.at(index).error() == simdjson::SUCCESS; }
  static bool as_bool(const input_t& c, std::size_t index) {
    bool b;
    check(item(c, index).get_bool().get(b), "bool");
    return b;
  }
  static int as_integer(const input_t& c, std::size_t index) {
    int64_t i;
    check(item(c, index).get_int64().get(i), "integer");
    return static_cast<int>(i);
  }
  static double as_floating(const input_t& c, std::size_t index) {
    double d;
    check(item(c, index).get_double().get(d), "number");
    return d;
  }
  static std::string as_string(const input_t& c, std::size_t index) {
    std::string_view s;
    check(item(c, index).get_string().get(s), "string");
    return std::string(s);
  }
};
}  // namespace reelay

namespace {

using Input = reelay::json;
namespace od = simdjson::ondemand;

Input convert(od::value v);

Input convert_object(od::object obj) {
  Input out = Input::object();
  for (auto field : obj) {
    std::string_view key;
    check(field.unescaped_key().get(key), "key");
    od::value val;
    check(field.value().get(val), "value");
    out.emplace(std::string(key), convert(val));
  }
  return out;
}

// The top-level object of a line, converted into `out`, which is kept from line to line: a key already
// there gets its new value in place (no allocation for a scalar), a new key is inserted, and keys the line
// lacks are erased, so `out` equals the line's object exactly, as a fresh conversion would.
void convert_line(od::object obj, Input& out, std::vector<std::string_view>& seen) {
  seen.clear();
  for (auto field : obj) {
    std::string_view key;
    check(field.unescaped_key().get(key), "key");
    od::value val;
    check(field.value().get(val), "value");
    seen.push_back(key);
    auto it = out.find(key);
    if (it == out.end()) out.emplace(std::string(key), convert(val));
    else *it = convert(val);
  }
  if (out.size() == seen.size()) return;
  for (auto it = out.begin(); it != out.end();) {  // rare: a key of an earlier line is missing here
    bool present = false;
    for (auto k : seen) present = present || k == it.key();
    it = present ? std::next(it) : out.erase(it);
  }
}

Input convert(od::value v) {
  od::json_type t;
  check(v.type().get(t), "type");
  switch (t) {
    case od::json_type::object: {
      od::object o;
      check(v.get_object().get(o), "object");
      return convert_object(o);
    }
    case od::json_type::array: {
      od::array a;
      check(v.get_array().get(a), "array");
      Input out = Input::array();
      for (auto item : a) {
        od::value iv;
        check(item.get(iv), "array item");
        out.push_back(convert(iv));
      }
      return out;
    }
    case od::json_type::string: {
      std::string_view s;
      check(v.get_string().get(s), "string");
      return Input(std::string(s));
    }
    case od::json_type::boolean: {
      bool b;
      check(v.get_bool().get(b), "bool");
      return Input(b);
    }
    case od::json_type::null: {
      bool is_null;
      check(v.is_null().get(is_null), "null");
      return Input(nullptr);
    }
    case od::json_type::number: {
      od::number_type nt;
      check(v.get_number_type().get(nt), "number");
      if (nt == od::number_type::signed_integer) {
        int64_t i;
        check(v.get_int64().get(i), "int64");
        return Input(i);
      }
      if (nt == od::number_type::unsigned_integer) {
        uint64_t u;
        check(v.get_uint64().get(u), "uint64");
        return Input(u);
      }
      double d;
      check(v.get_double().get(d), "double");
      return Input(d);
    }
  }
  throw Failure("unknown JSON type");
}

struct Counts {
  uint64_t messages = 0, verdicts = 0, false_verdicts = 0;
};

bool g_convert_only = false;  // --convert-only: parse and convert, no monitor (to see where the time goes)

template <typename Monitor, typename In>
void feed(Monitor& m, const In& obj, Counts& c, bool print) {
  ++c.messages;
  if (g_convert_only) return;
  Input out = m.update(obj);
  if (out.empty()) return;
  ++c.verdicts;
  const bool value = out.at("value").get<bool>();
  if (!value) ++c.false_verdicts;
  if (print) std::printf("{\"time\":%lld,\"value\":%s}\n", static_cast<long long>(out.at("time").get<int64_t>()),
                         value ? "true" : "false");
}

// Parses the complete lines in buf[0, len) (buf has SIMDJSON_PADDING writable bytes after len) into
// reelay::json objects for the monitor.
struct JsonLines {
  using input_type = Input;
  od::parser parser;
  Input line = Input::object();
  std::vector<std::string_view> seen;

  template <typename Monitor>
  void parse(const char* buf, size_t len, Monitor& m, Counts& c, bool print) {
    od::document_stream docs;
    // batch_size must hold the largest document; a chunk's lines are all shorter than the chunk.
    check(parser.iterate_many(buf, len, std::max<size_t>(len, 64)).get(docs), "iterate_many");
    for (auto it = docs.begin(); it != docs.end(); ++it) {
      auto doc = *it;
      od::object obj;
      check(doc.get_object().get(obj), "line is not a JSON object");
      convert_line(obj, line, seen);
      feed(m, line, c, print);
    }
    check(docs.truncated_bytes() == 0 ? simdjson::SUCCESS : simdjson::TAPE_ERROR, "truncated document");
  }
};

// The same, each line's DOM element going to the monitor as it is.
struct DomLines {
  using input_type = simdjson::dom::element;
  simdjson::dom::parser parser;

  template <typename Monitor>
  void parse(const char* buf, size_t len, Monitor& m, Counts& c, bool print) {
    simdjson::dom::document_stream docs;
    check(parser.parse_many(buf, len, std::max<size_t>(len, 64)).get(docs), "parse_many");
    for (auto it = docs.begin(); it != docs.end(); ++it) {
      simdjson::dom::element doc;
      check((*it).get(doc), "line");
      if (!doc.is_object()) throw Failure("line is not a JSON object");
      feed(m, doc, c, print);
    }
    check(docs.truncated_bytes() == 0 ? simdjson::SUCCESS : simdjson::TAPE_ERROR, "truncated document");
  }
};

template <typename Lines>
int run(const std::string& spec, const char* path, bool print) {
  using Monitor = reelay::discrete_timed_monitor<int64_t, typename Lines::input_type, Input, true>;
  Monitor monitor = Monitor::make(spec, reelay::basic_options().with_condensing(true));
  std::FILE* f = std::fopen(path, "rb");
  if (!f) throw Failure(std::string("cannot open ") + path);
  Lines lines;
  Counts counts;
  size_t cap = size_t(4) << 20;  // chunk size; doubles if one line does not fit
  std::vector<char> buf(cap + simdjson::SIMDJSON_PADDING);
  size_t have = 0;  // bytes in buf (a partial line carried over from the previous chunk first)
  bool eof = false;
  while (!eof) {
    if (have == cap) {
      cap *= 2;
      buf.resize(cap + simdjson::SIMDJSON_PADDING);
    }
    size_t n = std::fread(buf.data() + have, 1, cap - have, f);
    have += n;
    eof = n == 0 || std::feof(f);
    size_t end = have;  // parse up to and including the last newline (or everything at EOF)
    if (!eof) {
      while (end > 0 && buf[end - 1] != '\n') --end;
      if (end == 0) continue;  // no complete line yet: grow and read more
    }
    // iterate_many reads the padding after `end`: move the carried-over tail aside first.
    std::string tail(buf.data() + end, buf.data() + have);
    std::memset(buf.data() + end, 0, simdjson::SIMDJSON_PADDING);
    if (end > 0) lines.parse(buf.data(), end, monitor, counts, print);
    std::memcpy(buf.data(), tail.data(), tail.size());
    have = tail.size();
  }
  std::fclose(f);
  std::printf("{\"messages\":%llu,\"verdicts\":%llu,\"false_verdicts\":%llu}\n",
              static_cast<unsigned long long>(counts.messages), static_cast<unsigned long long>(counts.verdicts),
              static_cast<unsigned long long>(counts.false_verdicts));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string spec;
  const char* path = nullptr;
  bool print = false;
  std::string input = "dom";
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--spec" && i + 1 < argc) spec = argv[++i];
    else if (a == "--print") print = true;
    else if (a == "--convert-only") g_convert_only = true;
    else if (a == "--input" && i + 1 < argc) input = argv[++i];
    else if (!path && a.rfind("--", 0) != 0) path = argv[i];
    else {
      std::fprintf(stderr, "usage: reelay_check --spec FORMULA [--input dom|json] [--print] [--convert-only] FILE\n");
      return 2;
    }
  }
  if (spec.empty() || !path || (input != "dom" && input != "json")) {
    std::fprintf(stderr, "usage: reelay_check --spec FORMULA [--input dom|json] [--print] [--convert-only] FILE\n");
    return 2;
  }
  try {
    auto inspection = reelay::ptl_inspector().inspect(spec);
    if (reelay::any_cast<bool>(inspection["has_references"]))
      throw Failure("formulas with data references are not supported by this harness");
    return input == "dom" ? run<DomLines>(spec, path, print) : run<JsonLines>(spec, path, print);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "reelay_check: %s\n", e.what());
    return 1;
  }
}
