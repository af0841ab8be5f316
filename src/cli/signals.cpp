#include "cli/signals.hpp"

#include <atomic>
#include <csignal>

namespace rvc::cli {
namespace {
volatile std::sig_atomic_t g_stop = 0;
volatile std::sig_atomic_t g_stats = 0;
extern "C" void on_stop(int) { g_stop = 1; }
extern "C" void on_stats(int) { g_stats = 1; }
}  // namespace

void install_stop_signals() {
  std::signal(SIGINT, on_stop);
  std::signal(SIGTERM, on_stop);
  std::signal(SIGUSR1, on_stats);
}

bool stop_requested() { return g_stop != 0; }

bool stats_requested() {
  if (!g_stats) return false;
  g_stats = 0;
  return true;
}

}  // namespace rvc::cli
