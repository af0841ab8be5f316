#include "msg/type_registry.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "msg/idl_parser.hpp"
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
  if (std::filesystem::is_regular_file(dir, ec) && std::filesystem::path(dir).extension() == ".idl") {
    read_idl_file(dir);
    return;
  }
  if (!std::filesystem::is_directory(dir, ec)) throw MsgError("--msg-path " + dir + ": not a folder or an .idl file");
  search_paths_.push_back(dir);
}

namespace {
std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  if (!in || (!in.good() && !in.eof())) throw MsgError(p.string() + ": cannot be read");
  return ss.str();
}
}  // namespace

void TypeRegistry::add_idl(std::string_view text, const std::string& source) {
  for (auto& t : parse_idl(text, source)) {
    std::string key = t.full_name();
    idl_.insert_or_assign(key, std::move(t));
  }
}

void TypeRegistry::read_idl_file(const std::string& path) {
  if (!idl_files_read_.insert(path).second) return;
  add_idl(read_file(path), path);
}

void TypeRegistry::add_concatenated_idl(std::string_view text, const std::string& source) {
  // As ros2msg schemas: sections after a line of '=', each headed "IDL: pkg/msg/Name".
  std::string current, name = "main";
  auto flush = [&] {
    if (current.find_first_not_of(" \t\r\n") != std::string::npos) add_idl(current, source + " (" + name + ")");
    current.clear();
  };
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (line.size() >= 3 && line.find_first_not_of("=\r") == std::string_view::npos) {
      flush();
    } else if (current.find_first_not_of(" \t\r\n") == std::string::npos && line.substr(0, 4) == "IDL:") {
      name = std::string(line.substr(4));
      while (!name.empty() && (name.front() == ' ')) name.erase(0, 1);
    } else {
      current.append(line).push_back('\n');
    }
    start = end + 1;
  }
  flush();
}

