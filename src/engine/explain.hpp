// --explain outside the shared discrete monitor: why a property has its
// value at one moment, as sentences that walk the formula from the root and
// follow only the operands that decide the value, down to the atoms (or to a
// temporal operator, whose reason lies in its window). The wording is that of
// discrete::Monitor::explain ("{x > 3} is false at step 12"); dense time
// names times in seconds and intervals ("{brake} is false throughout
// [3.5, 5)", "{brake} never held in [2, 3.5]"), data references name the
// value of the quantified variable that decides ("for f = \"a.txt\": ...").
//
// A Walker reads the values the monitor already holds for the moment
// explained: nothing is computed before a violation starts. Header-only (the
// monitors of src/engine/dense and src/engine/data each derive one).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "engine/program.hpp"
#include "spec/exact_time.hpp"

namespace rvc::engine::explain {

// At most this many sentences: for a wide formula the first reasons are enough
// (the same limit as discrete::Monitor::explain).
inline constexpr size_t kMaxSentences = 16;

// Names a bound value by its id (io::BoundValues) as JSON text: "\"a.txt\"",
// 3, true. Empty (or no function): the sentence names where the value came
// from instead ("the value of file at step 3").
using ValueNames = std::function<std::string(uint32_t id)>;

// A time in seconds with the fewest digits that give it back within a few
// units in the last place: 3.3 - 1.5 is "1.8", not "1.7999999999999998".
// Dense time: the instant engine time 0 stands for (engine::Checker sets it
// while its monitors explain: their times are nanoseconds from the origin,
// spec/exact_time.hpp).
inline thread_local int64_t origin_ns = 0;
inline thread_local bool nanoseconds = false;  // engine times are ns from origin_ns (else plain seconds)

// A dense engine time as the instant's seconds: exactly, from nanoseconds;
// else the shortest text that reads back close to it.
inline std::string seconds(double v) {
  if (!std::isfinite(v)) return v > 0 ? "inf" : "-inf";
  if (nanoseconds) return spec::seconds_text(origin_ns + static_cast<int64_t>(std::llround(v)));
  const double a = std::fabs(v);
  const double tolerance = std::max(1e-12, 8 * (std::nextafter(a, std::numeric_limits<double>::infinity()) - a));
  char buf[64];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::fabs(std::strtod(buf, nullptr) - v) <= tolerance) break;
  }
  return buf;
}

class Walker {
 public:
  // `now`: the step (discrete) or the time in seconds (dense) explained.
  Walker(const Program& program, bool dense, double now) : program_(program), dense_(dense), now_(now) {}
  virtual ~Walker() = default;

  std::vector<std::string> run() {
    out_.clear();
    if (!program_.code.empty()) why(program_.code.size() - 1);
    return out_;
  }

 protected:
  // Instruction i's value at the moment explained, under assignment_.
  virtual bool value(size_t i) const = 0;
  // Where an atom's value holds: "at step 4", "throughout [3.5, 5)".
  virtual std::string held(size_t i) const = 0;
  // Data references. Variable v's indexes: 0 stands for every value not seen
  // yet, 1.. for the values seen (data/tables.hpp).
  virtual uint32_t indexes(int /*var*/) const { return 1; }
  // The indexes the tests binding v hold at the moment (their fields' values).
  virtual std::vector<uint32_t> bound_now(int /*var*/) const { return {}; }
  // How a sentence names index k of variable v (0: "any value not seen yet").
  virtual std::string value_name(int /*var*/, uint32_t /*index*/) const { return "any value not seen yet"; }

  const Program& program_;
  std::array<uint32_t, kMaxVariables> assignment_{};  // each quantified variable's index, where fixed

 private:
  static const char* word(bool v) { return v ? "true" : "false"; }

  void say(std::string sentence) {
    if (context_.empty()) {
      out_.push_back(std::move(sentence));
      return;
    }
    std::string prefix = "for ";
    for (size_t k = 0; k < context_.size(); ++k)
      prefix += (k ? ", " : "") + program_.variables[static_cast<size_t>(context_[k].first)] + " = " + context_[k].second;
    out_.push_back(prefix + ": " + sentence);
  }

  // The part of the timeline an operator's bounds look at now: "at steps
  // 0..4" (as discrete::Monitor's range_text), "in [2, 3.5]" (dense: closed,
  // and nothing before time 0).
  std::string window(const spec::Bounds& b) const {
    if (!dense_) {
      using Step = int64_t;
      constexpr Step kForever = std::numeric_limits<Step>::max() / 4;  // discrete::kForever
      const auto now = static_cast<Step>(now_);
      const Step from = b.hi >= static_cast<double>(kForever) ? 0 : std::max<Step>(0, now - static_cast<Step>(b.hi));
      const Step to = now - static_cast<Step>(b.lo);
      if (to < from) return "at no step yet";
      return from == to ? "at step " + std::to_string(from)
                        : "at steps " + std::to_string(from) + ".." + std::to_string(to);
    }
    const double from = std::isinf(b.hi) ? 0 : std::max(0.0, now_ - b.hi);  // ns from the origin
    const double to = now_ - b.lo;
    if (to < from) return "at no time yet";  // the window is still before time 0
    return from == to ? "at time " + seconds(from) : "in [" + seconds(from) + ", " + seconds(to) + "]";
  }

