#include "cli/option_rules.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <vector>

#include "cli/option_ranges.hpp"
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

// CLI11's name of the option's value type: the part of get_type_name()
// before the validators' descriptions ("UINT:in 1 to 16777216 frames").
std::string base_type(const CLI::Option& opt) {
  const std::string t = opt.get_type_name();
  return t.substr(0, t.find(':'));
}

bool integer_type(const std::string& t) { return t == "INT" || t == "UINT"; }

bool numeric(const CLI::Option& opt) {
  const std::string t = base_type(opt);
  return opt.get_type_size() != 0 && (integer_type(t) || t == "FLOAT");
}

// The range in_range() declared on the option: its validator's name holds
// "lo hi", its description "in 1 to 16777216 frames".
const CLI::Validator* declared_range(const CLI::Option& opt, double& lo, double& hi, bool* above = nullptr) {
  auto& o = const_cast<CLI::Option&>(opt);
  for (int i = 0;; ++i) {
    const CLI::Validator* v = nullptr;
    try {
      v = o.get_validator(i);
    } catch (const CLI::OptionNotFound&) {
      return nullptr;
    }
    const std::string& name = v->get_name();
    const size_t n = std::strlen(kRangeValidator);
    if (name.compare(0, n, kRangeValidator) == 0 && std::sscanf(name.c_str() + n, "%lf %lf", &lo, &hi) == 2) {
      if (above) *above = name.size() > 6 && name.compare(name.size() - 6, 6, " above") == 0;
      return v;
    }
  }
}

// Before the range: an integer option takes a whole number, written as CLI11's
// integer conversion reads it ("1e3" -> "1000"); without a declared range,
// any option takes only a finite number.
CLI::Validator number_check(bool integer, bool ranged, const std::string& allowed, double lo, double hi) {
  const std::string tail = allowed.empty() ? "" : " (allowed: " + allowed + ")";
  CLI::Validator v(
      [integer, ranged, tail, lo, hi](std::string& text) -> std::string {
        double d = 0;
        if (!CLI::detail::lexical_cast(text, d)) return ranged ? "" : "'" + text + "' is not a number" + tail;
        if (ranged && !integer) return {};  // NaN, and infinity unless the range holds it: the range says so
        if (!std::isfinite(d)) return ranged ? "" : "'" + text + "' is not a finite number" + tail;
        if (!integer) return {};
        if (d != std::floor(d)) return "'" + text + "' is not a whole number" + tail;
        // Digits are CLI11's to convert (exactly: a 64-bit seed is no double);
        // "1e3", "+5", "5.0" are rewritten as the whole number they are.
        const size_t digits = text.find_first_not_of("0123456789", text[0] == '-' ? 1 : 0);
        if ((digits != std::string::npos || text == "-") && (!ranged || (d >= lo && d <= hi))) {  // (else the range names it as written)
          char buf[48];
          std::snprintf(buf, sizeof buf, "%.0f", d);
          text = buf;
        }
        return {};
      },
      "");
  v.name("rvc-number");
  return v;
}

void apply_numeric_rule(CLI::App& app) {
  for (CLI::Option* opt : app.get_options({})) {
    if (!numeric(*opt)) continue;
    double lo = 0, hi = 0;
    const CLI::Validator* range = declared_range(*opt, lo, hi);
    const std::string allowed = range ? range->get_description().substr(3) : "";  // after "in "
    // transform(), not check(): it may rewrite the text ("1e3"), and runs before the range.
    opt->transform(number_check(integer_type(base_type(*opt)), range != nullptr, allowed, lo, hi));
  }
  for (CLI::App* sub : subcommands_of(app)) apply_numeric_rule(*sub);
}

std::string json_number(double v) {
  if (std::isinf(v)) return v > 0 ? "\"infinity\"" : "\"-infinity\"";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

void list_numeric(const CLI::App& app, const std::string& path, std::string& out) {
  const auto subs = subcommands_of(app);
  if (!path.empty() && subs.empty()) {
    std::vector<std::string> positionals, required;
    for (const CLI::Option* opt : app.get_options()) {
      if (!opt->nonpositional()) positionals.push_back(opt->get_name(true));
      if (opt->nonpositional() && opt->get_required()) required.push_back(written_name(*opt));
    }
    for (const CLI::Option* opt : app.get_options()) {
      if (!numeric(*opt)) continue;
      double lo = 0, hi = 0;
      bool above = false;
      const CLI::Validator* range = declared_range(*opt, lo, hi, &above);
      io::JsonObject o;
      o.add("command", path).add("option", written_name(*opt)).add("positional", !opt->nonpositional());
      o.add("integer", integer_type(base_type(*opt)));
      o.add_raw("range", range ? "[" + json_number(lo) + "," + json_number(hi) + "]" : "null");
      o.add("above", above);  // the range is open at its low end (more than lo)
      o.add("default", opt->get_default_str());
      o.add_raw("positionals", string_array(positionals)).add_raw("required", string_array(required));
      out += o.str();
      out += '\n';
    }
  }
  for (const CLI::App* sub : subs) list_numeric(*sub, path.empty() ? sub->get_name() : path + " " + sub->get_name(), out);
}

}  // namespace

void numeric_rule(CLI::App& app) { apply_numeric_rule(app); }

std::string numeric_options_json(const CLI::App& app) {
  std::string out;
  list_numeric(app, "", out);
  return out;
}

CLI::Validator field_name() {
  CLI::Validator v(
      [](std::string& text) -> std::string {
        if (text.empty()) return "an empty field name (write a field path, e.g. id or vehicle.id)";
        return {};
      },
      "");
  v.name("rvc-field-name");
  return v;
}

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
