// Grammar fuzz helpers shared by the parser's unit tests (array quantifiers,
// expression atoms): random token soup, and what an accepted spec must do.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <exception>
#include <initializer_list>
#include <random>
#include <string>

#include "runtime/pipeline.hpp"
#include "spec/parser.hpp"
#include "spec/spec_error.hpp"

namespace rvc::test {

// 1..max_tokens tokens drawn from `tokens`, each followed by a space half the time.
template <size_t N>
std::string token_soup(std::mt19937& rng, const char* const (&tokens)[N], int max_tokens) {
  std::string s;
  for (int k = 1 + static_cast<int>(rng() % static_cast<unsigned>(max_tokens)); k > 0; --k) {
    s += tokens[rng() % N];
    if (rng() % 2) s += ' ';
  }
  return s;
}

// False when `s` is refused (a SpecError: random text mostly is). Else its
// canonical text must parse back to itself (a fixed point), and the spec runs
// on `trace` without a crash: an exception there is a refusal (e.g.
// robustness with data references), never a failure of the test.
inline bool accepted_round_trips_and_runs(const std::string& s, bool robust,
                                          std::initializer_list<const char*> trace) {
  spec::NodePtr ast;
  try {
    ast = spec::parse(s);
  } catch (const spec::SpecError&) {
    return false;
  }
  const std::string printed = spec::to_string(*ast);
  EXPECT_EQ(spec::to_string(*spec::parse(printed)), printed) << s;
  runtime::PipelineOptions po;
  po.robustness = robust;
  testing::internal::CaptureStderr();
  try {
    runtime::Pipeline p({{"p", s}}, po, nullptr);
    uint64_t n = 0;
    for (const char* line : trace) p.feed(line, ++n);
  } catch (const std::exception&) {
  }
  testing::internal::GetCapturedStderr();
  return true;
}

}  // namespace rvc::test
