// Which endpoints would feed a monitor or bridge its own output.
#include <gtest/gtest.h>

#include <stdexcept>

#include "test_util.hpp"
#include "transport/transport_options.hpp"

namespace rvc::transport {
namespace {

TEST(EndpointsOverlap, ZenohKeyExpressions) {
#ifdef RVC_HAVE_ZENOH
  EXPECT_TRUE(endpoints_overlap("zenoh:a/**", "zenoh:a/b"));
  EXPECT_TRUE(endpoints_overlap("zenoh:a/b", "zenoh:a/**"));
  EXPECT_TRUE(endpoints_overlap("zenoh:loop/**", "zenoh:loop/verdicts"));
  EXPECT_TRUE(endpoints_overlap("zenoh:**", "zenoh:x/y/z"));
  EXPECT_TRUE(endpoints_overlap("zenoh:a/*", "zenoh:a/b"));
  EXPECT_FALSE(endpoints_overlap("zenoh:a/*", "zenoh:a/b/c"));  // * is one chunk
  EXPECT_FALSE(endpoints_overlap("zenoh:in/**", "zenoh:out/verdicts"));
  EXPECT_TRUE(endpoints_overlap("zenoh:a/b$*", "zenoh:a/bc"));  // a sub-chunk wildcard
  EXPECT_THROW(endpoints_overlap("zenoh:a//b", "zenoh:a"), std::invalid_argument);
#else
  GTEST_SKIP() << "built without Zenoh";
#endif
}

TEST(EndpointsOverlap, DdsTopicsFilesAndSchemes) {
  EXPECT_TRUE(endpoints_overlap("dds:/rv/a", "dds:rv/a"));
  EXPECT_FALSE(endpoints_overlap("dds:/rv/a", "dds:/rv/b"));
  EXPECT_FALSE(endpoints_overlap("dds:/rv/a", "zenoh:rv/a"));  // different networks
  test::TempFile f("{}\n");
  EXPECT_TRUE(endpoints_overlap(f.path(), "file:" + f.path()));
  EXPECT_FALSE(endpoints_overlap("-", "-"));  // stdin vs stdout
}

}  // namespace
}  // namespace rvc::transport
