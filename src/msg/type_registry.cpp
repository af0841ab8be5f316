#include "msg/type_registry.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "msg/idl_parser.hpp"
#include "msg/msg_parser.hpp"
#include "msg/service_types.hpp"

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
  for (size_t i = 0; i < kBundledCount; ++i) {
    std::string name = kBundled[i].full_name;
    if (name.find("/srv/") == std::string::npos) {
      out.push_back(std::move(name));
      continue;
    }
    for (const char* part : {"_Request", "_Response", "_Event"}) out.push_back(name + part);  // a .srv's three types
  }
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
  std::string pkg, kind, name, service;
  if (!split_type_name(type_name, pkg, kind, name)) throw MsgError(source + ": not a message type name: '" + type_name + "'");
  ServicePart part;
  if (kind == "srv" && is_srv_text(text)) {
    // rosbag2 stores the .srv text as the schema of a service's event topic
    // (pkg/srv/Name_Event): it defines all three types of the service.
    if (!split_service_part(name, service, part)) service = name;
    added_srv_[pkg + "/srv/" + service] = {std::move(text), source};
    return;
  }
  added_[pkg + "/" + kind + "/" + name] = {std::move(text), source};
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

TypeRegistry::Found TypeRegistry::find_definition(const std::string& package, const std::string& kind,
                                                  const std::string& name, std::string& text, std::string& source) {
  auto added = added_.find(package + "/" + kind + "/" + name);
  if (added != added_.end()) {
    text = added->second.first;
    source = added->second.second;
    return Found::Msg;
  }
  if (kind == "srv") return find_service(package, name, text, source);
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

TypeRegistry::Found TypeRegistry::find_service(const std::string& package, const std::string& name, std::string& text,
                                               std::string& source) {
  std::string service;
  ServicePart part;
  if (!split_service_part(name, service, part)) return Found::None;
  const std::string srv_key = package + "/srv/" + service;
  std::string srv_text;
  bool found = false;
  if (auto added = added_srv_.find(srv_key); added != added_srv_.end()) {
    srv_text = added->second.first;
    source = added->second.second;
    found = true;
  }
  namespace fs = std::filesystem;
  for (size_t d = 0; !found && d < search_paths_.size(); ++d) {
    const std::string& dir = search_paths_[d];
    for (const char* ext : {".srv", ".idl"}) {
      if (found) break;
      for (fs::path p : {fs::path(dir) / package / "srv" / (service + ext), fs::path(dir) / "share" / package / "srv" / (service + ext),
                         fs::path(dir) / package / (service + ext), fs::path(dir) / (service + ext)}) {
        std::error_code ec;
        if (!fs::is_regular_file(p, ec)) continue;
        if (ext[1] == 's') {
          srv_text = read_file(p);
          source = p.string();
          found = true;
          break;
        }
        read_idl_file(p.string());  // rosidl's srv/Name.idl: structs Name_Request and Name_Response
        if (idl_.count(srv_key + "_Request")) {
          source = p.string();
          if (part == ServicePart::Event) return Found::Event;
          if (idl_.count(package + "/srv/" + name)) return Found::Idl;
        }
      }
    }
  }
  if (!found) {
    std::string_view bundled = bundled_definition(srv_key);
    if (!bundled.data()) return Found::None;
    srv_text = std::string(bundled);
    source = "bundled " + srv_key + ".srv";
  }
  if (part == ServicePart::Event) return Found::Event;
  text = srv_part(srv_text, part, source);
  return Found::Msg;
}

const MessageType& TypeRegistry::resolve(std::string_view type_name) {
  const std::string key(type_name);
  if (known(key)) return load(key, 0);
  std::string pkg, kind, name, text, source;
  const bool ros = split_type_name(type_name, pkg, kind, name);
  const std::string full = pkg + "/" + kind + "/" + name;
  // "pkg/msg/Name" is always ROS 2; "a::B" may be a ROS 2 pkg::Name or a plain IDL name.
  if (ros && (key.find('/') != std::string::npos || key.find("::msg::") != std::string::npos ||
              key.find("::srv::") != std::string::npos || known(full) ||
              find_definition(pkg, kind, name, text, source) != Found::None))
    return load(full, 0);
  scan_idl_files();
  if (known(key)) return load(key, 0);
  if (ros && key.find("::") == std::string::npos) return load(full, 0);  // the usual error
  throw MsgError("unknown message type '" + key + "': no .idl file of --msg-path defines it" +
                 (ros ? ", and there is no ROS 2 type " + full : std::string()) + idl_scan_errors_);
}

const MessageType& TypeRegistry::load(const std::string& key, int depth) {
  auto it = types_.find(key);
  if (it != types_.end()) {
    if (!it->second) throw MsgError("message type " + key + " contains itself");
    return *it->second;
  }
  if (depth > 64) throw MsgError("message types nested deeper than 64 levels at " + key);
  std::unique_ptr<MessageType> type;
  std::string pkg, kind, name, text, source;
  if (!idl_.count(key) && key.find('/') == std::string::npos) scan_idl_files();  // a plain IDL name
  if (auto idl = idl_.find(key); idl != idl_.end()) {
    type = std::make_unique<MessageType>(idl->second);
  } else if (key.find('/') != std::string::npos && split_type_name(key, pkg, kind, name)) {
    switch (find_definition(pkg, kind, name, text, source)) {
      case Found::Msg:
        type = std::make_unique<MessageType>(parse_msg(pkg, name, text, source));
        type->kind = kind;
        break;
      case Found::Idl: type = std::make_unique<MessageType>(idl_.at(key)); break;
      case Found::Event: {
        std::string service;
        ServicePart part;
        split_service_part(name, service, part);
        type = std::make_unique<MessageType>(service_event_type(pkg, service, source));
        break;
      }
      case Found::None: {
        std::string where = search_paths_.empty() ? "no --msg-path given" : "searched --msg-path";
        for (const auto& d : search_paths_) where += " " + d;
        throw MsgError("unknown message type " + key + ": not bundled with rvc, not in a bag schema, " + where +
                       (kind == "srv" ? " (a service's types come from its .srv: pkg/srv/Name.srv)" : ""));
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
