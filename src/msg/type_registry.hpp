// Finds, parses and links ROS 2 message types by name, from (in this order)
// definitions added in-process (an MCAP bag's schemas), folders given with
// --msg-path, and the definitions bundled with rvc (ROS 2's common_interfaces
// and services, the Autoware messages of the paper's Table 3).
// Definitions are ROS 2 .msg files or OMG IDL (.idl, see idl_parser.hpp):
// ROS 2 types by pkg/msg/Name, plain DDS IDL types by their scoped name.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "msg/msg_types.hpp"

namespace rvc::msg {

class TypeRegistry {
 public:
  // A registry that knows the bundled definitions only.
  TypeRegistry();

  // A folder of definitions: a ROS 2 install or share/ tree (<dir>/<pkg>/msg/<Name>.msg,
  // <dir>/share/<pkg>/msg/<Name>.msg) or a plain folder (<dir>/<Name>.msg, any package);
  // <Name>.idl beside or instead of <Name>.msg. Or one .idl file, read at once.
  void add_search_path(const std::string& dir);
  // Every struct of an IDL text (a file, a bag's schema).
  void add_idl(std::string_view text, const std::string& source);
  // One definition's text, e.g. from a bag's schema record.
  void add_definition(const std::string& type_name, std::string text, const std::string& source);
  // An MCAP "ros2msg" schema: the type's definition followed by those it uses,
  // each after a line of '=' and a line "MSG: pkg/Name".
  void add_concatenated(const std::string& type_name, std::string_view text, const std::string& source);

  // An MCAP "ros2idl" schema: IDL texts, each after a line of '=' and a line "IDL: pkg/msg/Name".
  void add_concatenated_idl(std::string_view text, const std::string& source);

  // The type and every type it uses, parsed and linked. Accepts "pkg/msg/Name",
  // "pkg/Name", the DDS name "pkg::msg::dds_::Name_", a service's types
  // "pkg/srv/Name_Request" / "_Response" / "_Event" (pkg::srv::dds_::Name_Request_), and plain IDL names
  // ("KeyedSeq", "vehicle::Speed"; these are looked for in every .idl file
  // of the search folders). Throws MsgError.
  const MessageType& resolve(std::string_view type_name);

  // The folders (or .idl files) given with add_search_path, in order.
  const std::vector<std::string>& search_paths() const { return search_paths_; }

  // Names of the bundled types ("pkg/msg/Name"), sorted.
  static std::vector<std::string> bundled_types();

 private:
  enum class Found { None, Msg, Idl, Event };  // Event: a service's Name_Event, made from its .srv
  const MessageType& load(const std::string& key, int depth);
  bool known(const std::string& key) const { return types_.count(key) || idl_.count(key); }
  // .msg text (Msg), or an .idl file now in idl_ (Idl), in the registry's order.
  // For "srv" types: `text` is the request or response part of the .srv.
  Found find_definition(const std::string& package, const std::string& kind, const std::string& name, std::string& text,
                        std::string& source);
  Found find_service(const std::string& package, const std::string& name, std::string& text, std::string& source);
  void read_idl_file(const std::string& path);
  void scan_idl_files();

  std::vector<std::string> search_paths_;
  std::map<std::string, MessageType> idl_;                          // full name -> parsed, unlinked
  std::set<std::string> idl_files_read_;
  bool idl_scanned_ = false;
  std::string idl_scan_errors_;
  std::map<std::string, std::pair<std::string, std::string>> added_;  // full name -> (text, source)
  std::map<std::string, std::pair<std::string, std::string>> added_srv_;  // "pkg/srv/Name" -> (.srv text, source)
  std::map<std::string, std::unique_ptr<MessageType>> types_;        // full name -> linked type
};

// The .msg text of a bundled type; a null string_view (data() == nullptr) if none.
std::string_view bundled_definition(std::string_view full_name);

}  // namespace rvc::msg
