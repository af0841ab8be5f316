// Sharding a fleet's key space over the replicas of a monitor group
// (`rvc monitor --group NAME --shard-by 'fleet/*'`, docs/fleet.md).
//
// The shard of a sample is the prefix of its key that the --shard-by pattern
// covers: `fleet/*` makes `fleet/v07/vehicle/status/gear_status` shard
// `fleet/v07`. Each shard is owned by exactly one member of the group: the
// one with the highest rendezvous (highest-random-weight) hash of
// (member, shard). Every replica computes the same owner from the same member
// set, and when a member leaves only its own shards move.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rvc::runtime::fleet {

class ShardPattern {
 public:
  // Chunks separated by '/', each literal or '*' (one chunk). Throws
  // std::invalid_argument for an empty pattern, an empty chunk or '**'.
  explicit ShardPattern(const std::string& pattern);
  // The key's first chunks that the pattern matches, or nullopt when the key
  // is shorter or a literal chunk differs.
  std::optional<std::string_view> shard_of(std::string_view key) const;
  const std::string& text() const { return text_; }
  size_t chunks() const { return chunks_.size(); }
  // `keyexpr` (an input's key expression) narrowed to one shard: its first
  // chunks() chunks replaced by `shard` (`fleet/*/vehicle/x`, shard
  // `fleet/v07` -> `fleet/v07/vehicle/x`), or nullopt when they cannot match
  // the pattern (a literal differs, a '**' or '$*' among them, too short).
  std::optional<std::string> narrow(std::string_view keyexpr, std::string_view shard) const;

 private:
  std::string text_;
  std::vector<std::string> chunks_;
};

// A 64-bit hash that is the same in every process and on every host (FNV-1a
// with a final avalanche): owners must agree across replicas.
uint64_t stable_hash(std::string_view a, std::string_view b);

// The owner of `shard` among `members` (rendezvous hashing); "" when there
// are none. Ties (equal hashes) go to the smaller member id.
std::string owner_of(std::string_view shard, const std::vector<std::string>& members);

// The first `n` choices for `shard` in rendezvous order: [0] is owner_of,
// [1] the member that owns the shard when [0] leaves (its backup), ...
std::vector<std::string> owners_of(std::string_view shard, const std::vector<std::string>& members, size_t n);

}  // namespace rvc::runtime::fleet
