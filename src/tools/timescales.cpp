#include "tools/timescales.hpp"

#include <algorithm>
#include <stdexcept>

namespace rvc::tools {
namespace {

// splitmix64: tiny, fast, and fully specified, so traces are reproducible.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  int64_t uniform(int64_t lo, int64_t hi) {  // inclusive; lo <= hi
    return lo + static_cast<int64_t>(next() % static_cast<uint64_t>(hi - lo + 1));
  }
  bool coin() { return next() >> 63; }

 private:
  uint64_t state_;
};

enum Prop : unsigned { P = 1, Q = 2, R = 4, S = 8 };

struct Family {
  const char* name;
  unsigned props;        // which propositions appear in the trace
  const char* formula;   // with L and U standing for the bounds
};

// Published formulas (shared/reference/timescales-formulas.tsv) with the bounds abstracted.
const Family kFamilies[] = {
    {"AbsentAQ", P | Q, "historically((once[:U]{q}) -> ((not{p}) since {q}))"},
    {"AbsentBQR", P | Q | R, "historically({r} && !{q} && once{q}) -> ((not{p}) since[L:U] {q})"},
    {"AbsentBR", P | R, "historically({r} -> (historically[:U](not{p})))"},
    {"AlwaysAQ", P | Q, "historically((once[:U]{q}) -> ({p} since {q}))"},
    {"AlwaysBQR", P | Q | R, "historically(({r} && !{q} && once{q}) -> ({p} since[L:U] {q}))"},
    {"AlwaysBR", P | R, "historically({r} -> (historically[:U]{p}))"},
    {"RecurBQR", P | Q | R, "historically(({r} && !{q} && once{q}) -> ((once[:U]({p} or {q})) since {q}))"},
    {"RecurGLB", P, "historically(once[:U]{p})"},
    {"RespondBQR", P | Q | R | S,
     "historically(({r} && !{q} && once{q}) -> ( (({s} -> once[L:U]{p}) and not((not {s}) since[U:] {p})) since {q}))"},
    {"RespondGLB", P | S, "historically(({s} -> once[L:U]{p}) and not((not {s}) since[U:] {p}))"},
};

const Family& find(const std::string& name) {
  for (const Family& f : kFamilies)
    if (name == f.name) return f;
  throw std::invalid_argument("unknown Timescales family '" + name + "'");
}

// Writes steps into a large buffer; one fwrite per 1 MiB.
class TraceWriter {
 public:
  TraceWriter(std::FILE* out, unsigned props, uint64_t limit) : out_(out), props_(props), limit_(limit) {
    buf_.reserve(1 << 21);
  }
  ~TraceWriter() { flush(); }
  bool full() const { return step_ >= limit_; }
  void step(unsigned on) {
    if (full()) return;
    buf_ += "{\"time\":";
    buf_ += std::to_string(step_);
    static const char* names[] = {"p", "q", "r", "s"};
    for (unsigned i = 0; i < 4; ++i) {
      if (!(props_ & (1u << i))) continue;
      buf_ += ",\"";
      buf_ += names[i];
      buf_ += (on & (1u << i)) ? "\":true" : "\":false";
    }
    buf_ += "}\n";
    ++step_;
    if (buf_.size() > (1 << 20)) flush();
  }
  void repeat(int64_t n, unsigned on) {
    for (int64_t i = 0; i < n && !full(); ++i) step(on);
  }
  void flush() {
    std::fwrite(buf_.data(), 1, buf_.size(), out_);
    buf_.clear();
  }

 private:
  std::FILE* out_;
  unsigned props_;
  uint64_t limit_, step_ = 0;
  std::string buf_;
};

}  // namespace

const std::vector<std::string>& timescales_families() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const Family& f : kFamilies) v.push_back(f.name);
    return v;
  }();
  return names;
}

bool is_timescales_family(const std::string& family) {
  return std::any_of(std::begin(kFamilies), std::end(kFamilies), [&](const Family& f) { return family == f.name; });
}

