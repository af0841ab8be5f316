#include "cli/option_rules.hpp"

#include <functional>
#include <vector>

#include "io/json_writer.hpp"

namespace rvc::cli {
namespace {

std::vector<CLI::App*> subcommands_of(const CLI::App& app) {
  return const_cast<CLI::App&>(app).get_subcommands([](CLI::App*) { return true; });
}

bool repeatable(const CLI::Option& opt) {
  return opt.nonpositional() && opt.get_expected_max() >= CLI::detail::expected_max_vector_size;
}

// How the option is written on a command line: its first long name, else its
// short one, else (a positional) its name.
std::string written_name(const CLI::Option& opt) {
  if (!opt.get_lnames().empty()) return "--" + opt.get_lnames().front();
  if (!opt.get_snames().empty()) return "-" + opt.get_snames().front();
  return opt.get_name(true);
}

std::string string_array(const std::vector<std::string>& items) {
  std::string out = "[";
  for (size_t i = 0; i < items.size(); ++i) {
    if (i) out += ',';
    io::append_json_string(out, items[i]);
  }
  return out + "]";
}

void list_repeatable(const CLI::App& app, const std::string& path, std::string& out) {
  const auto subs = subcommands_of(app);
  if (!path.empty() && subs.empty()) {  // a subcommand that runs (not a group such as `msg`)
    std::vector<std::string> options, positionals, required;
    for (const CLI::Option* opt : app.get_options()) {
      if (repeatable(*opt)) options.push_back(written_name(*opt));
      if (!opt->nonpositional()) positionals.push_back(opt->get_name(true));
      if (opt->nonpositional() && opt->get_required()) required.push_back(written_name(*opt));
    }
    out += io::JsonObject()
               .add("command", path)
               .add_raw("repeatable", string_array(options))
               .add_raw("positionals", string_array(positionals))
               .add_raw("required", string_array(required))
               .str();
    out += '\n';
  }
  for (const CLI::App* sub : subs) list_repeatable(*sub, path.empty() ? sub->get_name() : path + " " + sub->get_name(), out);
}

}  // namespace

void one_value_per_flag(CLI::App& app) {
  for (CLI::Option* opt : app.get_options({}))
    if (repeatable(*opt)) opt->allow_extra_args(false);
  for (CLI::App* sub : subcommands_of(app)) one_value_per_flag(*sub);
}

std::string parsed_json(const CLI::App& app) {
  const CLI::App* leaf = &app;
  std::string path;
  for (;;) {
    const auto chosen = leaf->get_subcommands();
    if (chosen.empty()) break;
    leaf = chosen.front();
    path += (path.empty() ? "" : " ") + leaf->get_name();
  }
  io::JsonObject options;
  for (const CLI::Option* opt : leaf->get_options())
    if (opt->count() > 0) options.add_raw(written_name(*opt), string_array(opt->results()));
  return io::JsonObject().add("command", path).add("options", options).str();
}

std::string repeatable_options_json(const CLI::App& app) {
  std::string out;
  list_repeatable(app, "", out);
  return out;
}

}  // namespace rvc::cli
