// The end of an array that array quantifiers read ({all(ranges[*] > 0.2)}):
// the one step both decoders (JSON and CDR) take after its last element.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "io/field_tests.hpp"

namespace rvc::io {

// Each quantifier atom in `ids` gets its value (and margin, with robustness)
// from its fold. An element without a usable value leaves the atom as it was,
// as a wrong-type field does: in strict mode the message is refused (false,
// `error` says why), else a warning is added.
inline bool settle_quantifiers(const std::vector<int>& ids, const std::vector<spec::FieldTest>& tests,
                               std::vector<QuantFold>& folds, uint32_t elements, std::vector<uint8_t>& next,
                               std::vector<double>* next_margin, bool strict, std::string& error,
                               std::vector<std::string>* warnings) {
  for (int id : ids) {
    double margin = 0;
    std::string problem;
    const int r = quant_finish(tests[id], folds[id], elements, margin, problem);
    if (r >= 0) {
      next[id] = static_cast<uint8_t>(r);
      if (next_margin) (*next_margin)[id] = margin;
      continue;
    }
    if (strict) {
      error = problem;
      return false;
    }
    if (warnings) warnings->push_back(problem + "; it keeps its previous value");
  }
  return true;
}

}  // namespace rvc::io