int64_t effective_lbound(const TimescalesOptions& o) { return o.lbound >= 0 ? o.lbound : (o.ubound * 3) / 10; }

std::string timescales_formula(const std::string& family, int64_t lbound, int64_t ubound, bool intended) {
  std::string text = find(family).formula;
  if (intended && family == "AbsentBQR")
    text = "historically(({r} && !{q} && once{q}) -> ((not{p}) since[L:U] {q}))";
  std::string out;
  for (char c : text) {
    if (c == 'L') out += std::to_string(lbound);
    else if (c == 'U') out += std::to_string(ubound);
    else out.push_back(c);
  }
  return out;
}

void generate_timescales(const TimescalesOptions& o, std::FILE* out) {
  const Family& fam = find(o.family);
  const int64_t U = std::max<int64_t>(o.ubound, 1);
  const int64_t L = std::min(effective_lbound(o), U);
  Rng rng(o.seed);
  TraceWriter w(out, fam.props, o.duration);
  auto noise = [&](unsigned props) {  // random values for the given propositions
    unsigned on = 0;
    for (unsigned bit = 1; bit <= S; bit <<= 1)
      if ((props & bit) && rng.coin()) on |= bit;
    return on;
  };
  auto free_phase = [&](int64_t n, unsigned props) {
    for (int64_t i = 0; i < n && !w.full(); ++i) w.step(noise(props));
  };
  const std::string& f = o.family;
  while (!w.full()) {
    if (f == "AbsentAQ") {          // q, then no p for the next U steps
      free_phase(rng.uniform(1, U), P);
      w.step(Q | noise(P));
      w.repeat(rng.uniform(U, 2 * U), 0);
    } else if (f == "AlwaysAQ") {   // q, then p for the next U steps
      free_phase(rng.uniform(1, U), P);
      w.step(Q | noise(P));
      w.repeat(U, P);
      w.repeat(1, 0);  // once[:U]{q} expires before the free phase
    } else if (f == "AbsentBR") {   // no p in the U steps up to r
      free_phase(rng.uniform(1, U), P);
      w.repeat(rng.uniform(U, 2 * U), 0);
      w.step(R);
    } else if (f == "AlwaysBR") {   // p in the U steps up to r
      free_phase(rng.uniform(1, U), P);
      w.repeat(rng.uniform(U, 2 * U), P);
      w.step(R | P);
    } else if (f == "AbsentBQR" || f == "AlwaysBQR") {  // q, d in [L, U] steps, r
      const unsigned fill = f == "AlwaysBQR" ? P : 0;
      free_phase(rng.uniform(1, U), P);
      w.step(Q | fill);
      w.repeat(rng.uniform(L, U) - 1, fill);
      w.step(R | fill);
    } else if (f == "RecurGLB") {   // p at least every U steps
      w.step(P);
      w.repeat(rng.uniform(0, U - 1), 0);
    } else if (f == "RecurBQR") {   // between q and r, p recurs within U steps
      free_phase(rng.uniform(1, U), P);
      w.step(Q);
      for (int64_t k = rng.uniform(1, 4); k > 0; --k) {
        w.repeat(rng.uniform(0, U - 1), 0);
        w.step(P);
      }
      w.repeat(rng.uniform(0, U - 1), 0);
      w.step(R);
    } else if (f == "RespondGLB" || f == "RespondBQR") {  // p answered by s after d in [L, U]
      const bool scoped = f == "RespondBQR";
      if (scoped) {
        free_phase(rng.uniform(1, U), S);  // a stray p here would need an answer inside the scope
        w.step(Q);
      }
      for (int64_t k = scoped ? rng.uniform(1, 3) : 1; k > 0; --k) {
        w.step(P);
        w.repeat(std::max<int64_t>(rng.uniform(L, U), 1) - 1, 0);
        w.step(S);
        w.repeat(rng.uniform(0, U), 0);
      }
      if (scoped) w.step(R);
    }
  }
}

}  // namespace rvc::tools
