// Names of the policies and release reasons, and the one factory that turns
// PolicyOptions into a policy (each policy checks the options it reads).
#include "sync/policy.hpp"

#include <stdexcept>

#include "sync/approximate_time.hpp"
#include "sync/exact_time.hpp"
#include "sync/latest_time.hpp"
#include "sync/stamp_merge.hpp"

namespace rvc::sync {

PolicyKind policy_from_string(const std::string& name) {
  if (name == "approximate") return PolicyKind::Approximate;
  if (name == "exact") return PolicyKind::Exact;
  if (name == "latest") return PolicyKind::Latest;
  if (name == "merge") return PolicyKind::Merge;
  throw std::invalid_argument("unknown sync policy '" + name + "' (approximate, exact, latest or merge)");
}

const char* to_string(PolicyKind kind) {
  switch (kind) {
    case PolicyKind::Approximate: return "approximate";
    case PolicyKind::Exact: return "exact";
    case PolicyKind::Latest: return "latest";
    case PolicyKind::Merge: return "merge";
  }
  return "?";
}

const char* to_string(Release why) {
  switch (why) {
    case Release::Used: return "used";
    case Release::Unmatched: return "unmatched";
    case Release::Overflow: return "overflow";
    case Release::Interval: return "interval";
    case Release::Replaced: return "replaced";
    case Release::Late: return "late";
    case Release::Unfinished: return "unfinished";
  }
  return "?";
}

std::unique_ptr<Policy> make_policy(PolicyKind kind, const PolicyOptions& options, Handler& handler) {
  switch (kind) {
    case PolicyKind::Approximate: return std::make_unique<ApproximateTime>(options, handler);
    case PolicyKind::Exact: return std::make_unique<ExactTime>(options, handler);
    case PolicyKind::Latest: return std::make_unique<LatestTime>(options, handler);
    case PolicyKind::Merge: return std::make_unique<StampMerge>(options, handler);
  }
  throw std::invalid_argument("unknown sync policy");
}

}  // namespace rvc::sync
