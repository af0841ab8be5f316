// --output mcap:PATH: verdicts as a ROS 2 MCAP file (profile "ros2"), one
// channel /rvc/verdicts of rvc_msgs/msg/Verdict (CDR, schema ros2msg carried in
// the file), so Foxglove, `ros2 bag` and rosbags read them without rvc's types.
// The file is valid once put_eos() (the run's end, a stop signal too) or the
// destructor wrote its summary and footer.
#pragma once

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "transport/endpoint.hpp"
#include "transport/mcap/mcap_writer.hpp"
#include "transport/verdict_sink.hpp"

namespace rvc::transport::mcap {

// The topic verdicts are written on, and their type.
inline constexpr const char* kVerdictTopic = "/rvc/verdicts";
inline constexpr const char* kVerdictType = "rvc_msgs/msg/Verdict";

class McapSink final : public Sink, public VerdictSink {
 public:
  // PATH, or PATH?inputs=1: also the input messages (a bag's) on their own topics.
  // Refuses a file rvc did not write (output_file.hpp).
  explicit McapSink(std::string path);
  ~McapSink() override;                 // closes the file if put_eos did not; never throws
  void put_verdict(std::string_view cdr, uint64_t log_time_ns) override;
  bool wants_inputs() const override { return inputs_; }
  void put_input(const InputMessage& message) override;
  // A payload that is not a verdict (rvc sync's sets): MCAP outputs take verdicts only.
  void put(std::string_view payload, uint64_t seq) override;
  void put_eos(uint64_t last_seq) override;
  void flush() override;
  void idle() override { flush(); }

 private:
  [[noreturn]] void fail(const std::string& what) const;

  std::string path_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<McapWriter> writer_;
  uint16_t verdict_channel_ = 0;
  uint32_t sequence_ = 0;
  bool inputs_ = false;
  struct InputChannel {
    uint16_t id;
    uint32_t sequence = 0;
  };
  std::map<std::string, InputChannel, std::less<>> input_channels_;  // by topic
};

// The ros2msg schema text of a bundled type followed by the bundled types it
// uses (`uses`, "pkg/msg/Name"), each after a line of 80 '=' and "MSG: pkg/Name",
// as rosbag2 stores a topic's definition.
std::string ros2msg_schema(const std::string& full_name, const std::vector<std::string>& uses);

}  // namespace rvc::transport::mcap
