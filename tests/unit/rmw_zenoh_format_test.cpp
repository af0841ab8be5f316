// rmw_zenoh's wire formats (ros2/rmw_zenoh docs/design.md): data keys, the
// 33-byte attachment, liveliness tokens, type-name mapping. Expected values
// are written out by hand from the design document's examples and layout
// tables, not produced by the code under test.
#include <gtest/gtest.h>

#include <cstdlib>
#include <map>

#include "transport/seq_counter.hpp"
#include "transport/zenoh/rmw_zenoh_format.hpp"

namespace rz = rvc::transport::rmw_zenoh;

TEST(RmwZenohFormat, DataKeyOfTheDesignDocumentsExamples) {
  EXPECT_EQ(rz::data_keyexpr(0, "/chatter", "std_msgs::msg::dds_::String_", rz::kStringTypeHash),
            "0/chatter/std_msgs::msg::dds_::String_/"
            "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18");
  EXPECT_EQ(rz::data_keyexpr(0, "/robot1/chatter", "T", "H"), "0/robot1/chatter/T/H");
  EXPECT_EQ(rz::data_keyexpr(2, "chatter"), "2/chatter/*/*");  // relative: the root namespace
  EXPECT_EQ(rz::data_keyexpr(0, "/vehicle/status/gear_status"), "0/vehicle/status/gear_status/*/*");
  for (const char* bad : {"", "/", "/a//b", "/a/", "/a/*", "/a/%b", "/$x"})
    EXPECT_THROW(rz::data_keyexpr(0, bad), std::invalid_argument) << bad;
}

TEST(RmwZenohFormat, ParsesDataKeys) {
  auto k = rz::parse_data_key("7/robot1/chatter/std_msgs::msg::dds_::String_/RIHS01_ab");
  ASSERT_TRUE(k);
  EXPECT_EQ(k->domain, 7);
  EXPECT_EQ(k->topic, "/robot1/chatter");
  EXPECT_EQ(k->dds_type, "std_msgs::msg::dds_::String_");
  EXPECT_EQ(k->type_hash, "RIHS01_ab");
  EXPECT_FALSE(rz::parse_data_key("x/chatter/T/H"));
  EXPECT_FALSE(rz::parse_data_key("0/T/H"));
}

TEST(RmwZenohFormat, TypeNamesBothWays) {
  EXPECT_EQ(rz::ros_type_of("std_msgs::msg::dds_::String_"), "std_msgs/msg/String");
  EXPECT_EQ(rz::ros_type_of("example_interfaces::srv::dds_::AddTwoInts_"), "example_interfaces/srv/AddTwoInts");
  EXPECT_EQ(rz::dds_type_of("autoware_auto_vehicle_msgs/msg/GearReport"),
            "autoware_auto_vehicle_msgs::msg::dds_::GearReport_");
  for (const char* bad : {"std_msgs/msg/String", "std_msgs::msg::String_", "std_msgs::msg::dds_::String", "::msg::dds_::X_"})
    EXPECT_FALSE(rz::ros_type_of(bad)) << bad;
  EXPECT_FALSE(rz::dds_type_of("String"));
  EXPECT_FALSE(rz::dds_type_of("std_msgs//String"));
}

TEST(RmwZenohFormat, AttachmentLayoutByHand) {
  // seq 5, timestamp 0x0102030405060708, GID length 16, GID 0xa0..0xaf.
  std::vector<uint8_t> bytes = {5, 0, 0, 0, 0, 0, 0, 0, 8, 7, 6, 5, 4, 3, 2, 1, 16};
  for (int i = 0; i < 16; ++i) bytes.push_back(static_cast<uint8_t>(0xa0 + i));
  auto a = rz::decode_attachment(bytes.data(), bytes.size());
  ASSERT_TRUE(a);
  EXPECT_EQ(a->seq, 5);
  EXPECT_EQ(a->source_timestamp_ns, 0x0102030405060708);
  EXPECT_EQ(a->gid[0], 0xa0);
  EXPECT_EQ(a->gid[15], 0xaf);
  const auto again = rz::encode_attachment(*a);
  EXPECT_EQ(std::vector<uint8_t>(again.begin(), again.end()), bytes);

  std::string error;
  EXPECT_FALSE(rz::decode_attachment(bytes.data(), 17, &error));  // rvc's own 17-byte attachment is not it
  EXPECT_NE(error.find("17 bytes"), std::string::npos) << error;
  bytes[16] = 24;
  EXPECT_FALSE(rz::decode_attachment(bytes.data(), bytes.size(), &error));
  EXPECT_NE(error.find("GID length"), std::string::npos) << error;
  EXPECT_FALSE(rz::decode_attachment(nullptr, 0, &error));
}

TEST(RmwZenohFormat, GidsBecomeDistinctNonZeroPublisherIds) {
  rz::Gid a{}, b{};
  b[15] = 1;
  EXPECT_NE(rz::publisher_id(a), 0u);
  EXPECT_NE(rz::publisher_id(a), rz::publisher_id(b));
  EXPECT_EQ(rz::publisher_id(b), rz::publisher_id(b));
  // Mapped onto SeqCounters: a gap in one GID's numbers is that publisher's loss only.
  rvc::transport::SeqCounters c;
  c.expect(2);
  for (uint64_t s : {1, 2, 3}) c.on_seq(s, rz::publisher_id(a));
  for (uint64_t s : {1, 3}) c.on_seq(s, rz::publisher_id(b));
  c.on_seq(1, rz::publisher_id(a));  // a numbering from 1 again: that publisher restarted
  c.on_seq(2, rz::publisher_id(a));
  EXPECT_EQ(c.gaps, 1u);
  EXPECT_EQ(c.duplicates, 0u);
  EXPECT_EQ(c.restarts, 1u);
  EXPECT_EQ(c.publishers(), 2u);
  // Each publisher's share, as the counters line lists it.
  std::map<uint64_t, rvc::transport::SeqCounters::Publisher> by;
  c.each_publisher([&](uint64_t id, const auto& p) { by[id] = p; });
  ASSERT_EQ(by.size(), 2u);
  const auto& pa = by.at(rz::publisher_id(a));
  const auto& pb = by.at(rz::publisher_id(b));
  EXPECT_EQ(pa.received, 5u);
  EXPECT_EQ(pa.gaps, 0u);
  EXPECT_EQ(pa.restarts, 1u);
  EXPECT_EQ(pa.last_seq, 2u);
  EXPECT_EQ(pb.received, 2u);
  EXPECT_EQ(pb.gaps, 1u);
  EXPECT_EQ(pb.restarts, 0u);
}