  void why(size_t i) {
    if (out_.size() >= kMaxSentences) return;
    const Instr& in = program_.code[i];
    const std::string& text = program_.text[i];
    const bool v = value(i);
    const size_t a = static_cast<size_t>(in.a), b = static_cast<size_t>(in.b);
    switch (in.code) {
      case Code::Atom:
      case Code::Bind: say(text + " is " + word(v) + " " + held(i)); return;
      case Code::True:
      case Code::False: return;
      case Code::Exists:
      case Code::Forall: quantifier(i); return;
      case Code::Not: why(a); return;
      case Code::And:
        if (v) {
          why(a);
          why(b);
        } else {
          why(!value(a) ? a : b);
        }
        return;
      case Code::Or:
        if (v) {
          why(value(a) ? a : b);
        } else {
          why(a);
          why(b);
        }
        return;
      case Code::Implies:
        if (v) {
          why(!value(a) ? a : b);
        } else {
          why(a);
          why(b);
        }
        return;
      case Code::Pre: {  // discrete time only (the compiler refuses it in dense time)
        const auto at = static_cast<int64_t>(now_);
        say(text + " is " + word(v) +
            (at == 0 ? ": there is no previous step"
                     : ": " + program_.text[a] + " was " + word(v) + " at step " + std::to_string(at - 1)));
        return;
      }
      case Code::Once:
        say(text + " is " + word(v) + ": " + program_.text[a] + (v ? " held at least once " : " never held ") +
            window(in.bounds));
        if (!v && in.bounds.lo == 0) why(a);  // nothing now either: why not
        return;
      case Code::Historically:
        say(text + " is " + word(v) + ": " + program_.text[a] +
            (v ? (dense_ ? " held at all times " : " held every time ") : " failed at least once ") +
            window(in.bounds));
        if (!v && in.bounds.lo == 0 && !value(a)) why(a);  // failing now: what broke it
        return;
      case Code::Since: {
        // Dense: "until now" because Reelay's dense since wants the left side at the moment itself too.
        const std::string after = dense_ ? " from then until now" : " at every step after";
        say(text + " is " + word(v) + ": " + program_.text[b] +
            (v ? " held " + window(in.bounds) + " and " + program_.text[a] + after
               : " never held " + window(in.bounds) + " with " + program_.text[a] + " holding" + after));
        if (!v && !value(a)) why(a);  // the left side failing now ended it
        return;
      }
    }
  }

  // exists/forall. A witness decides when one value does (forall false,
  // exists true): name it and explain the body for it. Otherwise every value
  // gives the body the same value: say so, and explain the body for the
  // values the binding tests hold now (the ones a reader looks for).
  // exists[x, y] is two instructions with one text: explained as one.
  void quantifier(size_t i) {
    const Code code = program_.code[i].code;
    const bool v = value(i);
    std::vector<int> vars;
    size_t body = i;
    do {
      vars.push_back(program_.code[body].var);
      body = static_cast<size_t>(program_.code[body].a);
    } while (program_.code[body].code == code && program_.text[body] == program_.text[i]);
    const std::string& text = program_.text[i];
    const std::string& body_text = program_.text[body];
    const size_t depth = context_.size();
    const bool witness = (code == Code::Forall) != v;  // forall false, exists true
    if (witness) {
      std::string names;
      size_t others = 0;
      size_t chain = i;
      for (const int var : vars) {
        // The next link (or the body) has this quantifier's value for the witness.
        const size_t next = static_cast<size_t>(program_.code[chain].a);
        const std::vector<uint32_t> order = candidates(var);
        uint32_t found = 0;
        size_t matching = 0;
        for (const uint32_t k : order) {
          assignment_[static_cast<size_t>(var)] = k;
          if (value(next) == v && matching++ == 0) found = k;
        }
        assignment_[static_cast<size_t>(var)] = found;
        if (vars.size() == 1 && matching > 0) others = matching - 1;
        names += (names.empty() ? "" : ", ") + program_.variables[static_cast<size_t>(var)] + " = " +
                 value_name(var, found);
        chain = next;
      }
      say(text + " is " + word(v) + ": " + body_text + " is " + word(v) + " for " + names +
          (others ? " (and for " + std::to_string(others) + (others == 1 ? " other value)" : " other values)") : ""));
      for (size_t k = 0; k < vars.size(); ++k) {
        const int var = vars[k];
        context_.emplace_back(var, value_name(var, assignment_[static_cast<size_t>(var)]));
      }
      why(body);
      context_.resize(depth);
      return;
    }
    std::string every, seen;
    for (const int var : vars) {
      every += (every.empty() ? "" : ", ") + program_.variables[static_cast<size_t>(var)];
      seen += (seen.empty() ? "" : ", ") + std::to_string(indexes(var) - 1);
    }
    say(text + " is " + word(v) + ": " + body_text + " is " + word(v) + " for every value of " + every + " (" + seen +
        " seen so far, and any other)");
    // The values bound now, one per variable; none bound: the sentence above is the reason.
    for (const int var : vars) {
      const std::vector<uint32_t> now = bound_now(var);
      if (now.empty()) {
        context_.resize(depth);
        return;
      }
      assignment_[static_cast<size_t>(var)] = now.front();
      context_.emplace_back(var, value_name(var, now.front()));
    }
    why(body);
    context_.resize(depth);
  }

  // Variable v's indexes in the order a witness is looked for: the values
  // bound now, the other values seen, then "any value not seen yet".
  std::vector<uint32_t> candidates(int var) const {
    std::vector<uint32_t> order = bound_now(var);
    for (uint32_t k = 1; k < indexes(var); ++k)
      if (std::find(order.begin(), order.end(), k) == order.end()) order.push_back(k);
    order.push_back(0);
    return order;
  }

  bool dense_;
  double now_;
  std::vector<std::pair<int, std::string>> context_;  // the variables fixed so far, with their values' names
  std::vector<std::string> out_;
};

}  // namespace rvc::engine::explain
