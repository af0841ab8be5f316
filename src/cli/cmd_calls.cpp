// rvc calls: ROS 2 service introspection events (JSON lines of a
// pkg/srv/Name_Event, as `rvc echo --type` or `rvc msg decode` print them)
// to one JSON line per service call, request and response paired by
// info.client_gid + info.sequence_number (src/io/service_calls.hpp), so that a
// property can read each call:
//   rvc echo dds:/add/_service_event --type example_interfaces/srv/AddTwoInts_Event \
//     | rvc calls --service-timeout 0.5 \
//     | rvc check --dense --spec 'historically({answered} and {latency <= 0.1})'
// The clock that decides "unanswered" is the events' stamps; with --wall also
// the system clock (live input, nodes on wall time), so a request that is
// never answered is reported at its deadline even if no other event comes.
#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "io/service_calls.hpp"

namespace rvc::cli {
namespace {

struct CallsCommand {
  std::string input = "-";
  double timeout = 1.0;
  bool wall = false;

  static double wall_now() {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  }

  int run() {
    int fd = 0;
    if (input != "-") {
      fd = ::open(input.c_str(), O_RDONLY | O_CLOEXEC);
      if (fd < 0) {
        std::fprintf(stderr, "rvc calls: cannot read '%s': %s\n", input.c_str(), std::strerror(errno));
        return kUsage;
      }
    }
    bool write_failed = false;
    io::ServiceCalls calls(timeout, [&](const std::string& line) {
      if (std::fwrite(line.data(), 1, line.size(), stdout) != line.size() || std::fputc('\n', stdout) == EOF ||
          std::fflush(stdout) != 0)
        write_failed = true;
    });
    std::string buffer, error;
    uint64_t line_no = 0;
    char chunk[1 << 16];
    bool eof = false;
    while (!eof && !write_failed) {
      if (wall) {  // wait for input at most until the next deadline, by the system clock
        const double deadline = calls.next_deadline();
        int wait_ms = -1;
        if (std::isfinite(deadline)) wait_ms = int(std::clamp((deadline - wall_now()) * 1000.0 + 1, 0.0, 60000.0));
        pollfd p{fd, POLLIN, 0};
        int r = ::poll(&p, 1, wait_ms);
        if (r == 0 || (r < 0 && errno == EINTR)) {
          calls.advance(wall_now());
          continue;
        }
      }
      ssize_t n = ::read(fd, chunk, sizeof chunk);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        eof = true;
        if (!buffer.empty()) buffer.push_back('\n');
      } else {
        buffer.append(chunk, size_t(n));
      }
      size_t start = 0;
      for (size_t nl; (nl = buffer.find('\n', start)) != std::string::npos; start = nl + 1) {
        std::string_view line(buffer.data() + start, nl - start);
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (line.find_first_not_of(" \t") == std::string_view::npos) continue;
        if (!calls.feed(line, error) && calls.counts().rejected <= 100)
          std::fprintf(stderr, "rvc calls: line %llu: %s (skipped)\n", static_cast<unsigned long long>(line_no),
                       error.c_str());
      }
      buffer.erase(0, start);
      if (wall) calls.advance(wall_now());
    }
    if (fd != 0) ::close(fd);
    if (wall) calls.advance(wall_now());
    calls.finish();
    const auto& c = calls.counts();
    std::fprintf(stderr,
                 "rvc calls: %llu events: %llu calls (%llu answered, %llu unanswered after %gs), %llu still within "
                 "their timeout at the end, %llu duplicate events of a call, %llu responses to no request seen, "
                 "%llu rejected\n",
                 (unsigned long long)c.events, (unsigned long long)c.requests, (unsigned long long)c.answered,
                 (unsigned long long)c.unanswered, timeout, (unsigned long long)c.pending,
                 (unsigned long long)c.duplicates, (unsigned long long)c.orphans, (unsigned long long)c.rejected);
    if (write_failed) {
      std::fprintf(stderr, "rvc calls: cannot write the output\n");
      return kRuntime;
    }
    if (c.answered + c.unanswered == 0) std::fprintf(stderr, "rvc calls: no call was made from the input\n");
    return c.rejected || c.answered + c.unanswered == 0 ? kBadInput : kOk;
  }
};

}  // namespace

Runner register_calls(CLI::App& app) {
  auto cmd = std::make_shared<CallsCommand>();
  auto* sub = app.add_subcommand(
      "calls", "ROS 2 service events (JSON lines of pkg/srv/Name_Event) to one JSON line per call (docs/services.md)");
  sub->add_option("input", cmd->input, "Input file of JSON lines (default: stdin)");
  sub->add_option("--service-timeout", cmd->timeout,
                  "Seconds after its request a call with no response is made as answered:false (default 1)")
      ->check(above_up_to(0, kMaxSeconds, "seconds"));
  sub->add_flag("--wall", cmd->wall,
                "Live input: the system clock also moves time (the events' stamps are wall-clock ROS time), so an "
                "unanswered request is reported at its deadline without waiting for the next event");
  return [cmd]() { return cmd->run(); };
}

}  // namespace rvc::cli
