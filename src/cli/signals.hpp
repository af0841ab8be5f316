// SIGINT/SIGTERM ask long-running subcommands to stop cleanly (flush, send
// end-of-stream, print counters); SIGUSR1 asks for the counters now.
#pragma once

namespace rvc::cli {

void install_stop_signals();
bool stop_requested();
bool stats_requested();  // true once per SIGUSR1

}  // namespace rvc::cli
