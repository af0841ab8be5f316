// SIGINT/SIGTERM ask every subcommand to stop cleanly (stop reading, check
// what was read, flush, close the results run, say how it ended); a second
// one cuts any wait that is left (a results database that is away: the rest
// goes to the spool at once). SIGUSR1 asks for the counters now.
#pragma once

namespace rvc::cli {

void install_stop_signals();
bool stop_requested();
int stop_signals();      // how many SIGINT/SIGTERM arrived (0, 1, 2, ...)
bool stats_requested();  // true once per SIGUSR1

// A blocking read of `fd` (a trace on stdin, a file) ends at a stop signal:
// the handler puts /dev/null in its place, so the read in progress (restarted
// after the handler) and every later one see the end of the input. Call
// after install_stop_signals(), from the thread that reads: the signal must
// reach that thread (rvc's other threads block it, store/results_store.cpp).
void end_input_on_stop(int fd);

}  // namespace rvc::cli
