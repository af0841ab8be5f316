#include "msg/service_types.hpp"

#include <vector>

namespace rvc::msg {

bool split_service_part(std::string_view name, std::string& service, ServicePart& part) {
  struct Suffix {
    std::string_view text;
    ServicePart part;
  };
  for (const Suffix& s : {Suffix{"_Request", ServicePart::Request}, Suffix{"_Response", ServicePart::Response},
                          Suffix{"_Event", ServicePart::Event}}) {
    if (name.size() > s.text.size() && name.substr(name.size() - s.text.size()) == s.text) {
      service = std::string(name.substr(0, name.size() - s.text.size()));
      part = s.part;
      return true;
    }
  }
  return false;
}

namespace {
// Line boundaries of the "---" separators (trailing spaces and '\r' allowed).
std::vector<size_t> separator_lines(std::string_view text) {
  std::vector<size_t> out;
  size_t start = 0, line = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view l = text.substr(start, end - start);
    while (!l.empty() && (l.back() == ' ' || l.back() == '\t' || l.back() == '\r')) l.remove_suffix(1);
    if (l == "---") out.push_back(line);
    ++line;
    start = end + 1;
  }
  return out;
}
}  // namespace

bool is_srv_text(std::string_view text) { return !separator_lines(text).empty(); }

std::string srv_part(std::string_view text, ServicePart part, const std::string& source) {
  const std::vector<size_t> seps = separator_lines(text);
  if (seps.size() != 1)
    throw MsgError(source + ": a service definition has one line '---' between request and response, this one has " +
                   std::to_string(seps.size()));
  std::string out;
  size_t start = 0, line = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const bool keep = part == ServicePart::Request ? line < seps[0] : line > seps[0];
    if (keep) out.append(text.substr(start, end - start));
    out.push_back('\n');
    ++line;
    start = end + 1;
  }
  return out;
}

MessageType service_event_type(const std::string& package, const std::string& service, const std::string& source) {
  MessageType t;
  t.package = package;
  t.kind = "srv";
  t.name = service + "_Event";
  t.source = source;
  auto field = [&](const char* name, std::string type_name, bool optional) {
    Field f;
    f.name = name;
    f.type.prim = Prim::Message;
    f.type.type_name = std::move(type_name);
    if (optional) {  // rosidl: a sequence bounded to 1, empty when the event does not carry it
      f.type.array = ArrayKind::Bounded;
      f.type.array_size = 1;
    }
    t.fields.push_back(std::move(f));
  };
  field("info", "service_msgs/msg/ServiceEventInfo", false);
  field("request", package + "/srv/" + service + "_Request", true);
  field("response", package + "/srv/" + service + "_Response", true);
  return t;
}

MessageType with_request_header(const MessageType& type) {
  MessageType out = type;
  Field guid, seq;
  guid.name = "client_guid";
  guid.type.prim = Prim::UInt64;
  seq.name = "sequence_number";
  seq.type.prim = Prim::Int64;
  // an empty message's one uint8 stays after the header, as rmw_cyclonedds writes it
  if (out.fields.empty()) {
    Field pad;
    pad.name = "structure_needs_at_least_one_member";
    pad.type.prim = Prim::UInt8;
    out.fields.push_back(pad);
  }
  out.fields.insert(out.fields.begin(), {guid, seq});
  out.fixed_bytes += 16;
  out.source = type.source + " (with the rmw_cyclonedds request header)";
  return out;
}

}  // namespace rvc::msg
