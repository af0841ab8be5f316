// Verdict output (JSON lines) and the properties file loader.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "io/properties_file.hpp"
#include "io/verdict_writer.hpp"

#include "test_util.hpp"

namespace rvc::io {
namespace {

std::string number(double v) {
  std::string s;
  append_number(s, v);
  return s;
}

TEST(VerdictWriter, NumbersInShortestForm) {
  EXPECT_EQ(number(12), "12");  // integers without ".0"
  EXPECT_EQ(number(0), "0");
  EXPECT_EQ(number(-3), "-3");
  EXPECT_EQ(number(2.5), "2.5");
  EXPECT_EQ(number(0.1), "0.1");  // shortest round-trip, not 0.1000000000000000055
  EXPECT_EQ(number(1e20), "1e+20");
  EXPECT_EQ(number(123456789012), "123456789012");
  // Found by fuzz_cdr: 2^69's shortest plain form is 21 digits, which a JSON
  // reader may refuse as an integer; integral values that large use an exponent.
  EXPECT_EQ(number(std::ldexp(1.0, 69)), "5.902958103587057e+20");
  EXPECT_EQ(number(-std::ldexp(1.0, 69)), "-5.902958103587057e+20");
  EXPECT_EQ(number(9007199254740992.0), "9.007199254740992e+15");
}

TEST(VerdictWriter, JsonStringEscapes) {
  std::string s;
  append_json_string(s, "a\"b\\c\nd\te\rf\x01g");
  EXPECT_EQ(s, "\"a\\\"b\\\\c\\nd\\te\\rf\\u0001g\"");
}

TEST(VerdictWriter, VerdictLine) {
  std::string out;
  append_verdict(out, 12, true, "p1", false);
  append_verdict(out, 2.5, false, "speed \"limit\"", true);
  EXPECT_EQ(out,
            "{\"time\":12,\"property\":\"p1\",\"value\":false}\n"
            "{\"time\":2.5,\"property\":\"speed \\\"limit\\\"\",\"value\":true}\n");
}

// ---------------------------------------------------------------- properties

TEST(PropertiesFile, ListOfNamedSpecs) {
  test::TempFile f(
      "properties:\n"
      "  - name: hazard\n"
      "    spec: historically({emergency} -> once[0:1]{hazard_lights})\n"
      "  - name: slow\n"
      "    spec: \"{speed < 3}\"\n");
  auto props = load_properties(f.path());
  ASSERT_EQ(props.size(), 2u);
  EXPECT_EQ(props[0].name, "hazard");
  EXPECT_EQ(props[0].spec, "historically({emergency} -> once[0:1]{hazard_lights})");
  EXPECT_EQ(props[1].name, "slow");
  EXPECT_EQ(props[1].spec, "{speed < 3}");
}

TEST(PropertiesFile, PlainMapAndUnnamedList) {
  test::TempFile map("a: \"{p}\"\nb: once {q}\n");
  auto m = load_properties(map.path());
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].name, "a");
  EXPECT_EQ(m[0].spec, "{p}");
  EXPECT_EQ(m[1].name, "b");
  EXPECT_EQ(m[1].spec, "once {q}");
  test::TempFile list("- \"{p}\"\n- name: named\n  spec: \"{q}\"\n- \"{r}\"\n");
  auto l = load_properties(list.path());
  ASSERT_EQ(l.size(), 3u);
  EXPECT_EQ(l[0].name, "p1");  // unnamed: p<position>
  EXPECT_EQ(l[1].name, "named");
  EXPECT_EQ(l[2].name, "p3");
}

TEST(PropertiesFile, JsonIsYaml) {
  test::TempFile f(R"({"properties": [{"name": "x", "spec": "{p} -> pre {q}"}]})");
  auto props = load_properties(f.path());
  ASSERT_EQ(props.size(), 1u);
  EXPECT_EQ(props[0].name, "x");
  EXPECT_EQ(props[0].spec, "{p} -> pre {q}");
}

void expect_properties_error(const std::string& content, const std::string& fragment) {
  test::TempFile f(content);
  try {
    load_properties(f.path());
    ADD_FAILURE() << "loaded: " << content;
  } catch (const PropertiesError& e) {
    std::string what = e.what();
    EXPECT_EQ(what.rfind(f.path(), 0), 0u) << what;  // names the file first
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
  }
}

TEST(PropertiesFile, Errors) {
  expect_properties_error("a: \"{p}\"\na: \"{q}\"\n", "duplicate property name 'a'");
  expect_properties_error("- name: a\n  spec: \"{p}\"\n- name: a\n  spec: \"{q}\"\n", "duplicate property name 'a'");
  expect_properties_error("properties: []\n", "no properties defined");
  expect_properties_error("42\n", "expected a list of properties or a map");
  // The second item (line 4, column 5) has no spec.
  expect_properties_error("properties:\n  - name: a\n    spec: \"{p}\"\n  - name: b\n", ":4:5: each property needs a 'spec'");
  expect_properties_error("a:\n  - \"{p}\"\n", "expected 'name: spec'");
  expect_properties_error("a: [unclosed\n", ":");
  EXPECT_THROW(load_properties("/nonexistent/rvc/props.yaml"), PropertiesError);
}

}  // namespace
}  // namespace rvc::io

namespace rvc::io {
namespace {

std::string load_error(const std::string& yaml) {
  test::TempFile f(yaml);
  try {
    load_properties(f.path());
    return "";
  } catch (const PropertiesError& e) {
    return e.what();
  }
}

TEST(PropertiesFileHostile, UnknownKeysAreNamedWithTheirPosition) {
  std::string e = load_error("properties:\n  - name: x\n    sepc: '{p}'\n    spec: '{q}'\n");
  EXPECT_NE(e.find(":3:5: unknown key 'sepc' (a property has 'name', 'spec' and optionally 'level')"), std::string::npos) << e;
  e = load_error("properties:\n  - name: x\n    spec: '{q}'\nversion: 2\n");
  EXPECT_NE(e.find(":4:1: unknown key 'version' next to 'properties'"), std::string::npos) << e;
}

TEST(PropertiesFileHostile, SecondDocumentIsRefusedNotDropped) {
  std::string e = load_error("a: '{p}'\n---\nb: '{q}'\n");
  EXPECT_NE(e.find(":3:1: a second YAML document starts here"), std::string::npos) << e;
}

TEST(PropertiesFileHostile, SpecMustBeAString) {
  std::string e = load_error("properties:\n  - name: x\n    spec: ['{p}', '{q}']\n");
  EXPECT_NE(e.find(":3:11: 'spec' must be a string"), std::string::npos) << e;
  EXPECT_NE(load_error("").find("no properties defined"), std::string::npos);
}

}  // namespace
}  // namespace rvc::io
