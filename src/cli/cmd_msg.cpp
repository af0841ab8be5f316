// rvc msg: the ROS 2 message types rvc knows, and CDR <-> JSON for one type.
//   rvc msg list                                  bundled types
//   rvc msg show geometry_msgs/msg/Twist          the definition, nested types expanded
//   rvc msg decode --type T [FILE]                CDR samples (one hex string per line) -> JSON lines
//   rvc msg encode --type T [FILE]                JSON lines -> CDR samples as hex lines
// The same codec serves typed inputs (--type) of check and monitor.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>

#include "cli/commands.hpp"
#include "io/cdr_codec.hpp"
#include "msg/type_registry.hpp"

namespace rvc::cli {
namespace {

struct MsgCommand {
  std::string type;
  std::vector<std::string> msg_paths;
  std::string input = "-";
  bool big_endian = false;

  bool registry(msg::TypeRegistry& reg) {
    try {
      for (const auto& p : msg_paths) reg.add_search_path(p);
      return true;
    } catch (const msg::MsgError& e) {
      std::fprintf(stderr, "rvc: %s\n", e.what());
      return false;
    }
  }

  static void show(const msg::MessageType& t, const std::string& indent, std::string& out) {
    for (const auto& c : t.constants)
      out += indent + msg::prim_name(c.prim) + " " + c.name + "=" + c.text + "\n";
    for (const auto& f : t.fields) {
      out += indent + f.type.to_string() + " " + f.name + (f.default_text.empty() ? "" : " " + f.default_text) + "\n";
      if (f.type.message) show(*f.type.message, indent + "\t", out);
    }
  }

  int run_show() {
    msg::TypeRegistry reg;
    if (!registry(reg)) return kUsage;
    try {
      const auto& t = reg.resolve(type);
      std::string out = "# " + t.full_name() + " (" + t.source + ")\n";
      show(t, "", out);
      std::fputs(out.c_str(), stdout);
      return kOk;
    } catch (const msg::MsgError& e) {
      std::fprintf(stderr, "rvc: %s\n", e.what());
      return kUsage;
    }
  }

  // Runs `convert` on every line of the input; returns the exit status.
  template <typename Convert>
  int each_line(Convert convert) {
    std::unique_ptr<std::ifstream> file;
    std::istream* in = &std::cin;
    if (input != "-") {
      file = std::make_unique<std::ifstream>(input, std::ios::binary);
      if (!*file) {
        std::fprintf(stderr, "rvc: cannot read '%s'\n", input.c_str());
        return kUsage;
      }
      in = file.get();
    }
    std::string line, out, error;
    uint64_t line_no = 0, rejected = 0;
    while (std::getline(*in, line)) {
      ++line_no;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.find_first_not_of(" \t") == std::string::npos) continue;
      out.clear();
      if (convert(line, out, error)) {
        out += '\n';
        if (std::fwrite(out.data(), 1, out.size(), stdout) != out.size()) {
          std::fprintf(stderr, "rvc: cannot write the output\n");
          return kRuntime;
        }
      } else {
        ++rejected;
        std::fprintf(stderr, "rvc: line %llu: %s (message skipped)\n", static_cast<unsigned long long>(line_no),
                     error.c_str());
      }
    }
    if (std::fflush(stdout) != 0) return kRuntime;
    return rejected ? kBadInput : kOk;
  }

  int run_decode() {
    msg::TypeRegistry reg;
    if (!registry(reg)) return kUsage;
    const msg::MessageType* t;
    try {
      t = &reg.resolve(type);
    } catch (const msg::MsgError& e) {
      std::fprintf(stderr, "rvc: %s\n", e.what());
      return kUsage;
    }
    std::string bytes;
    return each_line([&](const std::string& hex, std::string& out, std::string& error) {
      bytes.clear();
      std::string_view h = hex;
      while (!h.empty() && (h.back() == ' ' || h.back() == '\t')) h.remove_suffix(1);
      auto nibble = [](char c) -> int {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
      };
      for (size_t i = 0; i < h.size(); i += 2) {
        int hi = nibble(h[i]), lo = i + 1 < h.size() ? nibble(h[i + 1]) : -1;
        if (hi < 0 || lo < 0) {
          error = "column " + std::to_string(i + 1) + ": not a hex byte";
          return false;
        }
        bytes.push_back(static_cast<char>(hi * 16 + lo));
      }
      io::CdrError e;
      if (!io::cdr_to_json(*t, bytes, out, e)) {
        error = e.to_string();
        return false;
      }
      return true;
    });
  }

  int run_encode() {
    msg::TypeRegistry reg;
    if (!registry(reg)) return kUsage;
    const msg::MessageType* t;
    try {
      t = &reg.resolve(type);
    } catch (const msg::MsgError& e) {
      std::fprintf(stderr, "rvc: %s\n", e.what());
      return kUsage;
    }
    std::string sample;
    io::CdrWriteOptions opts;
    opts.big_endian = big_endian;
    return each_line([&](const std::string& json, std::string& out, std::string& error) {
      if (!io::json_to_cdr(*t, json, sample, error, opts)) return false;
      static const char* digits = "0123456789abcdef";
      for (unsigned char c : sample) {
        out += digits[c >> 4];
        out += digits[c & 15];
      }
      return true;
    });
  }
};

}  // namespace

Runner register_msg(CLI::App& app) {
  auto cmd = std::make_shared<MsgCommand>();
  auto* sub = app.add_subcommand("msg", "ROS 2 message types: list, show, CDR <-> JSON");
  sub->require_subcommand(1);
  auto* list = sub->add_subcommand("list", "Message types bundled with rvc");
  auto* show = sub->add_subcommand("show", "A type's definition, nested types expanded");
  show->add_option("type", cmd->type, "pkg/msg/Name")->required();
  auto* decode = sub->add_subcommand("decode", "CDR samples, one hex string per line, to JSON lines");
  auto* encode = sub->add_subcommand("encode", "JSON lines to CDR samples, one hex string per line");
  for (auto* s : {decode, encode}) {
    s->add_option("--type", cmd->type, "Message type, pkg/msg/Name")->required();
    s->add_option("input", cmd->input, "Input file (default: stdin)");
  }
  encode->add_flag("--big-endian", cmd->big_endian, "Write big-endian CDR (default: little endian)");
  for (auto* s : {show, decode, encode})
    s->add_option("--msg-path", cmd->msg_paths,
                  "Folder of .msg/.idl definitions (a ROS 2 share/ tree or a plain folder), or one .idl file (repeatable)");
  return [cmd, list, show, decode, encode]() -> int {
    if (list->parsed()) {
      for (const auto& t : msg::TypeRegistry::bundled_types()) std::printf("%s\n", t.c_str());
      return kOk;
    }
    if (show->parsed()) return cmd->run_show();
    if (decode->parsed()) return cmd->run_decode();
    if (encode->parsed()) return cmd->run_encode();
    return kUsage;
  };
}

}  // namespace rvc::cli
