// Timescales: the published benchmark of MTL monitors (Ulus). Ten property
// families over the propositions p, q, r, s; each trace follows its family's
// pattern with random delays inside [lbound, ubound], so the property holds,
// and the monitor's cost, not the verdict, is what varies.
// Deterministic: a seed gives the same bytes on every machine (own PRNG, no
// std distributions).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace rvc::tools {

struct TimescalesOptions {
  std::string family;     // e.g. "AbsentAQ"
  int64_t lbound = -1;    // -1: 30% of ubound, as the published suite uses
  int64_t ubound = 10;
  uint64_t duration = 10000;  // steps (lines)
  uint64_t seed = 1;
};

const std::vector<std::string>& timescales_families();
bool is_timescales_family(const std::string& family);
int64_t effective_lbound(const TimescalesOptions& options);

// The family's past-time formula in Rye, exactly as Reelay's benchmark
// publishes it. `intended` fixes AbsentBQR's published bracketing, which binds
// historically to the left of -> only.
std::string timescales_formula(const std::string& family, int64_t lbound, int64_t ubound, bool intended = false);

// Writes `duration` JSON lines {"time":i,"p":..,...} with the family's propositions.
void generate_timescales(const TimescalesOptions& options, std::FILE* out);

}  // namespace rvc::tools
