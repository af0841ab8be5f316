// Bounded future operators (issue 29) are monitored online with a delay: a
// formula whose value at t looks ahead at most h (its horizon) is rewritten
// into a past-only formula whose value at t is the original's at t − h
// ("pastification", as RTAMT does). The engines then run it unchanged, O(1)
// amortized per event whatever the bounds, and the checker reports the value
// at t as the verdict for t − h, known at t (engine/checker.hpp).
//
// The rules (docs/semantics.md, "Bounded future", derives them). P(φ, d) is
// true at monitor time t iff φ holds at t − d, for every d >= horizon(φ):
//   P(atom, d)            = once[d:d] atom                     (atom when d = 0)
//   P(not/and/or/->)      = the same over the operands' P(·, d)
//   P(eventually[a:b] ψ, d) = once[0:b−a] (P(ψ, d−b) and not E(d−b))
//   P(always[a:b] ψ, d)   = historically[0:b−a] (P(ψ, d−b) or E(d−b))
//   P(next ψ, d)          = P(ψ, d−1) and not E(d−1)
//   P(φ until[a:b] ψ, d)  = discrete only, with w = b − a and e = d − b:
//        or over k in 0..w of  once[w−k:w−k] (P(ψ,e) and not E(e)) and historically[w−k+1:b] P(φ,e)
//   P(once[a:b] φ, d)     = once[a:b] (P(φ, d) and S(d))
//   P(historically[a:b] φ, d) = historically[a:b] (P(φ, d) or not S(d))
//   P(φ since[a:b] ψ, d)  = P(φ, d) since[a:b] (P(ψ, d) and S(d))
//   P(pre φ, d)           = pre (P(φ, d) and S(d))
// S(d) = once[d:] true says "the time referred to is not before the stream's
// start", so past operators see no step before 0 (their Reelay semantics).
// E(e) = once[e:e] {end} says "the operand's time is past the end of the
// stream": the checker sets the end marker atom only while it settles the
// last verdicts after the last message (Checker::finish), so a future
// operator's window is cut at the end of the stream: eventually needs a
// witness inside the stream, always only the steps the stream has.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "spec/ast.hpp"

namespace rvc::spec {

// How far ahead of t φ's value at t looks: 0 for a past-only formula.
double horizon(const Node& node);
// Any future operator in it (horizon 0 too: until[0:0], eventually[0:0]).
bool has_future(const Node& node);

// until[a:b] is rewritten into b − a + 1 terms (no past operator picks the
// first witness of a sliding window in O(1)): wider windows are refused.
inline constexpr double kMaxUntilWindow = 256;

// The most nodes a rewrite may have: what one property alone may take in a
// discrete monitor (engine/discrete/monitor.cpp: 65535 slots, two of them the
// constants), and far below what makes building it slow.
inline constexpr uint64_t kMaxPastifiedNodes = 65000;

// The number of nodes pastify(root, h, ...) makes, computed in time linear in
// `root` without making them (saturating at 2^62). Throws pastify's SpecErrors
// about until (dense time, window width).
uint64_t pastified_size(const Node& root, double h, bool dense, const std::string& source);

// Rewrites `root` (horizon h > 0) into a past-only formula whose value at t is
// root's at t − h. `end_marker` is the end-of-stream atom (see above); `dense`
// refuses `until` (no finite rewrite). A rewrite of more than
// kMaxPastifiedNodes nodes is refused before it is made. Throws SpecError
// with the column.
NodePtr pastify(const Node& root, double h, const FieldTest& end_marker, bool dense, const std::string& source);

}  // namespace rvc::spec
