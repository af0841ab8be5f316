// One row for the results store. Every table the store writes (see
// schema.hpp) takes its values from one Row, so the writer thread, the spool
// file and both databases handle a single shape: a run id, up to three texts,
// two numbers and one integer, whose meaning depends on the table.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>

namespace rvc::store {

enum class Table : uint8_t {
  Run,        // run: text0 command line, text1 inputs (JSON array), text2 time model; number0 started_at
  Property,   // run: text0 name, text1 spec
  Verdict,    // run: text0 property; number0 time, number1 wall clock; integer value (0/1); known_at.
              // Changes only.
  Violation,  // run: text0 property, text1 witness (JSON array), text2 explanation (JSON array or "");
              // number0 time, number1 wall clock; known_at
  Counters,   // run: text0 counters (JSON object); number1 wall clock
  RunEnd,     // run: text0 end reason, text1 final counters (JSON); number1 ended_at; integer exit status
};
const char* table_name(Table t);  // "run", "property", ...

struct Row {
  Table table = Table::Verdict;
  std::string run;
  std::string text[3];
  double number[2] = {0, 0};
  int64_t integer = 0;
  // Verdict, Violation: the stream instant the verdict became known (bounded
  // future, issue 29: time + the property's horizon); NaN: at `time` itself
  // (also what a spool line of an older rvc gives).
  double known_at = std::numeric_limits<double>::quiet_NaN();
  double known() const { return known_at == known_at ? known_at : number[0]; }
};

// The spool file holds rows that could not be written yet, one JSON object
// per line. Returns false (and `error`) for a line that is not a spooled row.
std::string to_spool_line(const Row& row);
bool from_spool_line(std::string_view line, Row& row, std::string& error);

}  // namespace rvc::store
