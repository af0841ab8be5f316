// rvc check: run properties over a JSON-lines trace (file or stdin), print
// verdicts as JSON lines, and exit non-zero if a property was violated.
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <memory>

#include "cli/check_options.hpp"
#include "cli/commands.hpp"
#include "io/verdict_writer.hpp"

namespace rvc::cli {
namespace {

struct CheckCommand {
  CheckOptions check;
  std::string input;
  std::string output = "-";
  bool summary = false;

  int run() {
    auto properties = check.properties();
    std::string path = input.rfind("file:", 0) == 0 ? input.substr(5) : input;
    int fd = 0;
    if (path != "-") {
      fd = ::open(path.c_str(), O_RDONLY);
      if (fd < 0) {
        std::fprintf(stderr, "rvc: cannot open trace '%s'\n", path.c_str());
        return kUsage;
      }
    }
    std::FILE* out = stdout;
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> owned(nullptr, &std::fclose);
    if (output != "-") {
      std::string opath = output.rfind("file:", 0) == 0 ? output.substr(5) : output;
      owned.reset(std::fopen(opath.c_str(), "w"));
      if (!owned) {
        std::fprintf(stderr, "rvc: cannot write '%s'\n", opath.c_str());
        return kUsage;
      }
      out = owned.get();
    }
    // Reading stdin interactively: show each verdict as soon as it is known.
    io::VerdictWriter writer(out, !check.dense, path == "-" && isatty(0));
    Pipeline pipeline(properties, check.pipeline_options(),
                      [&](const engine::Verdict& v) { writer.write(v.time, v.property, v.value); });
    io::ReaderOptions ropts;
    ropts.max_line_bytes = check.max_message_size;
    std::string error;
    bool ok = io::read_jsonl(fd, pipeline, ropts, error);
    if (fd != 0) ::close(fd);
    writer.flush();
    pipeline.finish_report();
    if (!ok) {
      std::fprintf(stderr, "rvc: %s\n", error.c_str());
      return kUsage;
    }
    const auto& s = pipeline.stats();
    if (summary || s.rejected > 0) {
      std::fprintf(stderr, "rvc: %llu messages checked, %llu rejected, %llu warnings; %s\n",
                   static_cast<unsigned long long>(s.accepted), static_cast<unsigned long long>(s.rejected),
                   static_cast<unsigned long long>(s.warnings),
                   pipeline.violated() ? "a property was violated" : "no property was violated");
    }
    if (pipeline.violated()) return kViolated;
    return s.rejected > 0 ? kBadInput : kOk;
  }
};

}  // namespace

Runner register_check(CLI::App& app) {
  auto cmd = std::make_shared<CheckCommand>();
  CLI::App* sub = app.add_subcommand("check", "Check properties over a JSON-lines trace (file or - for stdin)");
  cmd->check.add_to(*sub);
  sub->add_option("trace", cmd->input, "Trace: PATH, file:PATH or - for stdin")->required();
  sub->add_option("--output,-o", cmd->output, "Where verdicts go: PATH, file:PATH or - (stdout)")->capture_default_str();
  sub->add_flag("--summary", cmd->summary, "Print message counts to stderr at the end");
  sub->footer(
      "Exit status: 0 all properties held, 1 a property was violated, 2 usage or spec error, 3 messages were rejected.\n"
      "Example: rvc check --spec 'historically({emergency} -> once[0:1]{hazard_lights})' trace.jsonl");
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