void TypeRegistry::scan_idl_files() {
  if (idl_scanned_) return;
  idl_scanned_ = true;
  namespace fs = std::filesystem;
  for (const auto& dir : search_paths_) {
    std::error_code ec;
    for (fs::recursive_directory_iterator it(dir, fs::directory_options::skip_permission_denied, ec), end;
         !ec && it != end; it.increment(ec)) {
      if (it.depth() > 4) it.disable_recursion_pending();
      if (!it->is_regular_file(ec) || it->path().extension() != ".idl") continue;
      try {
        read_idl_file(it->path().string());
      } catch (const MsgError& e) {  // a broken file that may not matter: named if the type is not found
        idl_scan_errors_ += std::string("\n  skipped ") + e.what();
      }
    }
  }
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

TypeRegistry::Found TypeRegistry::find_definition(const std::string& package, const std::string& name,
                                                  std::string& text, std::string& source) {
  auto added = added_.find(package + "/msg/" + name);
  if (added != added_.end()) {
    text = added->second.first;
    source = added->second.second;
    return Found::Msg;
  }
  namespace fs = std::filesystem;
  for (const auto& dir : search_paths_) {
    for (const char* ext : {".msg", ".idl"}) {
      for (fs::path p : {fs::path(dir) / package / "msg" / (name + ext), fs::path(dir) / "share" / package / "msg" / (name + ext),
                         fs::path(dir) / package / (name + ext), fs::path(dir) / (name + ext)}) {
        std::error_code ec;
        if (!fs::is_regular_file(p, ec)) continue;
        if (ext[1] == 'm') {
          text = read_file(p);
          source = p.string();
          return Found::Msg;
        }
        read_idl_file(p.string());
        if (idl_.count(package + "/msg/" + name)) return Found::Idl;
      }
    }
  }
  std::string_view bundled = bundled_definition(package + "/msg/" + name);
  if (bundled.data()) {  // std_msgs/Empty is bundled with an empty text
    text = std::string(bundled);
    source = "bundled " + package + "/msg/" + name + ".msg";
    return Found::Msg;
  }
  return Found::None;
}

const MessageType& TypeRegistry::resolve(std::string_view type_name) {
  const std::string key(type_name);
  if (known(key)) return load(key, 0);
  std::string pkg, name, text, source;
  const bool ros = split_type_name(type_name, pkg, name);
  // "pkg/msg/Name" is always ROS 2; "a::B" may be a ROS 2 pkg::Name or a plain IDL name.
  if (ros && (key.find('/') != std::string::npos || key.find("::msg::") != std::string::npos ||
              known(pkg + "/msg/" + name) || find_definition(pkg, name, text, source) != Found::None))
    return load(pkg + "/msg/" + name, 0);
  scan_idl_files();
  if (known(key)) return load(key, 0);
  if (ros && key.find("::") == std::string::npos) return load(pkg + "/msg/" + name, 0);  // the usual error
  throw MsgError("unknown message type '" + key + "': no .idl file of --msg-path defines it" +
                 (ros ? ", and there is no ROS 2 type " + pkg + "/msg/" + name : std::string()) + idl_scan_errors_);
}

const MessageType& TypeRegistry::load(const std::string& key, int depth) {
  auto it = types_.find(key);
  if (it != types_.end()) {
    if (!it->second) throw MsgError("message type " + key + " contains itself");
    return *it->second;
  }
  if (depth > 64) throw MsgError("message types nested deeper than 64 levels at " + key);
  std::unique_ptr<MessageType> type;
  std::string pkg, name, text, source;
  if (!idl_.count(key) && key.find('/') == std::string::npos) scan_idl_files();  // a plain IDL name
  if (auto idl = idl_.find(key); idl != idl_.end()) {
    type = std::make_unique<MessageType>(idl->second);
  } else if (key.find('/') != std::string::npos && split_type_name(key, pkg, name)) {
    switch (find_definition(pkg, name, text, source)) {
      case Found::Msg: type = std::make_unique<MessageType>(parse_msg(pkg, name, text, source)); break;
      case Found::Idl: type = std::make_unique<MessageType>(idl_.at(key)); break;
      case Found::None: {
        std::string where = search_paths_.empty() ? "no --msg-path given" : "searched --msg-path";
        for (const auto& d : search_paths_) where += " " + d;
        throw MsgError("unknown message type " + key + ": not bundled with rvc, not in a bag schema, " + where);
      }
    }
  } else {
    throw MsgError("unknown message type " + key + ": no .idl file of --msg-path defines it" + idl_scan_errors_);
  }
  source = type->source;
  types_[key] = nullptr;  // loading: a reference back to it is a cycle
  for (auto& f : type->fields) {
    if (f.type.prim != Prim::Message) continue;
    try {
      f.type.message = &load(f.type.type_name, depth + 1);
    } catch (const MsgError& e) {
      types_.erase(key);
      throw MsgError(std::string(e.what()) + "\n  used by field '" + f.name + "' of " + key + " (" + source + ":" +
                     std::to_string(f.line) + ")");
    }
  }
  // Its smallest sample, bounded (kMaxFixedBytes): a definition must not make
  // every encoder of a default sample allocate gigabytes.
  uint64_t bytes = type->fields.empty() ? 1 : 0;
  for (const auto& f : type->fields) {
    const uint64_t element = f.type.prim == Prim::Message                                   ? f.type.message->fixed_bytes
                             : f.type.prim == Prim::String || f.type.prim == Prim::WString ? 4
                                                                                           : prim_size(f.type.prim);
    bytes += f.type.array == ArrayKind::None    ? element
             : f.type.array == ArrayKind::Fixed ? element * f.type.array_size  // <= 2^26 * 2^24: no overflow
                                                : 4;
    if (bytes > kMaxFixedBytes) {
      types_.erase(key);
      throw MsgError(source + ":" + std::to_string(f.line) + ": field '" + f.name + "' (" + f.type.to_string() +
                     ") makes the smallest sample of " + key + " over rvc's limit of " +
                     std::to_string(kMaxFixedBytes >> 20) + " MiB (docs/ros2-types.md)");
    }
  }
  type->fixed_bytes = bytes;
  auto& slot = types_[key];
  slot = std::move(type);
  return *slot;
}

}  // namespace rvc::msg
