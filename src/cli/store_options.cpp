#include "cli/store_options.hpp"

#include <cstdio>

#include "cli/signals.hpp"
#include "cli/option_ranges.hpp"

namespace rvc::cli {

namespace {
std::string& command_line_text() {
  static std::string text;
  return text;
}
}  // namespace

void set_command_line(int argc, char** argv) {
  std::string& text = command_line_text();
  for (int i = 0; i < argc; ++i) {
    if (i) text += ' ';
    text += store::redact_password(argv[i]);  // the command line is stored: no database password in it
  }
}

const std::string& command_line() { return command_line_text(); }

void StoreFlags::add_to(CLI::App& app) {
  app.add_option("--witness", options.witness,
                 "With a database output: input messages stored with each violation (the last N up to it)")
      ->check(in_range(0, kMaxWitness))
      ->capture_default_str();
  app.add_option("--db-wait", options.wait_seconds,
                 "With a database output: seconds the end of the run waits for a database that went away")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  app.add_option("--spool", options.spool,
                 "With a database output: file for results kept while the database is away (default: the SQLite "
                 "file + .spool, or rvc-results.spool); the next run on it writes them first");
}

bool StoreFlags::take_database(std::vector<std::string>& outputs) {
  std::vector<std::string> rest;
  for (auto& uri : outputs) {
    if (!store::is_database_uri(uri)) {
      rest.push_back(std::move(uri));
    } else if (database.empty()) {
      database = uri;
    } else {
      std::fprintf(stderr, "rvc: one results database per run: '%s' and '%s' given\n", database.c_str(), uri.c_str());
      return false;
    }
  }
  outputs = std::move(rest);
  return true;
}

std::unique_ptr<runtime::ResultsOutput> StoreFlags::open() const {
  if (database.empty()) return nullptr;
  store::StoreOptions o = options;
  o.stop_signals = stop_signals;  // a stopped run spools at once; a second signal cuts any wait
  return std::make_unique<runtime::ResultsOutput>(database, o);
}

}  // namespace rvc::cli
