// The results schema, one for both databases (docs/results.md explains it):
//
//   runs        one row per monitor run: command line, inputs, time model,
//               start and end (wall clock, s), exit status, why it ended,
//               final counters (JSON)
//   properties  the properties a run checked, with their specs
//   verdicts    verdict changes: a property's first verdict and every change
//               after it (the time is the stream's: step or seconds)
//   violations  each start of a violation with its witness window, the last
//               N input messages up to the violating one (JSON array), and
//               with --explain why it is false (JSON array of sentences; ''
//               without)
//   counters    periodic counter snapshots (received, checked, lost, ...)
//
// Ids in verdicts/violations/counters only grow, so a reader (the dashboard)
// follows a table with "WHERE id > last seen".
#pragma once

#include <string>
#include <vector>

#include "store/row.hpp"

namespace rvc::store {

enum class Dialect { Sqlite, Postgres };

// CREATE TABLE/INDEX IF NOT EXISTS statements, in order.
std::vector<std::string> schema_statements(Dialect dialect);

// Columns added after a table was first released: a database made by an
// older rvc gains them (ALTER TABLE ... ADD COLUMN) before rows are written.
struct AddedColumn {
  const char* table;
  const char* column;
  const char* type;
};
std::vector<AddedColumn> added_columns();

// The statement that stores a row of `table`, with '?' placeholders, and the
// row's values in placeholder order ("" never stands for NULL here: every
// value is written). Run and Property rows are idempotent (ON CONFLICT DO
// NOTHING), so replaying a spool twice does not duplicate them.
const char* insert_statement(Table table);
std::vector<std::string> insert_values(const Row& row);

}  // namespace rvc::store
