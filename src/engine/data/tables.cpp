#include "engine/data/tables.hpp"

namespace rvc::engine::data {

std::vector<Mask> free_variables(const Program& program) {
  std::vector<Mask> mask(program.code.size(), 0);
  for (size_t i = 0; i < program.code.size(); ++i) {
    const Instr& in = program.code[i];
    const Mask a = in.a >= 0 ? mask[static_cast<size_t>(in.a)] : 0;
    const Mask b = in.b >= 0 ? mask[static_cast<size_t>(in.b)] : 0;
    switch (in.code) {
      case Code::Bind: mask[i] = bit(in.var); break;
      case Code::Exists:
      case Code::Forall: mask[i] = a & ~bit(in.var); break;
      default: mask[i] = a | b; break;
    }
  }
  return mask;
}

Bindings::Bindings(const Program& program, const std::string& property, uint32_t max_values)
    : code_(program.code),
      variables_(program.variables),
      property_(property),
      max_values_(max_values),
      domains_(program.variables.size()),
      value_index_(program.variables.size()),
      index_of_instr_(program.code.size(), 0),
      masks_(free_variables(program)) {}

void Bindings::check_size(const Domains& before) {
  for (Mask m : masks_) {
    if (domains_.capacity(m) <= kMaxEntries) continue;
    domains_ = before;
    std::string vars;
    for (size_t v = 0; v < variables_.size(); ++v)
      if (m & bit(static_cast<int>(v))) vars += (vars.empty() ? "" : ", ") + variables_[v];
    throw DataLimitError("property '" + property_ + "': a sub-formula over variables " + vars + " would need more than " +
                         std::to_string(kMaxEntries) + " entries (one per combination of their values seen)");
  }
}

void Bindings::check_limit(int var) const {
  if (domains_.size(var) - 1 < max_values_) return;
  throw DataLimitError("property '" + property_ + "': variable '" + variables_[static_cast<size_t>(var)] +
                       "' would take more than " + std::to_string(max_values_) +
                       " distinct values (--max-data-values); each one costs memory and time per message");
}

}  // namespace rvc::engine::data
