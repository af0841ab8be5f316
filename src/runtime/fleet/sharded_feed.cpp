#include "runtime/fleet/sharded_feed.hpp"

#include <algorithm>
#include <cstdio>

#include "io/json_writer.hpp"

namespace rvc::runtime::fleet {
namespace {

void add_stats_to(PipelineStats& to, const PipelineStats& s, int sign = 1) {
  to.accepted += sign * static_cast<int64_t>(s.accepted);
  to.rejected += sign * static_cast<int64_t>(s.rejected);
  to.warnings += sign * static_cast<int64_t>(s.warnings);
  to.by_layout += sign * static_cast<int64_t>(s.by_layout);
  to.late_to_clock += sign * static_cast<int64_t>(s.late_to_clock);
}

}  // namespace

ShardedFeed::ShardedFeed(ShardPattern pattern, GroupMembers& members, InstanceFactory factory, VerdictOutputs& outputs,
                         ShardedOptions options)
    : pattern_(std::move(pattern)),
      members_(members),
      factory_(std::move(factory)),
      outputs_(outputs),
      options_(std::move(options)) {
  follow_members();
}

ShardedFeed::~ShardedFeed() = default;

ShardedFeed::Shard& ShardedFeed::shard(std::string_view key) {
  auto it = shards_.find(std::string(key));
  if (it != shards_.end()) return *it->second;
  auto s = std::make_unique<Shard>();
  s->key = std::string(key);
  Shard& ref = *s;
  shards_.emplace(s->key, std::move(s));
  return ref;
}

void ShardedFeed::feed_input(uint32_t input, std::string_view payload, uint64_t position) {
  (void)input;
  (void)payload;
  (void)position;
  ++received_;
  ++no_shard_;  // no key: a group shards by key only
}

void ShardedFeed::feed_keyed(uint32_t input, std::string_view key, std::string_view payload, uint64_t position) {
  if (members_.generation() != generation_) follow_members();
  ++received_;
  const auto shard_key = pattern_.shard_of(key);
  if (!shard_key) {
    ++no_shard_;
    return;
  }
  Shard& s = shard(*shard_key);
  if (input < 64 && !(s.inputs_seen & (uint64_t{1} << input))) {
    // The first message of this input's publisher here: a sequence number
    // past 1 means this replica started after the vehicle did, so what it
    // keeps of the shard is not its whole history.
    s.inputs_seen |= uint64_t{1} << input;
    if (position > 1) s.evicted = true;
  }
  if (!s.started) {
    // A shard seen for the first time is no handover: its owner starts it
    // (with nothing to replay; partial if the vehicle started before this replica).
    s.started = true;
    if (owner_of(s.key, member_list_) == members_.self()) take(s, std::chrono::steady_clock::now());
  }
  if (s.instance) {
    s.instance->feed_input(input, payload, position);
    return;
  }
  ++not_owned_;
  if (options_.replay_window == 0 || !keeps_window(s)) return;
  if (s.window.size() >= options_.replay_window) {
    s.window.pop_front();
    ++window_evicted_;
    s.evicted = true;
  }
  s.window.push_back(Buffered{input, position, std::chrono::steady_clock::now(), std::string(payload)});
}

bool ShardedFeed::keeps_window(Shard& s) {
  if (!options_.subscribe_owned) return true;
  if (!s.backup) {
    // Only a shard's backup keeps its window; this one arrived here still
    // (samples in flight as its subscription went, or the first of a shard
    // whose role is not known yet): the first sight of a shard decides.
    const auto firsts = owners_of(s.key, member_list_, 2);
    s.backup = firsts.size() == 2 && firsts[1] == members_.self();
    if (!s.backup) {
      s.evicted = true;  // what it keeps later starts mid-history
      return false;
    }
  }
  return true;
}

void ShardedFeed::follow_members() {
  generation_ = members_.generation();
  std::chrono::steady_clock::time_point changed_at;
  std::vector<std::string> now = members_.snapshot(&changed_at);
  if (now == member_list_) return;
  std::string gone, joined;
  for (const auto& m : member_list_)
    if (!std::binary_search(now.begin(), now.end(), m)) gone += (gone.empty() ? "" : ",") + m;
  for (const auto& m : now)
    if (!std::binary_search(member_list_.begin(), member_list_.end(), m)) joined += (joined.empty() ? "" : ",") + m;
  member_list_ = std::move(now);
  if (shards_.empty()) {  // nothing to hand over yet
    std::fprintf(stderr, "rvc monitor: group %s: members %zu (%s)\n", options_.group.c_str(), member_list_.size(),
                 joined.c_str());
    return;
  }
  size_t taken = 0, released = 0;
  const uint64_t replayed_before = replayed_, partial_before = partial_replays_;
  std::string keys;
  for (auto& [key, s] : shards_) {
    const bool mine = owner_of(key, member_list_) == members_.self();
    if (mine && !s->instance) {
      take(*s, changed_at);
      ++taken;
      if (!keys.empty()) keys += ',';
      io::append_json_string(keys, key);
    } else if (!mine && s->instance) {
      release(*s);
      ++released;
    }
    if (options_.subscribe_owned && !mine) {
      // Backed up now, or no longer: a window kept while neither owner nor
      // backup would have gaps (the shard was not subscribed), so it restarts.
      const auto firsts = owners_of(key, member_list_, 2);
      const bool backup = firsts.size() == 2 && firsts[1] == members_.self();
      if (!backup || !s->backup) {
        s->window.clear();
        s->evicted = s->started;  // a started shard's later window lacks its beginning
      }
      s->backup = backup;
    }
  }
  std::fprintf(stderr,
               "rvc monitor: group %s: members %zu (left: %s; joined: %s): took over %zu shard%s (%llu messages "
               "replayed), handed %zu on\n",
               options_.group.c_str(), member_list_.size(), gone.empty() ? "-" : gone.c_str(),
               joined.empty() ? "-" : joined.c_str(), taken, taken == 1 ? "" : "s",
               static_cast<unsigned long long>(replayed_ - replayed_before), released);
  if (taken == 0 && released == 0) return;
  ++handovers_;
  if (options_.on_handover) {
    io::JsonObject h;
    h.add("group", options_.group)
        .add("member", members_.self())
        .add("left", gone)
        .add("joined", joined)
        .add("taken", static_cast<uint64_t>(taken))
        .add("released", static_cast<uint64_t>(released))
        .add("replayed", replayed_ - replayed_before)
        .add("partial_replays", partial_replays_ - partial_before)
        .add_raw("shards", "[" + keys + "]");
    io::JsonObject event;
    event.add_raw("handover", h.str());
    options_.on_handover(event.str());
  }
}

void ShardedFeed::take(Shard& s, std::chrono::steady_clock::time_point changed_at) {
  const Shard* shard = &s;  // shards_ holds each Shard behind a unique_ptr: the address stays
  s.instance = factory_(s.key, [this, shard](const engine::Verdict& v) { on_verdict(*shard, v); });
  s.partial = s.evicted;
  if (s.evicted) {
    // Bounded properties are rebuilt from the last window; what depends on
    // older messages (unbounded operators, discrete step numbers) may differ.
    ++partial_replays_;
    std::fprintf(stderr,
                 "rvc monitor: group %s: warning: shard %s is replayed from its last %zu messages only "
                 "(--replay-window): verdicts that depend on older messages may differ from one uninterrupted "
                 "monitor's\n",
                 options_.group.c_str(), s.key.c_str(), s.window.size());
  }
  // The old owner may have died up to a lease before its token went, with
  // messages still queued: verdicts of what arrived since then are published again.
  const auto overlap_from = changed_at - std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                             std::chrono::duration<double>(options_.handover_overlap));
  for (const Buffered& b : s.window) {
    withhold_ = b.arrival < overlap_from;
    mark_handover_ = !withhold_;
    s.instance->feed_input(b.input, b.payload, b.position);
  }
  withhold_ = false;
  mark_handover_ = false;
  replayed_ += s.window.size();
  s.replay_received = s.window.size();
  // What the replay counted is not this run's live count. A synchronizer may
  // still hold the last replayed messages: they count as replayed too when
  // a live message releases them into a set.
  s.replay = s.instance->stats();
  s.replay_lost = s.instance->lost();
  s.replay.accepted = s.window.size() - s.replay.rejected - s.replay_lost;
  s.window.clear();
  s.window.shrink_to_fit();
  s.evicted = false;
}

