// Loss accounting per publisher (hand-computed expectations).
#include <gtest/gtest.h>

#include "transport/seq_counter.hpp"

namespace rvc::transport {
namespace {

TEST(SeqCounters, GapsAndDuplicatesOfOnePublisher) {
  SeqCounters c;
  for (uint64_t s : {1, 2, 4, 4, 3, 5}) c.on_seq(s, 7);
  // 3 missing when 4 came (gap), then 4 again and 3 late: duplicates.
  EXPECT_EQ(c.received, 6u);
  EXPECT_EQ(c.gaps, 1u);
  EXPECT_EQ(c.duplicates, 2u);
  EXPECT_EQ(c.last_seq, 5u);
  c.on_eos(7, 7);  // 6 and 7 never came
  EXPECT_EQ(c.gaps, 3u);
  EXPECT_TRUE(c.all_ended());
}

TEST(SeqCounters, TwoPublishersInterleavedAreNotDuplicates) {
  SeqCounters c;
  for (uint64_t s = 1; s <= 3; ++s) {
    c.on_seq(s, 1);
    c.on_seq(s, 2);
  }
  c.on_eos(3, 1);
  EXPECT_FALSE(c.all_ended());  // publisher 2 still publishing
  c.on_eos(3, 2);
  EXPECT_TRUE(c.all_ended());
  EXPECT_EQ(c.received, 6u);
  EXPECT_EQ(c.gaps, 0u);
  EXPECT_EQ(c.duplicates, 0u);
  EXPECT_EQ(c.publishers(), 2u);
  EXPECT_EQ(c.last_seq, 6u);  // 3 announced by each
  EXPECT_EQ(c.restarts, 0u);
}

TEST(SeqCounters, RestartWithTheSameIdIsNotDuplicates) {
  SeqCounters c;
  for (uint64_t s = 1; s <= 4; ++s) c.on_seq(s, 9);
  for (uint64_t s = 1; s <= 2; ++s) c.on_seq(s, 9);  // the same publisher from 1 again
  EXPECT_EQ(c.restarts, 1u);
  EXPECT_EQ(c.duplicates, 0u);
  EXPECT_EQ(c.gaps, 0u);
  EXPECT_EQ(c.received, 6u);
}

TEST(SeqCounters, NewPublisherAfterAnEndOfStreamIsARestart) {
  SeqCounters c;
  c.on_seq(1, 5);
  c.on_seq(2, 5);
  c.on_eos(2, 5);
  c.on_seq(1, 6);  // the process ran again: a new id
  c.on_seq(2, 6);
  EXPECT_EQ(c.restarts, 1u);
  EXPECT_EQ(c.publishers(), 2u);
  EXPECT_FALSE(c.all_ended());
  EXPECT_EQ(c.duplicates + c.gaps, 0u);
}

// monitor --publishers 2: the second publisher, discovered only after the
// first ended (CI under ASan), is not a restart; a third one is.
TEST(SeqCounters, ExpectedPublishersDiscoveredLateAreNotRestarts) {
  SeqCounters c;
  c.expect(2);
  for (uint64_t s = 1; s <= 3; ++s) c.on_seq(s, 1);
  c.on_eos(3, 1);
  for (uint64_t s = 1; s <= 2; ++s) c.on_seq(s, 2);
  c.on_eos(2, 2);
  EXPECT_EQ(c.restarts, 0u);
  EXPECT_TRUE(c.all_ended());
  c.on_seq(1, 3);
  EXPECT_EQ(c.restarts, 1u);
  EXPECT_EQ(c.gaps + c.duplicates, 0u);
}

TEST(SeqCounters, UnnumberedMessagesAreCountedOnly) {
  SeqCounters c;
  c.on_seq(0);
  c.on_seq(0);
  EXPECT_EQ(c.received, 2u);
  EXPECT_EQ(c.gaps + c.duplicates, 0u);
}

}  // namespace
}  // namespace rvc::transport

// A monitor group's replica started mid-run (docs/fleet.md): a publisher's
// first number past 1 is where it joined, not a gap; gaps after it still count.
TEST(SeqCounters, JoiningMidStreamCountsTheNumbersBeforeAsBeforeJoinNotAsGaps) {
  rvc::transport::SeqCounters c;
  c.join_mid_stream();
  c.on_seq(41, 7);
  c.on_seq(42, 7);
  c.on_seq(44, 7);
  c.on_seq(1, 8);
  EXPECT_EQ(c.received, 4u);
  EXPECT_EQ(c.before_join, 40u);
  EXPECT_EQ(c.gaps, 1u);
  EXPECT_EQ(c.last_seq, 45u);  // 44 + 1: every number announced
  c.on_eos(44, 7);
  EXPECT_EQ(c.gaps, 1u);
  rvc::transport::SeqCounters plain;  // without it the same start is 40 lost
  plain.on_seq(41, 7);
  EXPECT_EQ(plain.gaps, 40u);
}