TEST(RmwZenohFormat, LivelinessTokensOfTheDesignDocument) {
  auto node = rz::parse_liveliness("@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener");
  ASSERT_TRUE(node);
  EXPECT_TRUE(node->is_node());
  EXPECT_EQ(node->domain, 2);
  EXPECT_EQ(node->node, "listener");
  EXPECT_EQ(node->name_space, "");

  const std::string sub_key =
      "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/10/MS/%/%/listener/%chatter/std_msgs::msg::dds_::String_/"
      "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18/::,10:,:,:,,";
  auto sub = rz::parse_liveliness(sub_key);
  ASSERT_TRUE(sub);
  EXPECT_TRUE(sub->is_subscription());
  EXPECT_EQ(sub->session_id, "aac3178e146ba6f1fc6e6a4085e77f21");
  EXPECT_EQ(sub->entity_id, "10");
  EXPECT_EQ(sub->topic, "/chatter");
  EXPECT_EQ(sub->dds_type, "std_msgs::msg::dds_::String_");
  EXPECT_EQ(sub->qos, "::,10:,:,:,,");
  EXPECT_EQ(rz::liveliness_key(*sub), sub_key);  // and back

  auto pub = rz::parse_liveliness(
      "@ros2_lv/0/ab/0/11/MP/%/%robot1/talker/%robot1%vehicle%status/pkg::msg::dds_::T_/RIHS01_x/::,7:,:,:,,");
  ASSERT_TRUE(pub);
  EXPECT_EQ(pub->name_space, "/robot1");
  EXPECT_EQ(pub->topic, "/robot1/vehicle/status");

  std::string error;
  EXPECT_FALSE(rz::parse_liveliness("rvc/monitors/x", &error));
  EXPECT_FALSE(rz::parse_liveliness("@ros2_lv/0/ab/0/11/XX/%/%/n/%t/T/H/q", &error));
  EXPECT_NE(error.find("XX"), std::string::npos);
  EXPECT_FALSE(rz::parse_liveliness("@ros2_lv/0/ab/0/11/MP/%/%/n", &error));  // a publisher needs its topic
  EXPECT_FALSE(rz::parse_liveliness("@ros2_lv/x/ab/0/0/NN/%/%/n", &error));
  EXPECT_EQ(rz::graph_keyexpr(3), "@ros2_lv/3/**");
}

TEST(RmwZenohFormat, GraphTopicsCountEndpointsAndSkipServices) {
  std::vector<rz::Entity> es;
  auto add = [&](const char* key) { es.push_back(*rz::parse_liveliness(key)); };
  add("@ros2_lv/0/s1/0/0/NN/%/%/talker");
  add("@ros2_lv/0/s1/0/1/MP/%/%/talker/%chatter/std_msgs::msg::dds_::String_/H/q");
  add("@ros2_lv/0/s1/0/1/MP/%/%/talker/%chatter/std_msgs::msg::dds_::String_/H/q");  // the same, answered twice
  add("@ros2_lv/0/s2/0/1/MP/%/%/talker2/%chatter/std_msgs::msg::dds_::String_/H/q");
  add("@ros2_lv/0/s3/0/1/MS/%/%/listener/%chatter/std_msgs::msg::dds_::String_/H/q");
  add("@ros2_lv/0/s3/0/2/MS/%/%/listener/%a%b/pkg::msg::dds_::B_/H/q");
  add("@ros2_lv/0/s3/0/3/SS/%/%/listener/%add/example_interfaces::srv::dds_::AddTwoInts_/H/q");
  auto topics = rz::graph_topics(es);
  ASSERT_EQ(topics.size(), 2u);
  EXPECT_EQ(topics[0].topic, "/a/b");
  EXPECT_EQ(topics[0].types, std::vector<std::string>{"pkg/msg/B"});
  EXPECT_EQ(topics[0].subscriptions, 1u);
  EXPECT_EQ(topics[1].topic, "/chatter");
  EXPECT_EQ(topics[1].publishers, 2u);
  EXPECT_EQ(topics[1].subscriptions, 1u);
}

TEST(RmwZenohFormat, DomainFromTheEnvironment) {
  ::unsetenv("ROS_DOMAIN_ID");
  EXPECT_EQ(rz::domain_id_from_env(), 0);
  ::setenv("ROS_DOMAIN_ID", "42", 1);
  EXPECT_EQ(rz::domain_id_from_env(), 42);
  ::setenv("ROS_DOMAIN_ID", "x", 1);
  EXPECT_THROW(rz::domain_id_from_env(), std::invalid_argument);
  ::setenv("ROS_DOMAIN_ID", "233", 1);
  EXPECT_THROW(rz::domain_id_from_env(), std::invalid_argument);
  ::unsetenv("ROS_DOMAIN_ID");
}
