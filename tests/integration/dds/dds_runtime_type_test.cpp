// RuntimeTopicType (src/transport/dds/dds_runtime_type.cpp) against idlc: the
// descriptor built at run time from .msg files must equal, word for word, the
// one idlc generates from the IDL rosidl would write for them
// (runtime_type_oracle.idl), with the same C layout (size, alignment) and
// instruction count. Then CycloneDDS itself must accept what rvc's CDR encoder
// writes for the type (dds_stream_normalize_data with these ops), and refuse a
// truncated sample.
#include <dds/dds.h>
#include <dds/ddsi/ddsi_cdrstream.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
#include "msg/type_registry.hpp"
#include "runtime_type_oracle.h"  // idlc output
#include "transport/dds/dds_runtime_type.hpp"

namespace rvc::transport::dds {
namespace {

msg::TypeRegistry& registry() {
  static msg::TypeRegistry r = [] {
    msg::TypeRegistry reg;
    reg.add_search_path(RVC_TEST_MSGS_DIR);
    return reg;
  }();
  return r;
}

std::vector<uint32_t> words(const dds_topic_descriptor_t& d) {
  const uint32_t n = dds_stream_countops(d.m_ops, d.m_nkeys, d.m_keys);
  return std::vector<uint32_t>(d.m_ops, d.m_ops + n);
}

// Everything of the descriptor that matters on the wire and for matching:
// name, layout, ops word for word, keys and the key flags.
void expect_same(msg::TypeRegistry& reg, const char* name, const dds_topic_descriptor_t& idlc) {
  SCOPED_TRACE(name);
  RuntimeTopicType t(reg.resolve(name));
  const dds_topic_descriptor_t& d = *t.descriptor();
  EXPECT_STREQ(d.m_typename, idlc.m_typename);
  EXPECT_EQ(d.m_size, idlc.m_size);
  EXPECT_EQ(d.m_align, idlc.m_align);
  EXPECT_EQ(d.m_nops, idlc.m_nops);
  ASSERT_EQ(d.m_nkeys, idlc.m_nkeys);
  for (uint32_t k = 0; k < d.m_nkeys; ++k) {
    EXPECT_STREQ(d.m_keys[k].m_name, idlc.m_keys[k].m_name);
    EXPECT_EQ(d.m_keys[k].m_offset, idlc.m_keys[k].m_offset) << "key " << k;
    EXPECT_EQ(d.m_keys[k].m_idx, idlc.m_keys[k].m_idx) << "key " << k;
  }
  constexpr uint32_t kKeyFlags = DDS_TOPIC_FIXED_KEY | DDS_TOPIC_FIXED_KEY_XCDR2;
  EXPECT_EQ(d.m_flagset & kKeyFlags, idlc.m_flagset & kKeyFlags);
  const auto ours = words(d), theirs = words(idlc);
  ASSERT_EQ(ours.size(), theirs.size());
  for (size_t i = 0; i < ours.size(); ++i)
    EXPECT_EQ(ours[i], theirs[i]) << "word " << i << " (op 0x" << std::hex << theirs[i] << ")";
  EXPECT_EQ(t.ops().size(), theirs.size());
}

void expect_same(const char* ros_name, const dds_topic_descriptor_t& idlc) { expect_same(registry(), ros_name, idlc); }

TEST(DdsRuntimeType, SameDescriptorAsIdlc) {
  expect_same("builtin_interfaces/msg/Time", builtin_interfaces_msg_dds__Time__desc);
  expect_same("rvc_test_msgs/msg/Deep", rvc_test_msgs_msg_dds__Deep__desc);
  expect_same("rvc_test_msgs/msg/Inner", rvc_test_msgs_msg_dds__Inner__desc);
  expect_same("rvc_test_msgs/msg/Nothing", rvc_test_msgs_msg_dds__Nothing__desc);
  expect_same("rvc_test_msgs/msg/Mixed", rvc_test_msgs_msg_dds__Mixed__desc);
  // Deep is reached through Inner before Wrap refers to it: a backward jump.
  expect_same("rvc_test_msgs/msg/Pair", rvc_test_msgs_msg_dds__Pair__desc);
}

// The same IDL file idlc compiled, read by rvc's IDL parser: its structs are
// plain IDL types named as idlc names them, keys included.
TEST(DdsRuntimeType, IdlFileGivesIdlcsDescriptors) {
  msg::TypeRegistry reg;
  reg.add_search_path(RVC_ORACLE_IDL);
  auto same = [&](const char* name, const dds_topic_descriptor_t& idlc) { expect_same(reg, name, idlc); };
  same("builtin_interfaces::msg::dds_::Time_", builtin_interfaces_msg_dds__Time__desc);
  same("rvc_test_msgs::msg::dds_::Mixed_", rvc_test_msgs_msg_dds__Mixed__desc);
  same("rvc_test_msgs::msg::dds_::Pair_", rvc_test_msgs_msg_dds__Pair__desc);
  same("rvc_test_msgs::msg::dds_::Nothing_", rvc_test_msgs_msg_dds__Nothing__desc);
  same("rvc_keyed::KeyedSeq", rvc_keyed_KeyedSeq_desc);
  same("rvc_keyed::TwoKeys", rvc_keyed_TwoKeys_desc);
  same("rvc_keyed::Listed", rvc_keyed_Listed_desc);
}

TEST(DdsRuntimeType, TypeNameIsTheRos2DdsName) {
  EXPECT_EQ(ros2_dds_type_name(registry().resolve("autoware_auto_vehicle_msgs/msg/GearReport")),
            "autoware_auto_vehicle_msgs::msg::dds_::GearReport_");
}

// CycloneDDS validates received samples with the ops: what rvc encodes must pass.
bool cyclone_accepts(const RuntimeTopicType& t, const std::string& sample) {
  std::vector<uint64_t> buf(sample.size() / 8 + 1);
  std::memcpy(buf.data(), sample.data() + 4, sample.size() - 4);
  uint32_t used = 0;
  return dds_stream_normalize_data(reinterpret_cast<char*>(buf.data()), &used,
                                   static_cast<uint32_t>(sample.size() - 4), sample[1] == 0, 1, t.ops().data()) != nullptr;
}

TEST(DdsRuntimeType, CycloneAcceptsWhatRvcEncodes) {
  const auto& type = registry().resolve("rvc_test_msgs/msg/Mixed");
  RuntimeTopicType t(type);
  const std::string json =
      R"({"stamp":{"sec":-3,"nanosec":7},"ok":true,"b":200,"c":65,"i8":-5,"u8":250,"i16":-300,"u16":60000,)"
      R"("i32":-70000,"u32":4000000000,"i64":-5000000000,"big":18446744073709551615,"f":1.5,"d":-2.25,)"
      R"("name":"hello","tag":"12345678","pos":[1,2,3],"samples":[1,-2,3],)"
      R"("inners":[{"x":1,"label":"a","raw":[1,2],"deep":{"id":9,"code":"xy"}}],"flags":[true,false,true],)"
      R"("words":["ab","abcd"],"codes":["a","abc"],)"
      R"("pair":[{"x":2,"label":"","raw":[0,0],"deep":{"id":1,"code":""}},{"x":3,"label":"bb","raw":[3,4],"deep":{"id":2,"code":"12345"}}],)"
      R"("many":[],"names":["n1","n2"],"more":["m"],"counts":[1,2,3,4],"nothing":{},"deep":{"id":-1,"code":"z"}})";
  for (bool big : {false, true}) {
    std::string sample, error;
    io::CdrWriteOptions o;
    o.big_endian = big;
    ASSERT_TRUE(io::json_to_cdr(type, json, sample, error, o)) << error;
    EXPECT_TRUE(cyclone_accepts(t, sample)) << (big ? "big endian" : "little endian");
    EXPECT_FALSE(cyclone_accepts(t, sample.substr(0, sample.size() - 12))) << "truncated";
  }
}

}  // namespace
}  // namespace rvc::transport::dds
