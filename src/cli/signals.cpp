#include "cli/signals.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <csignal>

namespace rvc::cli {
namespace {
// Lock-free atomics are safe in a signal handler and between threads (the
// results store's writer asks stop_signals() while the main thread stops).
std::atomic<int> g_stops{0};
std::atomic<bool> g_stats{false};
std::atomic<int> g_input{-1};     // fd that ends at a stop signal
std::atomic<int> g_dev_null{-1};  // what takes its place

extern "C" void on_stop(int) {
  g_stops.fetch_add(1);
  const int fd = g_input.load(), null_fd = g_dev_null.load();
  if (fd >= 0 && null_fd >= 0) ::dup2(null_fd, fd);  // async-signal-safe
}
extern "C" void on_stats(int) { g_stats = true; }

void handle(int signal, void (*handler)(int)) {
  struct sigaction action {};
  action.sa_handler = handler;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // reads and writes go on; the loops ask stop_requested()
  ::sigaction(signal, &action, nullptr);
}
}  // namespace

void install_stop_signals() {
  handle(SIGINT, on_stop);
  handle(SIGTERM, on_stop);
  handle(SIGUSR1, on_stats);
}

bool stop_requested() { return g_stops.load() > 0; }
int stop_signals() { return g_stops.load(); }

bool stats_requested() { return g_stats.exchange(false); }

void end_input_on_stop(int fd) {
  if (g_dev_null.load() < 0) g_dev_null = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  g_input = fd;
  if (fd >= 0 && stop_requested() && g_dev_null.load() >= 0) ::dup2(g_dev_null.load(), fd);  // a signal came first
}

}  // namespace rvc::cli
