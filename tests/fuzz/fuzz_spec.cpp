// libFuzzer harness: the Rye parser (src/spec) and the compiler into monitors
// (src/engine), discrete and dense.
//
// Any input must end as an accepted property or a SpecError: another
// exception escapes and counts as a crash, as do ASan/UBSan findings and
// stack overflows. Oracle: the canonical text of an accepted spec parses back
// to the same canonical text (a fixed point), so the printer and the parser
// agree on precedence, quoting and bounds.
#include <cstdint>
#include <cstdlib>
#include <string>

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
  try {
    checker.add_property({"p", text});
  } catch (const rvc::spec::SpecError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  check(text, false);
  check(text, true);
  return 0;
}
