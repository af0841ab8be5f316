#include "msg/type_registry.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "msg/msg_parser.hpp"

namespace rvc::msg {

// Generated from src/msg/definitions/<pkg>/msg/<Name>.msg (src/msg/CMakeLists.txt).
struct BundledDefinition {
  const char* full_name;
  const char* text;
};
extern const BundledDefinition kBundled[];
extern const size_t kBundledCount;

std::string_view bundled_definition(std::string_view full_name) {
  for (size_t i = 0; i < kBundledCount; ++i)
    if (full_name == kBundled[i].full_name) return kBundled[i].text;
  return {};
}

std::vector<std::string> TypeRegistry::bundled_types() {
  std::vector<std::string> out;
  for (size_t i = 0; i < kBundledCount; ++i) out.emplace_back(kBundled[i].full_name);
  std::sort(out.begin(), out.end());
  return out;
}

TypeRegistry::TypeRegistry() = default;

void TypeRegistry::add_search_path(const std::string& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) throw MsgError("--msg-path " + dir + ": not a folder");
  search_paths_.push_back(dir);
}

void TypeRegistry::add_definition(const std::string& type_name, std::string text, const std::string& source) {
  std::string pkg, name;
  if (!split_type_name(type_name, pkg, name)) throw MsgError(source + ": not a message type name: '" + type_name + "'");
  added_[pkg + "/msg/" + name] = {std::move(text), source};
}

void TypeRegistry::add_concatenated(const std::string& type_name, std::string_view text, const std::string& source) {
  // Sections are separated by a line of '=' (80 of them in rosbag2 and MCAP files).
  std::string current_type = type_name, current;
  size_t start = 0;
  auto flush = [&] { add_definition(current_type, current, source + " (" + current_type + ")"); };
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    bool separator = line.size() >= 3 && line.find_first_not_of('=') == std::string_view::npos;
    if (separator) {
      flush();
      current.clear();
      current_type.clear();
    } else if (current_type.empty() && line.substr(0, 4) == "MSG:") {
      std::string_view n = line.substr(4);
      while (!n.empty() && n.front() == ' ') n.remove_prefix(1);
      while (!n.empty() && n.back() == ' ') n.remove_suffix(1);
      current_type = std::string(n);
    } else {
      current.append(line).push_back('\n');
    }
    start = end + 1;
  }
  if (!current_type.empty()) flush();
}

bool TypeRegistry::find_text(const std::string& package, const std::string& name, std::string& text,
                             std::string& source) const {
  auto added = added_.find(package + "/msg/" + name);
  if (added != added_.end()) {
    text = added->second.first;
    source = added->second.second;
    return true;
  }
  namespace fs = std::filesystem;
  for (const auto& dir : search_paths_) {
    for (fs::path p : {fs::path(dir) / package / "msg" / (name + ".msg"),
                       fs::path(dir) / "share" / package / "msg" / (name + ".msg"),
                       fs::path(dir) / package / (name + ".msg"), fs::path(dir) / (name + ".msg")}) {
      std::error_code ec;
      if (!fs::is_regular_file(p, ec)) continue;
      std::ifstream in(p, std::ios::binary);
      std::stringstream ss;
      ss << in.rdbuf();
      if (!in.good() && !in.eof()) throw MsgError(p.string() + ": cannot be read");
      text = ss.str();
      source = p.string();
      return true;
    }
  }
  std::string_view bundled = bundled_definition(package + "/msg/" + name);
  if (bundled.data()) {  // std_msgs/Empty is bundled with an empty text
    text = std::string(bundled);
    source = "bundled " + package + "/msg/" + name + ".msg";
    return true;
  }
  return false;
}

const MessageType& TypeRegistry::resolve(std::string_view type_name) {
  std::string pkg, name;
  if (!split_type_name(type_name, pkg, name))
    throw MsgError("not a message type name: '" + std::string(type_name) +
                   "' (expected pkg/msg/Name, e.g. geometry_msgs/msg/Twist)");
  return load(pkg, name, 0);
}

const MessageType& TypeRegistry::load(const std::string& package, const std::string& name, int depth) {
  const std::string full = package + "/msg/" + name;
  auto it = types_.find(full);
  if (it != types_.end()) {
    if (!it->second) throw MsgError("message type " + full + " contains itself");
    return *it->second;
  }
  if (depth > 64) throw MsgError("message types nested deeper than 64 levels at " + full);
  std::string text, source;
  if (!find_text(package, name, text, source)) {
    std::string where = search_paths_.empty() ? "no --msg-path given" : "searched --msg-path";
    for (const auto& d : search_paths_) where += " " + d;
    throw MsgError("unknown message type " + full + ": not bundled with rvc, not in a bag schema, " + where);
  }
  auto type = std::make_unique<MessageType>(parse_msg(package, name, text, source));
  types_[full] = nullptr;  // loading: a reference back to it is a cycle
  for (auto& f : type->fields) {
    if (f.type.prim != Prim::Message) continue;
    std::string fp, fn;
    split_type_name(f.type.type_name, fp, fn);
    try {
      f.type.message = &load(fp, fn, depth + 1);
    } catch (const MsgError& e) {
      types_.erase(full);
      throw MsgError(std::string(e.what()) + "\n  used by field '" + f.name + "' of " + full + " (" + source + ":" +
                     std::to_string(f.line) + ")");
    }
  }
  auto& slot = types_[full];
  slot = std::move(type);
  return *slot;
}

}  // namespace rvc::msg
