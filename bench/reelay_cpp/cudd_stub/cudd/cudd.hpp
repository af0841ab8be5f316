// Stand-in for CUDD's C++ header, for bench/reelay_cpp only (written for rvc, not CUDD's code).
//
// Reelay's headers include <cudd/cudd.hpp> because its *data* monitors (formulas with references such
// as {id: *x}) keep sets of values as BDDs. CUDD is neither on PyPI nor in Debian, so the harness
// cannot link the real library. reelay_check only instantiates Reelay's discrete_timed_monitor (no
// data references; it refuses such formulas before building a monitor), which never touches a BDD:
// this header declares just enough of the BDD/Cudd interface for the shared headers to compile, and
// every operation aborts, so a BDD use could never pass unnoticed.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <vector>

struct DdNode;

[[noreturn]] inline void rvc_cudd_stub_used() {
  std::fprintf(stderr, "reelay_check: a BDD operation was reached; CUDD is not linked in this harness\n");
  std::abort();
}

class BDD {
 public:
  BDD() = default;
  DdNode* getNode() const { rvc_cudd_stub_used(); }
  BDD operator~() const { rvc_cudd_stub_used(); }
  BDD operator!() const { rvc_cudd_stub_used(); }
  BDD operator*(const BDD&) const { rvc_cudd_stub_used(); }
  BDD operator&(const BDD&) const { rvc_cudd_stub_used(); }
  BDD operator+(const BDD&) const { rvc_cudd_stub_used(); }
  BDD operator|(const BDD&) const { rvc_cudd_stub_used(); }
  BDD operator^(const BDD&) const { rvc_cudd_stub_used(); }
  BDD operator-(const BDD&) const { rvc_cudd_stub_used(); }
  BDD& operator*=(const BDD&) { rvc_cudd_stub_used(); }
  BDD& operator&=(const BDD&) { rvc_cudd_stub_used(); }
  BDD& operator+=(const BDD&) { rvc_cudd_stub_used(); }
  BDD& operator|=(const BDD&) { rvc_cudd_stub_used(); }
  BDD& operator^=(const BDD&) { rvc_cudd_stub_used(); }
  BDD& operator-=(const BDD&) { rvc_cudd_stub_used(); }
  bool operator==(const BDD&) const { rvc_cudd_stub_used(); }
  bool operator!=(const BDD&) const { rvc_cudd_stub_used(); }
  bool operator<=(const BDD&) const { rvc_cudd_stub_used(); }
  bool operator>=(const BDD&) const { rvc_cudd_stub_used(); }
  bool operator<(const BDD&) const { rvc_cudd_stub_used(); }
  bool operator>(const BDD&) const { rvc_cudd_stub_used(); }
  bool IsZero() const { rvc_cudd_stub_used(); }
  bool IsOne() const { rvc_cudd_stub_used(); }
  BDD ExistAbstract(const BDD&, int = 0) const { rvc_cudd_stub_used(); }
  BDD UnivAbstract(const BDD&) const { rvc_cudd_stub_used(); }
};

class Cudd {
 public:
  Cudd() = default;
  Cudd(unsigned, unsigned) {}
  void AutodynDisable() const { rvc_cudd_stub_used(); }
  BDD bddOne() const { rvc_cudd_stub_used(); }
  BDD bddZero() const { rvc_cudd_stub_used(); }
  BDD bddVar() const { rvc_cudd_stub_used(); }
  BDD computeCube(const std::vector<BDD>&) const { rvc_cudd_stub_used(); }
};
