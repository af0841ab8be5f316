// Rules every subcommand's options follow, applied once to the whole command
// tree after registration (main.cpp), so an option added later cannot miss them.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace rvc::cli {

// A repeatable option (one that collects into a container) takes exactly one
// value per flag: `--topic /a bag.mcap` leaves bag.mcap to the positional, and
// `--topic /a --topic /b` gives two. CLI11 would otherwise let the option take
// every word up to the next flag, so the meaning of a command line would
// depend on the order of its arguments.
void one_value_per_flag(CLI::App& app);

// The chosen subcommand (its path, "msg decode") and every option given, with
// the values CLI11 assigned to it, as one JSON object: the hidden
// `rvc --print-parsed SUB ...` prints it instead of running anything, so tests
// can see how a command line was read (tests/cli/test_option_order.py).
std::string parsed_json(const CLI::App& app);

// Every subcommand and its repeatable options, one JSON object per line
// ({"command":"msg decode","option":"--msg-path","positionals":["input"]}): the
// hidden `rvc --list-repeatable` prints them, so a test covers each one,
// including options added after it was written.
std::string repeatable_options_json(const CLI::App& app);

// Every numeric option (an integer or floating-point value, positionals too)
// goes through one rule: the range it declares with in_range()
// (option_ranges.hpp), NaN, infinities, empty and non-numbers refused with
// the option and the range named; an integer option also refuses a fraction
// ("1.5") and reads "1e3" as 1000, so CLI11's own conversion errors are never
// what a user sees. An option that declares no range is still refused NaN,
// infinities and empty text, and the listing below shows it without a range
// (tests/cli/test_numeric_options.py fails on it). Applied once to the tree
// after registration (main.cpp), like one_value_per_flag.
void numeric_rule(CLI::App& app);

// Every subcommand's numeric options, one JSON object per line
// ({"command":"monitor","option":"--queue","integer":true,"range":[1,16777216],
// "default":"...","positionals":[...],"required":[...]}; "range":null when
// none is declared): the hidden `rvc --list-numeric` prints them.
std::string numeric_options_json(const CLI::App& app);

// A string option that names a field (--instances-by, --time-field...): an
// empty name is refused ("--instances-by: an empty field name ...").
CLI::Validator field_name();

}  // namespace rvc::cli
