// Results-store flags shared by `rvc check` and `rvc monitor`: a database
// among the --output URIs (sqlite:PATH, postgresql://...), the witness
// window, and what happens while the database is away.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

#include "runtime/results_output.hpp"

namespace rvc::cli {

struct StoreFlags {
  store::StoreOptions options;
  std::string database;  // the database output, if any

  void add_to(CLI::App& app);
  // Takes the database URI out of `outputs` (verdict sinks stay). False, with
  // the reason printed, if more than one database is given.
  bool take_database(std::vector<std::string>& outputs);
  // Opens the database given (null without one). Throws store::DbError.
  std::unique_ptr<runtime::ResultsOutput> open() const;
};

// The command line of this process, as the results store records it.
void set_command_line(int argc, char** argv);
const std::string& command_line();

}  // namespace rvc::cli
