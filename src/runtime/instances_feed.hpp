// Parametric instances (`rvc check --instances-by id`, docs/semantics.md
// "Parametric instances"): one monitor instance (a Pipeline, the same a
// single-object check would run) per value of a key field, created on the
// key's first message; each instance's verdicts carry
// "instance":{"<key>":<value>}.
//
// One parse per message: the JSON-lines reader hands each line's simdjson
// object here; the key (and the time field, for expiry) are looked up in it,
// the object is reset and handed on to the instance's Pipeline, which decodes
// it as it would unrouted. The layout fast path is off (it reads lines
// without simdjson, for one Pipeline).
//
// Counts: received = checked + rejected + dropped. A message without the
// key (or with a key that is no string or number) is rejected ("no key");
// with --max-instances N, a message whose key would make instance N+1 is
// dropped ("instance_limit": exit 3, the run goes on). Only a message its
// instance checks makes or refreshes an instance: one it rejects (a bad time,
// a --strict type error) leaves none behind and no place taken.
// --instance-expiry S removes an instance whose last checked message is more
// than S (stream time) before the message being routed (an instance whose
// messages had no time: more than S messages before); the key's next message
// starts a fresh instance (steps and history from zero). An instance that
// ends (expiry, end of input) settles what its sub-trace's end decides
// (bounded future), as a check of that sub-trace does.
#pragma once

#include <cstdint>
#include <list>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "runtime/pipeline.hpp"
#include "runtime/verdict_outputs.hpp"

namespace rvc::runtime {

struct InstanceOptions {
  std::vector<std::string> key_path;  // "vehicle.id" -> {"vehicle", "id"}
  double expiry = 0;                  // seconds of stream time (<= 0: never)
  size_t max_instances = 100000;      // live instances at once
  bool tick_at_end = false;           // dense, --clock auto: an ending instance ticks at its last stamp
};

class InstancesFeed final : public io::JsonlHandler, public Feed {
 public:
  // Throws spec::SpecError for a bad spec (an instance is built once here to check).
  InstancesFeed(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options,
                VerdictOutputs& outputs, InstanceOptions instance_options);
  ~InstancesFeed() override;

  // JsonlHandler
  io::ReadResult on_object(const io::Position& position, simdjson::ondemand::object object) override;
  std::string json_error() const override { return json_error_; }
  void commit() override;
  void discard() override;
  void on_error(const io::LineError& error) override;
  void on_warning(const io::LineError& warning) override;

  // Feed (a network payload: its lines read as a file's)
  void feed_input(uint32_t input, std::string_view payload, uint64_t position) override;
  void warn(const io::LineError& warning) override { on_warning(warning); }
  uint64_t received() const override;
  void add_dropped(io::JsonObject& out) const override;
  uint64_t lost() const override { return limit_dropped_; }
  const PipelineStats& stats() const override;
  uint64_t violations() const override;
  void finish_report() override;
  // "instances": {"created", "expired", "live", "refused_keys"}
  void add_stats(io::JsonObject& out) const override;
  double last_stamp() const override { return last_stamp_; }
  // Dense time, --clock auto: each instance ticks at its own last stamp (its
  // last message's segment gets its verdict, as in a check of its sub-trace).
  void tick_each_at_end();
  // The loop's tick at a file's end: instances move with their own messages
  // (no --clock), so each ticks at its own last stamp, as tick_each_at_end.
  void tick(double) override { tick_each_at_end(); }
  void end_of_input() override;
  // Bounded future: every live instance settles its last horizon.
  void settle() override;
  uint64_t refused_keys() const { return refused_keys_; }

 private:
  struct Instance {
    std::string key;
    std::string mark;  // ,"instance":{...}: the members its verdicts get
    std::unique_ptr<Pipeline> pipeline;
    double last_time = std::numeric_limits<double>::quiet_NaN();  // of its last checked message
    uint64_t last_ordinal = 0;
    std::list<Instance*>::iterator lru;                  // in lru_
    std::list<Instance*>::iterator untimed;              // in untimed_ while last_time is NaN
    std::multimap<double, Instance*>::iterator timed;    // in by_time_ once it has a time
  };
  Instance* instance_for(const std::string& key, const std::string& key_json);
  void expire_before(double now, uint64_t ordinal);
  void touch(Instance& instance, double now);
  void retire(Instance& instance);
  void remove(Instance& instance);
  void fold(const Pipeline& pipeline);
  void drop_fresh();
  void report(const std::string& text);
  bool unescape_key(std::string_view raw, std::string_view& out);

  std::vector<engine::PropertySpec> properties_;
  PipelineOptions options_;
  VerdictOutputs& outputs_;
  InstanceOptions instance_options_;
  std::string key_name_;  // the path as written ("vehicle.id"): the instance object's member name
  std::unordered_map<std::string, std::unique_ptr<Instance>> instances_;
  // Least recently checked first: all instances (the order they end in), and
  // those whose messages had no time (they expire by message count). Those
  // with a time expire by it, oldest time first (by_time_): times of
  // different keys need not come in order, so one instance whose last time
  // is late cannot keep the others from expiring.
  std::list<Instance*> lru_, untimed_;
  std::multimap<double, Instance*> by_time_;
  Instance* current_ = nullptr;  // the pending message's instance
  bool current_fresh_ = false;   // ... made by that message
  double current_now_ = std::numeric_limits<double>::quiet_NaN();  // ... and its time, for expiry
  std::string pending_rejection_;
  uint64_t pending_line_ = 0;
  uint64_t ordinal_ = 0;
  PipelineStats retired_;
  uint64_t retired_violations_ = 0;
  uint64_t own_rejected_ = 0, own_warnings_ = 0, limit_dropped_ = 0;
  uint64_t created_ = 0, expired_ = 0, refused_keys_ = 0;
  uint64_t reported_ = 0;
  double last_stamp_ = std::numeric_limits<double>::quiet_NaN();
  std::string json_error_;
  simdjson::ondemand::parser key_parser_;  // unescapes keys with escapes (unescape_key)
  std::string key_scratch_;
  std::unordered_map<std::string, bool> refused_;  // keys refused by the limit (counted once each)
  mutable PipelineStats stats_;
};

}  // namespace rvc::runtime
