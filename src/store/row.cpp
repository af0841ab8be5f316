#include "store/row.hpp"

#include <simdjson.h>

#include <limits>

#include "io/json_writer.hpp"

namespace rvc::store {

namespace {
constexpr const char* kNames[] = {"run", "property", "verdict", "violation", "counters", "run_end"};
}

const char* table_name(Table t) { return kNames[static_cast<int>(t)]; }

std::string to_spool_line(const Row& row) {
  std::string texts = "[", numbers = "[";
  for (int i = 0; i < 3; ++i) {
    if (i) texts += ',';
    io::append_json_string(texts, row.text[i]);
  }
  for (int i = 0; i < 2; ++i) {
    if (i) numbers += ',';
    io::append_number(numbers, row.number[i]);
  }
  io::JsonObject line;
  line.add("table", table_name(row.table))
      .add("run", row.run)
      .add_raw("text", texts + "]")
      .add_raw("number", numbers + "]")
      .add("integer", row.integer);
  if (row.known_at == row.known_at) {  // bounded future only: older spool readers see the same shape otherwise
    std::string k;
    io::append_number(k, row.known_at);
    line.add_raw("known_at", k);
  }
  return line.str();
}

bool from_spool_line(std::string_view line, Row& row, std::string& error) {
  static thread_local simdjson::dom::parser parser;
  simdjson::dom::element doc;
  if (auto e = parser.parse(line.data(), line.size()).get(doc)) {
    error = std::string("not JSON: ") + simdjson::error_message(e);
    return false;
  }
  std::string_view table, run;
  simdjson::dom::array text, number;
  int64_t integer = 0;
  if (doc["table"].get(table) || doc["run"].get(run) || doc["text"].get(text) || doc["number"].get(number) ||
      doc["integer"].get(integer) || text.size() != 3 || number.size() != 2) {
    error = "not a spooled row (table, run, text[3], number[2], integer)";
    return false;
  }
  bool known = false;
  for (int i = 0; i < 6; ++i)
    if (table == kNames[i]) {
      row.table = static_cast<Table>(i);
      known = true;
    }
  if (!known) {
    error = "unknown table '" + std::string(table) + "'";
    return false;
  }
  row.run = std::string(run);
  int i = 0;
  for (auto t : text) {
    std::string_view s;
    if (t.get(s)) {
      error = "text values must be strings";
      return false;
    }
    row.text[i++] = std::string(s);
  }
  i = 0;
  for (auto n : number) {
    double d = 0;
    if (n.is_null()) d = 0;
    else if (n.get(d)) {
      error = "number values must be numbers";
      return false;
    }
    row.number[i++] = d;
  }
  row.integer = integer;
  double known_at = 0;
  row.known_at = doc["known_at"].get(known_at) ? std::numeric_limits<double>::quiet_NaN() : known_at;
  return true;
}

}  // namespace rvc::store
