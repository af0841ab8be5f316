// Numbers compared exactly. A double holds every integer up to 2^53; beyond
// that, 64-bit integers (JSON integer literals, int64/uint64 fields, spec
// constants) are kept as integers beside their rounded double, so
// {u == 9223372036854775807} is false for 2^63 and {t > 1700000000000000000}
// true for ...001. Integers never round through double when compared, with
// each other or with a double: the comparison is the exact one of the two
// real values (as Python compares an int with a float). The double stays the
// value for everything that computes (robustness margins, times).
#pragma once

#include <cmath>
#include <cstdint>
#include <string_view>

namespace rvc::spec {

// An integer beyond +-2^53 (a double might not hold it); None: the number is
// its double exactly.
struct ExactInt {
  enum Kind : uint8_t { None, Signed, Unsigned } kind = None;
  uint64_t bits = 0;  // Signed: an int64_t's bits; Unsigned: a value >= 2^63
  bool operator==(const ExactInt& o) const { return kind == o.kind && bits == o.bits; }
};

inline constexpr double kTwo53 = 9007199254740992.0;

// The integer, kept exactly only where a double may not hold it.
inline ExactInt exact_of(int64_t v) {
  if (v >= -(int64_t{1} << 53) && v <= (int64_t{1} << 53)) return {};
  return {ExactInt::Signed, static_cast<uint64_t>(v)};
}
inline ExactInt exact_of(uint64_t v) {
  if (v <= (uint64_t{1} << 53)) return {};
  if (v <= static_cast<uint64_t>(INT64_MAX)) return {ExactInt::Signed, v};
  return {ExactInt::Unsigned, v};
}

// Three-way comparison results; Unordered when a NaN is involved.
enum Order : int { Less = -1, Equal = 0, Greater = 1, Unordered = 2 };

inline Order order_of(double a, double b) {
  return a < b ? Less : a > b ? Greater : a == b ? Equal : Unordered;
}

// An integer against a double, exactly. No long double: floor(d) of a double
// within the integer type's range is itself an integer of that type.
inline Order order_int_double(const ExactInt& x, double d) {
  if (std::isnan(d)) return Unordered;
  if (x.kind == ExactInt::Unsigned) {
    if (d < 9223372036854775808.0) return Greater;   // x >= 2^63
    if (d >= 18446744073709551616.0) return Less;    // x < 2^64
    const auto u = static_cast<uint64_t>(d);         // an integer: d >= 2^63 > 2^53
    return x.bits < u ? Less : x.bits > u ? Greater : Equal;
  }
  const auto i = static_cast<int64_t>(x.bits);
  if (d >= 9223372036854775808.0) return Less;
  if (d < -9223372036854775808.0) return Greater;
  const double f = std::floor(d);  // in [-2^63, 2^63): an int64
  const auto fi = static_cast<int64_t>(f);
  if (i != fi) return i < fi ? Less : Greater;
  return d > f ? Less : Equal;  // i == floor(d): equal, or below d's fraction
}

inline Order order_ints(const ExactInt& a, const ExactInt& b) {
  if (a.kind != b.kind) return a.kind == ExactInt::Unsigned ? Greater : Less;  // every Unsigned is >= 2^63
  if (a.kind == ExactInt::Unsigned) return a.bits < b.bits ? Less : a.bits > b.bits ? Greater : Equal;
  const auto x = static_cast<int64_t>(a.bits), y = static_cast<int64_t>(b.bits);
  return x < y ? Less : x > y ? Greater : Equal;
}

// a (its double da, exactly ea) against b.
inline Order order_numbers(double da, const ExactInt& ea, double db, const ExactInt& eb) {
  if (ea.kind == ExactInt::None && eb.kind == ExactInt::None) return order_of(da, db);
  if (ea.kind != ExactInt::None && eb.kind != ExactInt::None) return order_ints(ea, eb);
  if (ea.kind != ExactInt::None) return order_int_double(ea, db);
  const Order o = order_int_double(eb, da);
  return o == Unordered || o == Equal ? o : o == Less ? Greater : Less;
}

// An integer literal (an optional sign, then digits only) read exactly: its
// double and, beyond 2^53, the integer. False when `text` is no integer
// literal or lies beyond the 64-bit range (the caller keeps its double).
bool integer_literal(std::string_view text, double& d, ExactInt& exact);

// The exact integer's decimal text.
void append_exact(std::string& out, const ExactInt& x);

}  // namespace rvc::spec
