// Dense time, exact to the nanosecond (issue 36).
//
// Instants are integer nanoseconds (int64: +-292 years around the epoch), read
// exactly from what carries them: a bag's log time, a builtin_interfaces/Time
// {sec, nanosec}, or the decimal text of a JSON number of seconds
// ("1746721937.599626818") — never through a double, which at epoch scale
// resolves only about 240 ns, so two stamps exactly 25 ms apart could differ
// by 25.0000002 ms.
//
// Inside the engine a dense instant is the offset from the run's origin (the
// first message's stamp by default, 0 with --origin zero) in nanoseconds,
// held in a double: every integer up to 2^53 (kExactSpanNs, 104 days) is a
// double exactly, and so are sums and differences below it, so windows, ages,
// deadlines and horizons are integer arithmetic, while +inf still means
// "never" and "unbounded" as the monitors expect. Spec bounds are read from
// their text to integer nanoseconds and refused beyond kExactSpanNs.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace rvc::spec {

// 2^53 ns (9007199.254740992 s, about 104 days): the span within which dense
// instants and bounds are exact.
inline constexpr int64_t kExactSpanNs = int64_t{1} << 53;
inline constexpr double kExactSpanSeconds = 9007199.254740992;
inline constexpr int64_t kNsPerSecond = 1000000000;

enum class SecondsStatus { Ok, Malformed, OutOfRange };

// The decimal text of a number of seconds (JSON number syntax, an optional
// leading '+', an exponent allowed: "1.5", "1746721937.599626818", "25e-3")
// as integer nanoseconds. Digits past the ninth decimal are rounded to the
// nearest nanosecond (ties to even); a value outside int64 nanoseconds is
// OutOfRange. Trailing spaces are ignored.
SecondsStatus parse_seconds(std::string_view text, int64_t& ns);

// (sec, nanosec) of a builtin_interfaces/Time (or any integer pair) as
// nanoseconds; false on overflow.
bool time_to_ns(int64_t sec, int64_t nanosec, int64_t& ns);

// Nanoseconds as decimal seconds, exactly: no exponent, at most 9 decimals,
// trailing zeros dropped ("1746721937.59962682", "5", "-0.5").
void append_seconds(std::string& out, int64_t ns);
std::string seconds_text(int64_t ns);

// A number of seconds held in a double (a spec literal) as nanoseconds, in
// a double: exact for what decimal text of at most 15 significant digits
// meant (the double's shortest text is read exactly), +-inf and NaN kept,
// +-inf beyond int64 nanoseconds.
double seconds_to_ns(double seconds);

}  // namespace rvc::spec
