#include "runtime/fleet/shard_map.hpp"

#include <algorithm>
#include <stdexcept>

namespace rvc::runtime::fleet {

ShardPattern::ShardPattern(const std::string& pattern) : text_(pattern) {
  if (pattern.empty()) throw std::invalid_argument("--shard-by: empty pattern");
  size_t start = 0;
  while (true) {
    const size_t slash = pattern.find('/', start);
    std::string chunk = pattern.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (chunk.empty())
      throw std::invalid_argument("--shard-by '" + pattern + "': empty chunk at column " + std::to_string(start + 1));
    if (chunk != "*" && chunk.find('*') != std::string::npos)
      throw std::invalid_argument("--shard-by '" + pattern + "': chunk '" + chunk +
                                  "' (column " + std::to_string(start + 1) +
                                  "): a chunk is a literal or '*' (one chunk; '**' cannot name a shard)");
    chunks_.push_back(std::move(chunk));
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
}

std::optional<std::string_view> ShardPattern::shard_of(std::string_view key) const {
  size_t pos = 0;
  for (size_t i = 0; i < chunks_.size(); ++i) {
    if (pos > key.size()) return std::nullopt;
    const size_t slash = key.find('/', pos);
    const size_t end = slash == std::string_view::npos ? key.size() : slash;
    const std::string_view chunk = key.substr(pos, end - pos);
    if (chunk.empty() || (chunks_[i] != "*" && chunk != chunks_[i])) return std::nullopt;
    if (i + 1 == chunks_.size()) return key.substr(0, end);
    if (slash == std::string_view::npos) return std::nullopt;
    pos = slash + 1;
  }
  return std::nullopt;
}

uint64_t stable_hash(std::string_view a, std::string_view b) {
  uint64_t h = 14695981039346656037ull;
  auto mix = [&h](std::string_view s) {
    for (unsigned char c : s) {
      h ^= c;
      h *= 1099511628211ull;
    }
  };
  mix(a);
  mix(std::string_view("\0", 1));  // (ab, c) and (a, bc) hash apart
  mix(b);
  // splitmix64's finalizer: FNV's low bits alone are poorly spread.
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebull;
  h ^= h >> 31;
  return h;
}

std::string owner_of(std::string_view shard, const std::vector<std::string>& members) {
  const std::string* best = nullptr;
  uint64_t best_hash = 0;
  for (const auto& m : members) {
    const uint64_t h = stable_hash(m, shard);
    if (!best || h > best_hash || (h == best_hash && m < *best)) {
      best = &m;
      best_hash = h;
    }
  }
  return best ? *best : std::string();
}

std::vector<std::string> owners_of(std::string_view shard, const std::vector<std::string>& members, size_t n) {
  std::vector<std::pair<uint64_t, const std::string*>> ranked;
  ranked.reserve(members.size());
  for (const auto& m : members) ranked.emplace_back(stable_hash(m, shard), &m);
  // The same order as owner_of: highest hash first, ties to the smaller id.
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : *a.second < *b.second;
  });
  std::vector<std::string> out;
  for (size_t i = 0; i < ranked.size() && i < n; ++i) out.push_back(*ranked[i].second);
  return out;
}

std::optional<std::string> ShardPattern::narrow(std::string_view keyexpr, std::string_view shard) const {
  size_t pos = 0;
  for (size_t i = 0; i < chunks_.size(); ++i) {
    if (pos > keyexpr.size()) return std::nullopt;
    const size_t slash = keyexpr.find('/', pos);
    const size_t end = slash == std::string_view::npos ? keyexpr.size() : slash;
    const std::string_view chunk = keyexpr.substr(pos, end - pos);
    // Each of the key's first chunks is '*' or the pattern's own literal;
    // a literal where the pattern varies (one vehicle only), '**' or '$*'
    // would not give one subscription per shard.
    if (chunk.empty() || chunk == "**" || chunk.find('$') != std::string_view::npos) return std::nullopt;
    if (chunk != "*" && (chunks_[i] == "*" || chunk != chunks_[i])) return std::nullopt;
    pos = slash == std::string_view::npos ? keyexpr.size() + 1 : slash + 1;
  }
  std::string out(shard);
  if (pos < keyexpr.size()) out += "/" + std::string(keyexpr.substr(pos));
  return out;
}

}  // namespace rvc::runtime::fleet
