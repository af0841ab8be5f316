// rvc: one binary, thin subcommands that wire endpoints to stages.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <malloc.h>

#include <algorithm>
#include <iterator>
#include <map>
#include <string>
#include <utility>

#include "cli/commands.hpp"
#include "cli/option_rules.hpp"
#include "cli/store_options.hpp"
#include "msg/msg_types.hpp"
#include "io/properties_file.hpp"
#include "spec/spec_error.hpp"

namespace {

// Network subcommands allocate and free a buffer per sample. Past glibc's
// mmap threshold every such buffer is mmap'd and unmapped again, and freed
// heap tops are trimmed back to the kernel, so samples of 64 KiB and more
// cost page faults each (DDS in-process at 64 KiB: 4.3 k samples/s as is,
// 15.5 k with these settings). Keep that memory in the process instead; its
// size is bounded by the largest samples in flight. (`check` keeps glibc's
// defaults: it allocates nothing per event.)
void keep_freed_memory() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace rvc::cli;
  set_command_line(argc, argv);
  CLI::App app{"rvc: runtime verification of pub/sub traffic against past-time temporal logic (Rye syntax)"};
  app.set_version_flag("--version", std::string("rvc ") + RVC_VERSION);
  app.require_subcommand(1);
  // Registering a subcommand builds all its options (CLI11 objects, their
  // help texts): about 5 M instructions for all of them, more than `rvc
  // check` spends on a small file. So when the first argument names a
  // subcommand, only that one is registered; anything else (--help, a typo)
  // registers them all, so help and error messages list every subcommand.
  using Register = Runner (*)(CLI::App&);
  static const std::pair<const char*, Register> kSubcommands[] = {
      {"check", register_check},   {"timescales", register_timescales}, {"monitor", register_monitor},
      {"replay", register_replay}, {"perf", register_perf},             {"bridge", register_bridge},
      {"msg", register_msg},       {"echo", register_echo},             {"sync", register_sync},
      {"hz", register_hz},         {"calls", register_calls},
      {"dashboard", register_dashboard},
      {"bag", register_bag},
#ifdef RVC_HAVE_ZENOH
      {"router", register_router},
      {"topics", register_topics},
#endif
#ifdef RVC_HAVE_DDS
      {"dds-config", register_dds_config},
#endif
  };
  std::map<std::string, Runner> runners;
  const std::string first = argc > 1 ? argv[1] : "";
  const bool one = std::any_of(std::begin(kSubcommands), std::end(kSubcommands),
                               [&](const auto& s) { return first == s.first; });
  for (const auto& [name, add] : kSubcommands)
    if (!one || first == name) runners[name] = add(app);
  one_value_per_flag(app);
  numeric_rule(app);
  // Hidden, for tests: how the command line is read (option_rules.hpp).
  if (first == "--list-repeatable") {
    std::fputs(repeatable_options_json(app).c_str(), stdout);
    return 0;
  }
  if (first == "--list-numeric") {
    std::fputs(numeric_options_json(app).c_str(), stdout);
    return 0;
  }
  bool print_parsed = false;
  app.add_flag("--print-parsed", print_parsed, "Print how the command line was read, run nothing")->group("");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kUsage;
  }
  if (print_parsed) {
    std::printf("%s\n", parsed_json(app).c_str());
    return 0;
  }
  try {
    for (CLI::App* sub : app.get_subcommands()) {
      if (sub->get_name() != "check" && sub->get_name() != "timescales") keep_freed_memory();
      return runners.at(sub->get_name())();
    }
  } catch (const rvc::spec::SpecError& e) {
    std::fprintf(stderr, "rvc: %s\n", e.what());
    return kUsage;
  } catch (const rvc::msg::MsgError& e) {
    std::fprintf(stderr, "rvc: %s\n", e.what());
    return kUsage;
  } catch (const rvc::io::PropertiesError& e) {
    std::fprintf(stderr, "rvc: %s\n", e.what());
    return kUsage;
  } catch (const CLI::Error& e) {
    std::fprintf(stderr, "rvc: %s\n", e.what());
    return kUsage;
  } catch (const rvc::store::DbError& e) {  // a results database that cannot be opened: nothing ran
    std::fprintf(stderr, "rvc: %s\n", e.what());
    return kUsage;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "rvc: %s\n", e.what());
    return kUsage;
  } catch (const std::exception& e) {
    // Anything else happened while running (an output that cannot be written,
    // a transport that failed): a runtime failure, not a usage error.
    std::fprintf(stderr, "rvc: error: %s\n", e.what());
    return kRuntime;
  }
  return kUsage;
}
