#include "transport/mcap/mcap_sink.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "msg/type_registry.hpp"
#include "transport/output_file.hpp"

namespace rvc::transport::mcap {

std::string ros2msg_schema(const std::string& full_name, const std::vector<std::string>& uses) {
  auto text = [](const std::string& name) {
    const std::string_view t = msg::bundled_definition(name);
    if (!t.data()) throw std::logic_error("no bundled definition of " + name);
    return std::string(t);
  };
  std::string out = text(full_name);
  for (const auto& name : uses) {
    if (!out.empty() && out.back() != '\n') out += '\n';
    const size_t slash = name.find("/msg/");
    out += std::string(80, '=') + "\nMSG: " + name.substr(0, slash) + "/" + name.substr(slash + 5) + "\n" + text(name);
  }
  return out;
}

McapSink::McapSink(std::string path) : path_(std::move(path)) {
  // Options after '?' (a path with a '?' of its own: name it ./a?b?inputs=0).
  if (const size_t q = path_.rfind('?'); q != std::string::npos) {
    const std::string option = path_.substr(q + 1);
    if (option == "inputs=1" || option == "inputs=true") inputs_ = true;
    else if (option != "inputs=0" && option != "inputs=false")
      throw std::invalid_argument("mcap:" + path_ + ": unknown option '" + option + "' (mcap:PATH?inputs=1 copies the inputs)");
    path_.resize(q);
  }
  if (path_ == "-") throw std::invalid_argument("mcap: writes a file: give its path (mcap:PATH), not '-'");
  file_ = open_output_file(path_, "--output");  // refuses a file rvc did not write, marks this one
  try {
    writer_ = std::make_unique<McapWriter>(file_, "ros2", "rvc");
    const uint16_t schema = writer_->add_schema(
        kVerdictType, "ros2msg", ros2msg_schema(kVerdictType, {"builtin_interfaces/msg/Time"}));
    verdict_channel_ = writer_->add_channel(schema, kVerdictTopic, "cdr");
  } catch (const std::runtime_error& e) {
    std::fclose(file_);
    throw std::invalid_argument("cannot write '" + path_ + "': " + e.what());
  }
}

McapSink::~McapSink() {
  try {
    if (writer_) writer_->close();  // a run that ended by an exception still leaves a readable file
  } catch (...) {
  }
  std::fclose(file_);
}

void McapSink::fail(const std::string& what) const { throw std::runtime_error("cannot write '" + path_ + "': " + what); }

void McapSink::put_verdict(std::string_view cdr, uint64_t log_time_ns) {
  try {
    writer_->write_message(verdict_channel_, ++sequence_, log_time_ns, log_time_ns, cdr);
  } catch (const std::runtime_error& e) {
    fail(e.what());
  }
}

void McapSink::put_input(const InputMessage& m) {
  try {
    auto it = input_channels_.find(m.topic);
    if (it == input_channels_.end()) {
      const uint16_t schema =
          m.schema_encoding.empty() ? 0 : writer_->add_schema(m.type, m.schema_encoding, m.schema);
      it = input_channels_.emplace(std::string(m.topic), InputChannel{writer_->add_channel(schema, m.topic, m.message_encoding)})
               .first;
    }
    writer_->write_message(it->second.id, ++it->second.sequence, m.log_time_ns, m.log_time_ns, m.data);
  } catch (const std::runtime_error& e) {
    fail(e.what());
  }
}

void McapSink::put(std::string_view, uint64_t) {
  throw std::runtime_error("'" + path_ + "': an mcap: output takes verdicts (rvc check, rvc monitor) only");
}

void McapSink::put_eos(uint64_t) {
  try {
    writer_->close();
  } catch (const std::runtime_error& e) {
    fail(e.what());
  }
}

void McapSink::flush() {
  if (std::fflush(file_) != 0 || std::ferror(file_)) fail(std::strerror(errno ? errno : EIO));
}

}  // namespace rvc::transport::mcap
