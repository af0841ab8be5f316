#include "runtime/instances_feed.hpp"

#include <cmath>
#include <cstdio>

namespace rvc::runtime {
InstancesFeed::InstancesFeed(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options,
                             VerdictOutputs& outputs, InstanceOptions instance_options)
    : properties_(properties), options_(options), outputs_(outputs), instance_options_(std::move(instance_options)) {
  options_.layouts = false;  // lines go through simdjson, whose object is routed (see the header)
  for (size_t i = 0; i < instance_options_.key_path.size(); ++i)
    key_name_ += (i ? "." : "") + instance_options_.key_path[i];
  // A bad spec is refused before any message, as a single Pipeline does.
  Pipeline probe(properties_, options_, [](const engine::Verdict&) {});
}

InstancesFeed::~InstancesFeed() = default;

// The key string without writing it into the document's string buffer: that
// buffer holds one unescaped copy of each string of the document (simdjson
// sizes it so), and the instance's Pipeline unescapes every string again after
// the object is reset; a key read there too overflowed it once the key was
// about a third of the buffer (a 54,700-character key: heap corruption).
// A key without escapes is its raw text; one with escapes is unescaped by a
// parser of its own, in a buffer of its own.
bool InstancesFeed::unescape_key(std::string_view raw, std::string_view& out) {
  while (!raw.empty() && (raw.back() == ' ' || raw.back() == '\t' || raw.back() == '\r' || raw.back() == '\n'))
    raw.remove_suffix(1);
  if (raw.size() < 2 || raw.front() != '"' || raw.back() != '"') return false;
  const std::string_view inner = raw.substr(1, raw.size() - 2);
  if (inner.find('\\') == std::string_view::npos) {  // (UTF-8 was validated with the whole document)
    out = inner;
    return true;
  }
  key_scratch_.assign(raw.data(), raw.size());
  key_scratch_.append(simdjson::SIMDJSON_PADDING, ' ');
  simdjson::ondemand::document doc;
  if (key_parser_.iterate(key_scratch_.data(), raw.size(), key_scratch_.size()).get(doc)) return false;
  return !doc.get_string().get(out);
}

void InstancesFeed::report(const std::string& text) {
  if (reported_++ < options_.max_reported) std::fprintf(stderr, "rvc: %s\n", text.c_str());
}

io::ReadResult InstancesFeed::on_object(const io::Position& where, simdjson::ondemand::object object) {
  current_ = nullptr;
  current_fresh_ = false;
  current_now_ = std::nan("");
  pending_rejection_.clear();
  pending_line_ = where.number();
  ++ordinal_;
  // The key: walk the path (members in any order), then read a string or a number.
  std::string key, key_json;
  {
    simdjson::ondemand::object at = object;
    const auto& path = instance_options_.key_path;
    simdjson::ondemand::value value;
    bool found = true;
    for (size_t i = 0; i < path.size() && found; ++i) {
      auto field = at.find_field_unordered(path[i]);
      if (field.error() == simdjson::NO_SUCH_FIELD) {
        found = false;
        break;
      }
      if (field.error()) {
        json_error_ = simdjson::error_message(field.error());
        return io::ReadResult::Malformed;
      }
      value = field.value_unsafe();
      if (i + 1 < path.size()) {
        auto child = value.get_object();
        if (child.error()) {
          found = false;
          break;
        }
        at = child.value_unsafe();
      }
    }
    if (!found) {
      pending_rejection_ = "no key field '" + key_name_ + "' (--instances-by)";
    } else {
      auto type = value.type();
      if (type.error()) {
        json_error_ = simdjson::error_message(type.error());
        return io::ReadResult::Malformed;
      }
      if (type.value_unsafe() == simdjson::ondemand::json_type::string) {
        std::string_view s;
        if (!unescape_key(value.raw_json_token(), s)) {
          json_error_ = "invalid string";
          return io::ReadResult::Malformed;
        }
        key.assign(1, 's').append(s);  // (not "s" + std::string(s): GCC 12 warns falsely, -Wrestrict)
        key_json.clear();
        io::append_json_string(key_json, s);
      } else if (type.value_unsafe() == simdjson::ondemand::json_type::number) {
        std::string_view raw = value.raw_json_token();
        while (!raw.empty() && (raw.back() == ' ' || raw.back() == '\t' || raw.back() == '\r' || raw.back() == '\n'))
          raw.remove_suffix(1);
        double d;
        if (value.get_double().get(d) || !std::isfinite(d)) {
          pending_rejection_ = "key field '" + key_name_ + "' is not a finite number";
        } else {
          key = "n" + std::string(raw);  // 17 and 17.0 are two keys: the text as written
          key_json = std::string(raw);
        }
      } else {
        pending_rejection_ = "key field '" + key_name_ + "' is not a string or a number";
      }
    }
  }
  // The time, for expiry (a number at the top level; the instance checks it properly).
  double now = std::nan("");
  if (instance_options_.expiry > 0 && !options_.time_field.empty()) {
    if (auto r = object.reset(); r.error()) {
      json_error_ = simdjson::error_message(r.error());
      return io::ReadResult::Malformed;
    }
    auto t = object.find_field_unordered(options_.time_field);
    if (!t.error()) {
      double d;
      if (!t.value_unsafe().get_double().get(d) && std::isfinite(d)) now = d;
    }
  }
  if (auto r = object.reset(); r.error()) {
    json_error_ = simdjson::error_message(r.error());
    return io::ReadResult::Malformed;
  }
  if (!pending_rejection_.empty()) return io::ReadResult::Pending;  // counted at commit() (it may be broken)
  if (instance_options_.expiry > 0) expire_before(now, ordinal_);
  const uint64_t created_before = created_;
  current_ = instance_for(key, key_json);
  current_fresh_ = created_ != created_before;
  if (!current_) {
    pending_rejection_.clear();
    return io::ReadResult::Pending;  // dropped at commit(): the limit
  }
  current_now_ = now;  // the instance is refreshed at commit(), if it checks the message
  io::ReadResult result = current_->pipeline->on_object(where, object);
  if (result != io::ReadResult::Pending) drop_fresh();  // broken JSON: the reader reports it to us
  return result;
}

InstancesFeed::Instance* InstancesFeed::instance_for(const std::string& key, const std::string& key_json) {
  if (auto it = instances_.find(key); it != instances_.end()) return it->second.get();
  if (instances_.size() >= instance_options_.max_instances) {
    if (refused_.emplace(key, true).second) {
      ++refused_keys_;
      if (refused_keys_ == 1)
        std::fprintf(stderr,
                     "rvc: --max-instances %zu reached: messages of new keys (first: %s) are dropped "
                     "(\"instance_limit\")\n",
                     instance_options_.max_instances, key_json.c_str());
    }
    return nullptr;
  }
  auto inst = std::make_unique<Instance>();
  inst->key = key;
  inst->mark = ",\"instance\":{";
  io::append_json_string(inst->mark, key_name_);
  inst->mark += ":" + key_json + "}";
  Instance* raw = inst.get();
  inst->pipeline = std::make_unique<Pipeline>(properties_, options_, [this, raw](const engine::Verdict& v) {
    outputs_.set_mark(raw->mark);
    outputs_.put(v);
    outputs_.set_mark({});
  });
  inst->last_ordinal = ordinal_;
  inst->lru = lru_.insert(lru_.end(), raw);
  inst->untimed = untimed_.insert(untimed_.end(), raw);
  ++created_;
  instances_.emplace(key, std::move(inst));
  return raw;
}

void InstancesFeed::expire_before(double now, uint64_t ordinal) {
  const double s = instance_options_.expiry;
  // Stream time for instances that have one (a message with a time); else messages.
  if (!std::isnan(now))
    while (!by_time_.empty() && now - by_time_.begin()->first > s) retire(*by_time_.begin()->second);
  while (!untimed_.empty() && double(ordinal - untimed_.front()->last_ordinal) > s) retire(*untimed_.front());
}

// The instance checked the pending message (at time `now`, NaN: none).
void InstancesFeed::touch(Instance& inst, double now) {
  inst.last_ordinal = ordinal_;
  lru_.splice(lru_.end(), lru_, inst.lru);
  if (!std::isnan(now)) {
    if (std::isnan(inst.last_time)) untimed_.erase(inst.untimed);
    else by_time_.erase(inst.timed);
    inst.last_time = now;
    inst.timed = by_time_.emplace(now, &inst);
  } else if (std::isnan(inst.last_time)) {
    untimed_.splice(untimed_.end(), untimed_, inst.untimed);
  }
}

// An instance ends: what the end of its sub-trace decides first (its last
// segment's tick, bounded-future horizons), as a check of the sub-trace
// ends; its counts stay in the run's.
void InstancesFeed::retire(Instance& inst) {
  Pipeline& p = *inst.pipeline;
  p.end_of_input();
  if (instance_options_.tick_at_end) p.tick(p.last_stamp());  // NaN (nothing taken): no tick
  p.settle();
  p.finish_report();
  fold(p);
  retired_violations_ += p.violations();
  ++expired_;
  remove(inst);
}

void InstancesFeed::fold(const Pipeline& pipeline) {
  const PipelineStats& s = pipeline.stats();
  retired_.accepted += s.accepted;
  retired_.rejected += s.rejected;
  retired_.warnings += s.warnings;
  retired_.by_layout += s.by_layout;
  retired_.late_to_clock += s.late_to_clock;
}

void InstancesFeed::remove(Instance& inst) {
  if (std::isnan(inst.last_time)) untimed_.erase(inst.untimed);
  else by_time_.erase(inst.timed);
  lru_.erase(inst.lru);
  instances_.erase(inst.key);  // destroys inst
}

void InstancesFeed::commit() {
  if (current_) {
    Instance& inst = *current_;
    const bool fresh = current_fresh_;
    current_ = nullptr;
    current_fresh_ = false;
    Pipeline& p = *inst.pipeline;
    const uint64_t checked_before = p.stats().accepted;
    p.commit();
    if (p.stats().accepted > checked_before) {
      touch(inst, current_now_);
      const double t = p.last_stamp();
      if (!std::isnan(t) && (std::isnan(last_stamp_) || t > last_stamp_)) last_stamp_ = t;
    } else if (fresh) {
      // Rejected by the instance it made (a bad time, a --strict type error):
      // no instance for it, so garbage under many keys takes no place.
      fold(p);  // (its rejection, reported by the instance)
      --created_;
      remove(inst);
    }
    return;
  }
  if (!pending_rejection_.empty()) {
    ++own_rejected_;
    report(options_.position_name + " " + std::to_string(pending_line_) + ": " + pending_rejection_ +
           " (message skipped)");
    pending_rejection_.clear();
    return;
  }
  ++limit_dropped_;
}

void InstancesFeed::discard() {
  if (current_) current_->pipeline->discard();
  drop_fresh();
  pending_rejection_.clear();
}

// The pending message made its instance and turned out broken: no instance
// was started by it (a key seen only on broken lines makes none).
void InstancesFeed::drop_fresh() {
  if (current_ && current_fresh_) {
    --created_;
    remove(*current_);
  }
  current_ = nullptr;
  current_fresh_ = false;
}

void InstancesFeed::on_error(const io::LineError& error) {
  ++own_rejected_;
  std::string where = options_.position_name + " " + std::to_string(error.line);
  if (error.column) where += ", column " + std::to_string(error.column);
  report(where + ": " + error.message + " (message skipped)");
}

void InstancesFeed::on_warning(const io::LineError& w) {
  ++own_warnings_;
  report("warning: " + options_.position_name + " " + std::to_string(w.line) + ": " + w.message);
}

void InstancesFeed::feed_input(uint32_t, std::string_view payload, uint64_t position) {
  io::ChunkReader reader(*this, options_.max_message_size);
  reader.read(payload, position);
}

uint64_t InstancesFeed::received() const { return stats().accepted + stats().rejected + limit_dropped_; }

void InstancesFeed::add_dropped(io::JsonObject& out) const {
  if (limit_dropped_) out.add("instance_limit", limit_dropped_);
}

const PipelineStats& InstancesFeed::stats() const {
  stats_ = retired_;
  stats_.rejected += own_rejected_;
  stats_.warnings += own_warnings_;
  for (const auto& [key, inst] : instances_) {
    const PipelineStats& s = inst->pipeline->stats();
    stats_.accepted += s.accepted;
    stats_.rejected += s.rejected;
    stats_.warnings += s.warnings;
    stats_.by_layout += s.by_layout;
    stats_.late_to_clock += s.late_to_clock;
  }
  return stats_;
}

uint64_t InstancesFeed::violations() const {
  uint64_t n = retired_violations_;
  for (const auto& [key, inst] : instances_) n += inst->pipeline->violations();
  return n;
}

void InstancesFeed::finish_report() {
  for (auto* inst : lru_) inst->pipeline->finish_report();
  if (reported_ > options_.max_reported)
    std::fprintf(stderr, "rvc: %llu more errors/warnings were not shown\n",
                 static_cast<unsigned long long>(reported_ - options_.max_reported));
}

void InstancesFeed::add_stats(io::JsonObject& out) const {
  io::JsonObject o;
  o.add("created", created_).add("expired", expired_).add("live", uint64_t(instances_.size()));
  o.add("refused_keys", refused_keys_);
  out.add("instances", o);
}

void InstancesFeed::tick_each_at_end() {
  for (auto* inst : lru_) inst->pipeline->tick(inst->pipeline->last_stamp());
}

void InstancesFeed::end_of_input() {
  for (auto* inst : lru_) inst->pipeline->end_of_input();
}

void InstancesFeed::settle() {
  for (auto* inst : lru_) inst->pipeline->settle();
}

}  // namespace rvc::runtime
