// The types of a ROS 2 service (src/msg/service_types.hpp, TypeRegistry):
// Name_Request / Name_Response / Name_Event from a .srv, their names in every
// accepted form, and errors that name the .srv's own line.
#include <gtest/gtest.h>

#include <string>

#include "msg/msg_parser.hpp"
#include "msg/type_registry.hpp"

namespace {

using namespace rvc::msg;

TEST(ServiceTypes, NamesOfAServicesTypes) {
  std::string pkg, kind, name;
  for (const char* text : {"std_srvs/srv/SetBool_Request", "std_srvs::srv::SetBool_Request",
                           "std_srvs::srv::dds_::SetBool_Request_"}) {
    ASSERT_TRUE(split_type_name(text, pkg, kind, name)) << text;
    EXPECT_EQ(pkg + "|" + kind + "|" + name, "std_srvs|srv|SetBool_Request") << text;
    EXPECT_FALSE(split_type_name(text, pkg, name)) << text;  // the msg-only form refuses it
  }
  ASSERT_TRUE(split_type_name("std_msgs/String", pkg, kind, name));
  EXPECT_EQ(kind, "msg");
}

TEST(ServiceTypes, BundledServiceGivesThreeTypes) {
  TypeRegistry reg;
  const MessageType& req = reg.resolve("std_srvs/srv/SetBool_Request");
  ASSERT_EQ(req.fields.size(), 1u);
  EXPECT_EQ(req.fields[0].name, "data");
  EXPECT_EQ(req.full_name(), "std_srvs/srv/SetBool_Request");
  const MessageType& resp = reg.resolve("std_srvs::srv::dds_::SetBool_Response_");
  ASSERT_EQ(resp.fields.size(), 2u);
  EXPECT_EQ(resp.fields[1].name, "message");
  const MessageType& ev = reg.resolve("std_srvs/srv/SetBool_Event");
  ASSERT_EQ(ev.fields.size(), 3u);
  EXPECT_EQ(ev.fields[0].type.to_string(), "service_msgs/msg/ServiceEventInfo");
  EXPECT_EQ(ev.fields[1].type.to_string(), "std_srvs/srv/SetBool_Request[<=1]");
  EXPECT_EQ(ev.fields[2].type.to_string(), "std_srvs/srv/SetBool_Response[<=1]");
  EXPECT_EQ(ev.fields[1].type.message, &req);
  ASSERT_NE(ev.fields[0].type.message, nullptr);
  EXPECT_NE(ev.fields[0].type.message->constant("RESPONSE_RECEIVED"), nullptr);
  // An empty request (std_srvs/Empty, Trigger) is an empty message
  EXPECT_TRUE(reg.resolve("std_srvs/srv/Trigger_Request").fields.empty());
}

TEST(ServiceTypes, BagSchemaOfAnEventTopicIsTheSrvText) {
  // rosbag2 stores the .srv text as the schema of <service>/_service_event
  TypeRegistry reg;
  reg.add_concatenated("my_msgs/srv/Add_Event", "int64 a\nint64 b\n---\nint64 sum\n", "bag");
  const MessageType& ev = reg.resolve("my_msgs/srv/Add_Event");
  EXPECT_EQ(ev.fields[1].type.message->fields.size(), 2u);
  EXPECT_EQ(ev.fields[2].type.message->fields[0].name, "sum");
}

TEST(ServiceTypes, ErrorsNameTheSrvLine) {
  TypeRegistry reg;
  reg.add_definition("my_msgs/srv/Bad_Event", "int64 a\n---\nint64 ok\nfloat64[<=x] broken\n", "my.srv");
  EXPECT_NO_THROW(reg.resolve("my_msgs/srv/Bad_Request"));
  try {
    reg.resolve("my_msgs/srv/Bad_Response");
    FAIL();
  } catch (const MsgError& e) {
    EXPECT_NE(std::string(e.what()).find("my.srv:4:"), std::string::npos) << e.what();
  }
  reg.add_definition("my_msgs/srv/Two_Event", "int64 a\n---\nint64 b\n---\nint64 c\n", "two.srv");
  try {
    reg.resolve("my_msgs/srv/Two_Request");
    FAIL();
  } catch (const MsgError& e) {
    EXPECT_NE(std::string(e.what()).find("this one has 2"), std::string::npos) << e.what();
  }
  try {
    reg.resolve("nope_srvs/srv/Missing_Event");
    FAIL();
  } catch (const MsgError& e) {
    EXPECT_NE(std::string(e.what()).find("pkg/srv/Name.srv"), std::string::npos) << e.what();
  }
}

}  // namespace
