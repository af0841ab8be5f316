// rvc timescales: generate a Timescales benchmark trace and its formula.
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "tools/timescales.hpp"
#include "transport/output_file.hpp"

namespace rvc::cli {
namespace {

struct TimescalesCommand {
  tools::TimescalesOptions opts;
  std::string output = "-";
  std::string properties_out;
  bool formula_only = false;
  bool intended = false;

  int run() {
    if (!tools::is_timescales_family(opts.family)) {
      std::string all;
      for (const auto& f : tools::timescales_families()) all += " " + f;
      std::fprintf(stderr, "rvc: unknown Timescales family '%s'; choose one of:%s\n", opts.family.c_str(), all.c_str());
      return kUsage;
    }
    if (opts.ubound < 1 || (opts.lbound >= 0 && opts.lbound > opts.ubound)) {
      std::fprintf(stderr, "rvc: need 1 <= ubound and 0 <= lbound <= ubound\n");
      return kUsage;
    }
    std::string formula = tools::timescales_formula(opts.family, tools::effective_lbound(opts), opts.ubound, intended);
    if (formula_only) {
      std::printf("%s\n", formula.c_str());
      return kOk;
    }
    if (!properties_out.empty()) {
      std::FILE* f = nullptr;
      try {
        f = transport::open_output_file(properties_out, "--properties-out");
      } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "rvc: %s\n", e.what());
        return kUsage;
      }
      std::fprintf(f, "properties:\n  - name: %s%lld\n    spec: \"%s\"\n", opts.family.c_str(),
                   static_cast<long long>(opts.ubound), formula.c_str());
      std::fclose(f);
    }
    std::FILE* out = stdout;
    if (output != "-") {
      try {
        out = transport::open_output_file(output, "--output");
      } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "rvc: %s\n", e.what());
        return kUsage;
      }
    }
    tools::generate_timescales(opts, out);
    if (out != stdout) std::fclose(out);
    else std::fflush(stdout);
    return kOk;
  }
};

}  // namespace

Runner register_timescales(CLI::App& app) {
  auto cmd = std::make_shared<TimescalesCommand>();
  CLI::App* sub = app.add_subcommand("timescales", "Generate a Timescales benchmark trace (JSON lines) and its formula");
  sub->add_option("family", cmd->opts.family,
                  "AbsentAQ AbsentBQR AbsentBR AlwaysAQ AlwaysBQR AlwaysBR RecurBQR RecurGLB RespondBQR RespondGLB")
      ->required();
  sub->add_option("--lbound", cmd->opts.lbound, "Lower time bound (default: 30% of ubound, as published)")
      ->check(in_range(0, 1e9, "steps"));
  sub->add_option("--ubound", cmd->opts.ubound, "Upper time bound")
      ->check(in_range(1, 1e9, "steps"))
      ->capture_default_str();
  sub->add_option("--duration", cmd->opts.duration, "Number of steps (lines)")
      ->check(in_range(0, kMaxCount, "lines"))
      ->capture_default_str();
  sub->add_option("--seed", cmd->opts.seed, "Random seed: same seed, same bytes")
      ->check(in_range(0, kMaxCount))
      ->capture_default_str();
  sub->add_option("--output,-o", cmd->output, "Trace file (- for stdout)")->capture_default_str();
  sub->add_option("--properties-out", cmd->properties_out, "Also write the formula as a properties file");
  sub->add_flag("--formula", cmd->formula_only, "Print only the formula and exit");
  sub->add_flag("--intended", cmd->intended, "AbsentBQR: historically over the whole implication (as meant)");
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
