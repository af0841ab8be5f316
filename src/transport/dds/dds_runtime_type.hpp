// A CycloneDDS topic descriptor built at run time from a ROS 2 message type
// (src/msg), equal to what idlc generates for the IDL that rosidl derives from
// the .msg: type name "pkg::msg::dds_::Name_", final extensibility, XCDR1, no
// keys, empty messages with their one uint8 member. Plain DDS IDL types
// (msg::MessageType::idl_name) keep their own name and their keys. It lets rvc subscribe to
// any ROS 2 topic as raw CDR (dds_takecdr), with no generated code: CycloneDDS
// uses the ops to check each sample it receives, rvc decodes the bytes itself
// (src/io/cdr_codec).
//
// The ops follow the layout of the C struct idlc would generate (offsets,
// sizes, alignment), so the descriptor is also valid for dds_take/dds_write.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "msg/msg_types.hpp"

namespace rvc::transport::dds {

// "autoware_auto_vehicle_msgs/msg/GearReport" -> "autoware_auto_vehicle_msgs::msg::dds_::GearReport_"
std::string ros2_dds_type_name(const msg::MessageType& type);

class RuntimeTopicType {
 public:
  explicit RuntimeTopicType(const msg::MessageType& type);
  RuntimeTopicType(const RuntimeTopicType&) = delete;
  RuntimeTopicType& operator=(const RuntimeTopicType&) = delete;

  const dds_topic_descriptor_t* descriptor() const { return desc_.get(); }
  const std::vector<uint32_t>& ops() const { return ops_; }
  uint32_t sample_size() const { return size_; }
  uint32_t sample_align() const { return align_; }

 private:
  std::string type_name_;
  std::vector<uint32_t> ops_;
  std::vector<std::string> key_names_;
  std::vector<dds_key_descriptor_t> keys_;
  uint32_t size_ = 0, align_ = 1;
  std::unique_ptr<dds_topic_descriptor_t> desc_;
};

}  // namespace rvc::transport::dds
