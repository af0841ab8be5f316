// .msg default and constant values read as rosidl reads them (msg/msg_values.hpp;
// rosidl_adapter/parser.py, parse_primitive_value_string: bool from
// true/false/1/0 in any case, integers by Python's int() then int(text, 0),
// floats by float()), encoded into every default sample; what rosidl refuses
// is refused at file:line:column. Expected bytes are written by hand
// (little-endian CDR after the 4-byte header), and the size limits of
// arrays, bounds and whole types.
#include <gtest/gtest.h>

#include <string>

#include "io/cdr_codec.hpp"
#include "msg/msg_parser.hpp"
#include "msg/type_registry.hpp"

namespace rvc {
namespace {

std::string hex(std::string_view bytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned char c : bytes) out += kHex[c >> 4], out += kHex[c & 15];
  return out;
}

// The body (after the header) of the sample `rvc msg encode` makes of {} for a type of one definition.
std::string default_sample(const std::string& definition) {
  msg::TypeRegistry registry;
  registry.add_definition("v_msgs/msg/T", definition, "T.msg");
  std::string sample, error;
  EXPECT_TRUE(io::json_to_cdr(registry.resolve("v_msgs/msg/T"), "{}", sample, error)) << error;
  return hex(sample.substr(sample.size() >= 4 ? 4 : 0));
}

std::string refusal(const std::string& definition) {
  msg::TypeRegistry registry;
  registry.add_definition("v_msgs/msg/T", definition, "T.msg");
  try {
    registry.resolve("v_msgs/msg/T");
  } catch (const msg::MsgError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(MsgValues, DefaultsAreEncodedAsRosidlReadsThem) {
  // The cases: every one was encoded as 0, false or [] before.
  EXPECT_EQ(default_sample("bool enable TRUE\n"), "01");
  EXPECT_EQ(default_sample("bool enable True\n"), "01");
  EXPECT_EQ(default_sample("bool b 1\n"), "01");  // was accepted, then every encode failed
  EXPECT_EQ(default_sample("uint8 a 0x10\n"), "10");
  EXPECT_EQ(default_sample("int32 b +5\n"), "05000000");
  EXPECT_EQ(default_sample("int16 c 007\n"), "0700");  // Python's int("007") is 7 (decimal)
  EXPECT_EQ(default_sample("float64 d nan\n"), "000000000000f87f");
  EXPECT_EQ(default_sample("bool[] flags [True, False]\n"), "020000000100");
  // More of the same rules.
  EXPECT_EQ(default_sample("int64 x -0x8000000000000000\n"), "0000000000000080");
  EXPECT_EQ(default_sample("uint64 y 18446744073709551615\n"), "ffffffffffffffff");
  EXPECT_EQ(default_sample("uint8 o 0o17\nuint8 b 0b101\nint8 u 1_0\n"), "0f050a");
  EXPECT_EQ(default_sample("float32 f 1_000.5\n"), "00207a44");
  EXPECT_EQ(default_sample("float64 i -Infinity\n"), "000000000000f0ff");
  EXPECT_EQ(default_sample("float64 e 1E3\n"), "0000000000408f40");
  EXPECT_EQ(default_sample("int32[2] a [0x10, -2]\n"), "10000000feffffff");
  EXPECT_EQ(default_sample("string s \"a \\\"q\\\"\"\n"), "060000006120227122" "00");
  EXPECT_EQ(default_sample("string[] s ['x', \"y,z\"]\n"), "02000000" "0200000078000000" "04000000792c7a00");
  EXPECT_EQ(default_sample("bool FLAG=TRUE\nuint8 k 0\n"), "00");
}

TEST(MsgValues, ConstantsAreReadTheSameWay) {
  msg::TypeRegistry registry;
  registry.add_definition("v_msgs/msg/C", "uint8 A=0x10\nbool B=TRUE\nuint64 C=0xFFFFFFFFFFFFFFFF\nint32 D=+5\n", "C.msg");
  const msg::MessageType& t = registry.resolve("v_msgs/msg/C");
  EXPECT_EQ(t.constant("A")->number, 16);
  EXPECT_EQ(t.constant("B")->number, 1);
  EXPECT_EQ(t.constant("C")->text, "18446744073709551615");  // exact: typed specs read this text
  EXPECT_EQ(t.constant("D")->number, 5);
}

TEST(MsgValues, WhatRosidlRefusesIsRefusedAtItsColumn) {
  EXPECT_EQ(refusal("bool b 2\n"), "T.msg:1:8: a bool value is true, false, 1 or 0 (any case), not '2'");
  EXPECT_EQ(refusal("int8 x 128\n"), "T.msg:1:8: 128 does not fit in int8");
  EXPECT_EQ(refusal("uint8 x -1\n"), "T.msg:1:9: -1 does not fit in uint8");
  EXPECT_EQ(refusal("int32 v 1.5\n"), "T.msg:1:9: not an integer for int32: '1.5'");
  EXPECT_EQ(refusal("int32 v 0x\n"), "T.msg:1:9: not an integer for int32: '0x'");
  EXPECT_EQ(refusal("int32 v 1__0\n"), "T.msg:1:9: not an integer for int32: '1__0'");
  EXPECT_EQ(refusal("float64 f 1e\n"), "T.msg:1:11: not a float64 value: '1e'");
  EXPECT_EQ(refusal("int32[2] a [1]\n"), "T.msg:1:12: the array needs exactly 2 elements, not 1");
  EXPECT_EQ(refusal("int32[<=1] a [1, 2]\n"), "T.msg:1:14: the array has at most 1 elements, not 2");
  EXPECT_EQ(refusal("int32[] a 1\n"), "T.msg:1:11: an array value is written [a, b, ...], not '1'");
  EXPECT_EQ(refusal("string<=3 s \"abcd\"\n"), "T.msg:1:13: a string of 4 bytes over its bound 3");
  EXPECT_EQ(refusal("uint8 K=0x100\n"), "T.msg:1:9: 0x100 does not fit in uint8");
  // Found by fuzz_msg: a string default that is not UTF-8 was accepted, and then no encoder could write it.
  EXPECT_EQ(refusal("string s \"a\xff\"\n"), "T.msg:1:10: a string value must be UTF-8 text without NUL bytes");
  EXPECT_EQ(refusal("string[] s ['\xc3']\n"), "T.msg:1:12: element 0: a string value must be UTF-8 text without NUL bytes");
}

TEST(MsgValues, SizesAreBoundedWhereTheyAreWritten) {
  EXPECT_EQ(refusal("int32[4294967295] a\n"),
            "T.msg:1:7: the array size 4294967295 is over rvc's limit of 16777216 (docs/ros2-types.md)");
  EXPECT_EQ(refusal("int32[99999999999999999999] a\n"),
            "T.msg:1:7: the array size 99999999999999999999 is over rvc's limit of 16777216 (docs/ros2-types.md)");
  EXPECT_EQ(refusal("int32[<=16777217] a\n"),
            "T.msg:1:9: the array bound 16777217 is over rvc's limit of 16777216 (docs/ros2-types.md)");
  EXPECT_EQ(refusal("string<=16777217 s\n"),
            "T.msg:1:9: the string bound 16777217 is over rvc's limit of 16777216 (docs/ros2-types.md)");
  EXPECT_EQ(refusal("uint8[16777216] a\nstring<=16777216 s\nint8[<=16777216] b\n"), "accepted");  // at the limit
  // A type whose smallest sample is over 64 MiB: 16 Mi float64 = 128 MiB.
  EXPECT_EQ(refusal("uint8 a\nfloat64[16777216] big\n"),
            "T.msg:2: field 'big' (float64[16777216]) makes the smallest sample of v_msgs/msg/T over rvc's limit of "
            "64 MiB (docs/ros2-types.md)");
  // Nested: 4096 x 4096 x 8 bytes, through a fixed array of a message.
  msg::TypeRegistry registry;
  registry.add_definition("v_msgs/msg/Row", "float64[4096] x\n", "Row.msg");
  registry.add_definition("v_msgs/msg/Grid", "v_msgs/Row[4096] rows\n", "Grid.msg");
  try {
    registry.resolve("v_msgs/msg/Grid");
    ADD_FAILURE() << "accepted";
  } catch (const msg::MsgError& e) {
    EXPECT_EQ(std::string(e.what()),
              "Grid.msg:1: field 'rows' (v_msgs/msg/Row[4096]) makes the smallest sample of v_msgs/msg/Grid over "
              "rvc's limit of 64 MiB (docs/ros2-types.md)");
  }
}

}  // namespace
}  // namespace rvc