void ShardedFeed::retire(Shard& s) {
  PipelineStats live = s.instance->stats();
  add_stats_to(live, s.replay, -1);
  add_stats_to(retired_, live);
  retired_violations_ += s.instance->violations();
  retired_lost_ += s.instance->lost() - s.replay_lost;
}

void ShardedFeed::release(Shard& s) {
  // Another replica took it (it joined, or came back): it rebuilds the
  // state from its own window; this one starts keeping a window again.
  s.instance->end_of_input();
  retire(s);
  s.instance.reset();
  s.replay = PipelineStats{};
  s.replay_lost = 0;
  s.evicted = true;  // the window restarts here: taken back, it replays from now on only
}

void ShardedFeed::on_verdict(const Shard& s, const engine::Verdict& v) {
  if (withhold_) {
    ++withheld_verdicts_;
    return;
  }
  // A verdict of an instance that began mid-history (a late joiner, a window
  // that lost the shard's oldest messages) need not be the uninterrupted
  // monitor's: its discrete steps count from the replay's first message, and
  // unbounded operators miss what came before. Marked "partial", so a reader
  // never takes it for the same (property, time) as the first owner's.
  const char* mark = s.partial ? (mark_handover_ ? ",\"handover\":true,\"partial\":true" : ",\"partial\":true")
                               : (mark_handover_ ? ",\"handover\":true" : nullptr);
  if (mark_handover_) ++replayed_verdicts_;
  if (!mark) {
    outputs_.put(v);
    return;
  }
  outputs_.set_mark(mark);
  outputs_.put(v);
  outputs_.set_mark("");
}

