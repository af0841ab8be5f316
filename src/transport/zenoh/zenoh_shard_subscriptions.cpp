#include "transport/zenoh/zenoh_shard_subscriptions.hpp"

#include <cstdio>
#include <stdexcept>

#include "transport/zenoh/seq_attachment.hpp"

namespace rvc::transport {
namespace {

class ShardSource final : public Source {
 public:
  ShardSource(ZenohShardSubscriptions& owner, ZenohShardSubscriptions::Input* input) : owner_(owner), input_(input) {}
  ~ShardSource() override { stop(); }
  void start(FrameHandler handler) override {
    started_ = true;
    owner_.started(input_, std::move(handler));
  }
  void stop() override {
    if (started_) owner_.stopped(input_);
    started_ = false;
  }

 private:
  ZenohShardSubscriptions& owner_;
  ZenohShardSubscriptions::Input* input_;
  bool started_ = false;
};

}  // namespace

ZenohShardSubscriptions::ZenohShardSubscriptions(std::shared_ptr<ZenohSession> session,
                                                 runtime::fleet::ShardPattern pattern,
                                                 runtime::fleet::GroupMembers& members, std::string group)
    : session_(std::move(session)), pattern_(std::move(pattern)), members_(members), group_(std::move(group)) {
  // History: the vehicles already announced when this replica starts.
  discovery_ = std::make_unique<ZenohLivelinessSubscriber>(
      session_, pattern_.text(), true, [this](std::string_view key, bool alive) {
        if (!alive) return;
        const auto shard = pattern_.shard_of(key);
        if (!shard) return;
        std::lock_guard lock(mutex_);
        if (shards_.insert(std::string(*shard)).second) {
          dirty_ = true;
          cv_.notify_all();
        }
      });
  worker_ = std::thread([this] { run(); });
}

ZenohShardSubscriptions::~ZenohShardSubscriptions() { close(); }

void ZenohShardSubscriptions::close() {
  {
    std::lock_guard lock(mutex_);
    if (stop_ && !worker_.joinable()) return;
    stop_ = true;
    cv_.notify_all();
  }
  if (worker_.joinable()) worker_.join();
  discovery_.reset();
  std::lock_guard lock(mutex_);
  for (auto& in : inputs_) in->subs.clear();
}

std::unique_ptr<Source> ZenohShardSubscriptions::source(const std::string& keyexpr) {
  if (!pattern_.narrow(keyexpr, pattern_.text()))
    throw std::invalid_argument("--shard-subscribe owned: the key '" + keyexpr + "' does not begin with '*' where --shard-by '" +
                                pattern_.text() + "' has '*' and its literals where it has literals");
  std::lock_guard lock(mutex_);
  inputs_.push_back(std::make_unique<Input>());
  inputs_.back()->keyexpr = keyexpr;
  return std::make_unique<ShardSource>(*this, inputs_.back().get());
}

void ZenohShardSubscriptions::started(Input* input, FrameHandler handler) {
  std::lock_guard lock(mutex_);
  {
    std::lock_guard in_lock(*input->mutex);
    *input->closed = false;
  }
  input->handler = std::move(handler);
  dirty_ = true;
  cv_.notify_all();
}

void ZenohShardSubscriptions::stopped(Input* input) {
  std::map<std::string, std::unique_ptr<ZenohSubscriber>> subs;
  {
    std::lock_guard lock(mutex_);
    subs.swap(input->subs);
    input->handler = nullptr;
  }
  subs.clear();  // undeclared outside the lock: a callback may be running
  std::lock_guard lock(*input->mutex);
  *input->closed = true;  // after this no handler call runs or will run
}

void ZenohShardSubscriptions::run() {
  uint64_t generation = UINT64_MAX;
  std::unique_lock lock(mutex_);
  while (!stop_) {
    cv_.wait_for(lock, std::chrono::milliseconds(50));
    if (stop_) break;
    const uint64_t now = members_.generation();
    if (!dirty_ && now == generation) continue;
    generation = now;
    dirty_ = false;
    lock.unlock();
    try {
      reconcile();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc monitor: group %s: shard subscriptions: %s\n", group_.c_str(), e.what());
    }
    lock.lock();
  }
}

void ZenohShardSubscriptions::reconcile() {
  // Which shards this replica receives: those it owns and those it backs up.
  const std::vector<std::string> members = members_.snapshot();
  std::set<std::string> shards;
  std::vector<Input*> inputs;
  {
    std::lock_guard lock(mutex_);
    shards = shards_;
    for (auto& in : inputs_)
      if (in->handler) inputs.push_back(in.get());
  }
  std::set<std::string> wanted;
  for (const auto& shard : shards)
    for (const auto& m : runtime::fleet::owners_of(shard, members, 2))
      if (m == members_.self()) wanted.insert(shard);
  size_t added = 0, removed = 0;
  for (Input* in : inputs) {
    std::vector<std::unique_ptr<ZenohSubscriber>> gone;
    std::vector<std::string> to_add;
    {
      std::lock_guard lock(mutex_);
      for (auto it = in->subs.begin(); it != in->subs.end();)
        if (!wanted.count(it->first)) {
          gone.push_back(std::move(it->second));
          it = in->subs.erase(it);
        } else {
          ++it;
        }
      for (const auto& shard : wanted)
        if (!in->subs.count(shard)) to_add.push_back(shard);
    }
    removed += gone.size();
    gone.clear();
    for (const auto& shard : to_add) {
      const std::string key = *pattern_.narrow(in->keyexpr, shard);
      FrameHandler handler;
      {
        std::lock_guard lock(mutex_);
        if (stop_ || !in->handler) return;
        handler = in->handler;
      }
      auto on_sample = [handler, mu = in->mutex, closed = in->closed](const ZenohSample& s) {
        const auto a = decode_seq_attachment(reinterpret_cast<const uint8_t*>(s.attachment.data()), s.attachment.size());
        Frame f;
        f.seq = a.seq;
        f.eos = a.eos;
        f.publisher = a.publisher;
        if (!a.eos) f.payload = s.payload;
        f.key = s.key;
        std::lock_guard lock(*mu);  // one input's samples of all shards: one handler call at a time
        if (!*closed) handler(f);
      };
      auto sub = std::make_unique<ZenohSubscriber>(session_, key, std::move(on_sample), true);  // announced: answers the flush barrier (docs/zenoh.md)
      {
        std::lock_guard lock(mutex_);
        // The input may have stopped while this was declared: its handler
        // (the loop's queue) must not outlive stop(), so the subscriber goes.
        if (!stop_ && in->handler) {
          in->subs.emplace(shard, std::move(sub));
          ++added;
          continue;
        }
      }
      return;  // `sub` is undeclared here, outside the lock
    }
  }
  if (added || removed)
    std::fprintf(stderr, "rvc monitor: group %s: subscribed to %zu of %zu shards (owned or backed up): +%zu -%zu subscribers\n",
                 group_.c_str(), wanted.size(), shards.size(), added, removed);
}

}  // namespace rvc::transport
