// libFuzzer harness: the Rye parser (src/spec) and the compiler into monitors
// (src/engine), discrete and dense.
//
// Any input must end as an accepted property or a SpecError: another
// exception escapes and counts as a crash, as do ASan/UBSan findings and
// stack overflows. Oracle: the canonical text of an accepted spec parses back
// to the same canonical text (a fixed point), so the printer and the parser
// agree on precedence, quoting and bounds.
//
// Short accepted specs are then run for a few steps with atom values and
// bound values taken from the input's bytes, so the monitors (data
// references too: new values, tables laid out again) run under ASan/UBSan.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "spec/parser.hpp"

namespace {

void check(const std::string& text, bool dense) {
  rvc::spec::ParseOptions options;
  options.dense = dense;
  rvc::spec::NodePtr ast;
  try {
    ast = rvc::spec::parse(text, options);
  } catch (const rvc::spec::SpecError&) {
    return;
  }
  const std::string printed = rvc::spec::to_string(*ast);
  try {
    if (rvc::spec::to_string(*rvc::spec::parse(printed, options)) != printed) std::abort();
  } catch (const rvc::spec::SpecError&) {
    std::abort();  // the printer wrote something the parser refuses
  }
  rvc::engine::Checker checker(dense ? rvc::engine::TimeModel::Dense : rvc::engine::TimeModel::Discrete, false,
                               nullptr);
  checker.set_max_data_values(40);
  try {
    checker.add_property({"p", text});
  } catch (const rvc::spec::SpecError&) {
    return;
  }
  if (text.size() > 160) return;  // keeps each run fast; long specs are parsed and compiled above
  std::vector<uint8_t> atoms(checker.atoms().size());
  std::vector<uint32_t> bound(checker.atoms().size());
  uint32_t h = 2166136261u;
  for (unsigned char c : text) h = (h ^ c) * 16777619u;
  double begin = 0;
  try {
    for (int step = 0; step < 24; ++step) {
      for (size_t i = 0; i < atoms.size(); ++i) {
        h = h * 1103515245u + 12345u;
        atoms[i] = (h >> 16) & 1;
        bound[i] = (h >> 20) % 9;  // 0: no value yet; up to 8 distinct values per variable
      }
      if (dense) {  // contiguous segments, as messages cut time
        const double end = begin + 0.25 * (1 + h % 3);
        checker.step(begin, end, atoms.data(), bound.data());
        begin = end;
      } else {
        checker.step(atoms.data(), bound.data());
      }
    }
    checker.finish();  // bounded future: settles the last horizon (the end marker's steps)
  } catch (const rvc::engine::data::DataLimitError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  check(text, false);
  check(text, true);
  return 0;
}
