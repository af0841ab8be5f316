#include "store/schema.hpp"

#include <cmath>

#include "io/json_writer.hpp"

namespace rvc::store {

std::vector<std::string> schema_statements(Dialect dialect) {
  // Growing ids: the dashboard follows new rows by id.
  const std::string id = dialect == Dialect::Sqlite ? "id INTEGER PRIMARY KEY AUTOINCREMENT"
                                                    : "id BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY";
  const std::string real = "DOUBLE PRECISION";
  return {
      "CREATE TABLE IF NOT EXISTS runs (run TEXT PRIMARY KEY, command TEXT, inputs TEXT, time_model TEXT, "
      "started_at " + real + ", ended_at " + real + ", exit_status INTEGER, end_reason TEXT, counters TEXT)",
      "CREATE TABLE IF NOT EXISTS properties (run TEXT NOT NULL, name TEXT NOT NULL, spec TEXT, "
      "PRIMARY KEY (run, name))",
      "CREATE TABLE IF NOT EXISTS verdicts (" + id + ", run TEXT NOT NULL, property TEXT NOT NULL, time " + real +
          ", value INTEGER, wall " + real + ", known_at " + real + ")",
      "CREATE INDEX IF NOT EXISTS verdicts_by_run ON verdicts (run, property, id)",
      "CREATE TABLE IF NOT EXISTS violations (" + id + ", run TEXT NOT NULL, property TEXT NOT NULL, time " + real +
          ", wall " + real + ", witness TEXT, explanation TEXT, known_at " + real + ")",
      "CREATE INDEX IF NOT EXISTS violations_by_run ON violations (run, id)",
      "CREATE TABLE IF NOT EXISTS counters (" + id + ", run TEXT NOT NULL, wall " + real + ", counters TEXT)",
      "CREATE INDEX IF NOT EXISTS counters_by_run ON counters (run, id)",
  };
}

// Columns newer than the tables: added to an older database when a run
// writes to it (its rows keep NULL there: known_at NULL is "at time").
std::vector<AddedColumn> added_columns() {
  return {{"violations", "explanation", "TEXT"},
          {"verdicts", "known_at", "DOUBLE PRECISION"},
          {"violations", "known_at", "DOUBLE PRECISION"}};
}

const char* insert_statement(Table table) {
  switch (table) {
    case Table::Run:
      return "INSERT INTO runs (run, command, inputs, time_model, started_at) VALUES (?, ?, ?, ?, ?) "
             "ON CONFLICT DO NOTHING";
    case Table::Property:
      return "INSERT INTO properties (run, name, spec) VALUES (?, ?, ?) ON CONFLICT DO NOTHING";
    case Table::Verdict:
      return "INSERT INTO verdicts (run, property, time, value, wall, known_at) VALUES (?, ?, ?, ?, ?, ?)";
    case Table::Violation:
      return "INSERT INTO violations (run, property, time, wall, witness, explanation, known_at) "
             "VALUES (?, ?, ?, ?, ?, ?, ?)";
    case Table::Counters:
      return "INSERT INTO counters (run, wall, counters) VALUES (?, ?, ?)";
    case Table::RunEnd:
      return "UPDATE runs SET end_reason = ?, counters = ?, ended_at = ?, exit_status = ? WHERE run = ?";
  }
  return "";
}

namespace {
// Shortest text that reads back to the same double (also what verdict lines use).
std::string num(double v) {
  // PostgreSQL reads these spellings for double precision (JSON's null would be refused).
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
  std::string out;
  io::append_number(out, v);
  return out;
}
}  // namespace

std::vector<std::string> insert_values(const Row& r) {
  switch (r.table) {
    case Table::Run: return {r.run, r.text[0], r.text[1], r.text[2], num(r.number[0])};
    case Table::Property: return {r.run, r.text[0], r.text[1]};
    case Table::Verdict:
      return {r.run, r.text[0], num(r.number[0]), std::to_string(r.integer), num(r.number[1]), num(r.known())};
    case Table::Violation:
      return {r.run, r.text[0], num(r.number[0]), num(r.number[1]), r.text[1], r.text[2], num(r.known())};
    case Table::Counters: return {r.run, num(r.number[1]), r.text[0]};
    case Table::RunEnd: return {r.text[0], r.text[1], num(r.number[1]), std::to_string(r.integer), r.run};
  }
  return {};
}

}  // namespace rvc::store
