// Resource limits for a harness, set in the harness itself so that every run
// has them (scripts/fuzz.sh, a developer's command line): an allocation of
// more than 512 MB, or a process over 2 GB, is a finding (libFuzzer reports
// "out-of-memory (malloc(...))" with the input), not a machine brought to
// its knees. Flags given on the command line come later and win.
#pragma once

#include <vector>

namespace rvc::fuzz {

inline void add_resource_limits(int* argc, char*** argv) {
  static std::vector<char*> args;
  static char rss[] = "-rss_limit_mb=2048";
  static char malloc_limit[] = "-malloc_limit_mb=512";
  args.assign(*argv, *argv + *argc);
  args.insert(args.begin() + 1, {rss, malloc_limit});
  args.push_back(nullptr);
  *argc += 2;
  *argv = args.data();
}

}  // namespace rvc::fuzz