void ShardedFeed::warn(const io::LineError& warning) {
  std::fprintf(stderr, "rvc: warning: %s (line %llu)\n", warning.message.c_str(),
               static_cast<unsigned long long>(warning.line));
}

void ShardedFeed::idle() {
  if (members_.generation() != generation_) follow_members();
  // The loop calls idle whenever its queue runs empty, which a fast engine
  // does after nearly every batch: the instances' idle work (a synchronizer's
  // silent-input check) is done at most every 100 ms, not once per batch
  // times the number of shards.
  const auto now = std::chrono::steady_clock::now();
  if (now - last_idle_ < std::chrono::milliseconds(100)) return;
  last_idle_ = now;
  for (auto& [key, s] : shards_)
    if (s->instance) s->instance->idle();
}

void ShardedFeed::end_of_input() {
  ended_ = true;
  for (auto& [key, s] : shards_)
    if (s->instance) s->instance->end_of_input();
}

void ShardedFeed::input_ended(uint32_t input) {
  for (auto& [key, s] : shards_)
    if (s->instance) s->instance->input_ended(input);
}

void ShardedFeed::add_dropped(io::JsonObject& out) const {
  out.add("not owned", not_owned_);
  if (no_shard_) out.add("no shard", no_shard_);
  // The instances' own drops: a synchronizer's late messages.
  if (const uint64_t late = lost()) out.add("late", late);
}

uint64_t ShardedFeed::lost() const {
  uint64_t n = retired_lost_;
  for (const auto& [key, s] : shards_)
    if (s->instance) n += s->instance->lost() - s->replay_lost;
  return n;
}

const PipelineStats& ShardedFeed::stats() const {
  stats_ = retired_;
  for (const auto& [key, s] : shards_)
    if (s->instance) {
      add_stats_to(stats_, s->instance->stats());
      add_stats_to(stats_, s->replay, -1);
    }
  return stats_;
}

uint64_t ShardedFeed::violations() const {
  uint64_t n = retired_violations_;
  for (const auto& [key, s] : shards_)
    if (s->instance) n += s->instance->violations();
  return n;
}

void ShardedFeed::finish_report() {
  for (auto& [key, s] : shards_)
    if (s->instance) s->instance->finish_report();
}

size_t ShardedFeed::owned() const {
  size_t n = 0;
  for (const auto& [key, s] : shards_) n += s->instance != nullptr;
  return n;
}

void ShardedFeed::add_stats(io::JsonObject& out) const {
  io::JsonObject g;
  g.add("name", options_.group)
      .add("member", members_.self())
      .add("members", static_cast<uint64_t>(member_list_.size()))
      .add("shards", static_cast<uint64_t>(shards_.size()))
      .add("owned", static_cast<uint64_t>(owned()))
      .add("handovers", handovers_)
      .add("replayed", replayed_)
      .add("handover_verdicts", replayed_verdicts_)
      .add("window_evicted", window_evicted_)
      .add("partial_replays", partial_replays_);
  out.add_raw("group", g.str());
}

}  // namespace rvc::runtime::fleet
