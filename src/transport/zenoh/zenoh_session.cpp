#include "transport/zenoh/zenoh_session.hpp"

#include <atomic>
#include <cstdio>
#include <map>
#include <mutex>
#include <vector>

#include "transport/zenoh/rvc_zenoh.h"

namespace rvc::transport {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw ZenohError("zenoh: " + what + ": " + rvc_zenoh_last_error());
}

void check(int rc, const std::string& what) {
  if (rc < 0) fail(what);
}

struct ConfigDeleter {
  void operator()(rvc_zenoh_config* c) const { rvc_zenoh_config_free(c); }
};
using ConfigPtr = std::unique_ptr<rvc_zenoh_config, ConfigDeleter>;

ConfigPtr build_config(const ZenohOptions& o) {
  std::vector<const char*> connect, listen;
  for (const auto& e : o.connect) connect.push_back(e.c_str());
  for (const auto& e : o.listen) listen.push_back(e.c_str());
  const bool have_file = !o.config_file.empty();
  rvc_zenoh_config_opts c{};
  c.base_file = have_file ? o.config_file.c_str() : nullptr;
  // A config file keeps its own mode unless --mode was given explicitly.
  c.mode = (!have_file || o.mode_explicit) ? o.mode.c_str() : nullptr;
  c.connect = connect.data();
  c.n_connect = connect.size();
  c.listen = listen.data();
  c.n_listen = listen.size();
  c.multicast_scouting = o.multicast_scouting;
  rvc_zenoh_config* cfg = nullptr;
  check(rvc_zenoh_config_build(&c, &cfg), "building config");
  return ConfigPtr(cfg);
}

std::string take_string(char* s) {
  std::string out = s ? s : "";
  rvc_zenoh_string_free(s);
  return out;
}

std::string registry_key(const ZenohOptions& o) {
  // '\x1f' cannot appear in endpoints, modes or sane paths.
  std::string k = o.mode + '\x1f' + (o.mode_explicit ? "1" : "0") + '\x1f' +
                  std::to_string(o.multicast_scouting) + '\x1f' + o.config_file + '\x1f';
  for (const auto& e : o.connect) k += "c:" + e + '\x1f';
  for (const auto& e : o.listen) k += "l:" + e + '\x1f';
  return k;
}

}  // namespace

std::string zenoh_config_json(const ZenohOptions& opts, const std::string& key) {
  ConfigPtr cfg = build_config(opts);
  char* s = rvc_zenoh_config_get_json(cfg.get(), key.c_str());
  if (!s) fail("reading config key '" + key + "'");
  return take_string(s);
}

void zenoh_init_logging(const char* fallback_filter) {
  check(rvc_zenoh_init_logging(fallback_filter), "initialising logging");
}

// ---- ZenohSession ----------------------------------------------------------

std::shared_ptr<ZenohSession> ZenohSession::open(const ZenohOptions& opts) {
  ConfigPtr cfg = build_config(opts);
  rvc_zenoh_session* s = nullptr;
  check(rvc_zenoh_session_open_config(cfg.get(), &s), "opening session");
  return std::shared_ptr<ZenohSession>(new ZenohSession(s));
}

std::shared_ptr<ZenohSession> ZenohSession::open_json5(const char* json5) {
  rvc_zenoh_session* s = nullptr;
  check(rvc_zenoh_session_open(json5, &s), "opening session");
  return std::shared_ptr<ZenohSession>(new ZenohSession(s));
}

std::shared_ptr<ZenohSession> ZenohSession::shared(const ZenohOptions& opts) {
  static std::mutex mu;
  static std::map<std::string, std::weak_ptr<ZenohSession>> sessions;
  std::lock_guard lock(mu);
  auto& slot = sessions[registry_key(opts)];
  if (auto s = slot.lock()) return s;
  auto s = open(opts);
  slot = s;
  return s;
}

ZenohSession::~ZenohSession() {
  if (rvc_zenoh_session_close(s_) < 0)
    std::fprintf(stderr, "rvc: zenoh: closing session: %s\n", rvc_zenoh_last_error());
}

std::string ZenohSession::zid() const {
  char buf[64];
  check(rvc_zenoh_session_zid(s_, buf, sizeof buf), "reading session id");
  return buf;
}

// ---- ZenohSubscriber -------------------------------------------------------

struct ZenohSubscriber::State {
  ZenohSampleCallback callback;
  std::atomic<uint64_t> errors{0};

  static void trampoline(const uint8_t* payload, size_t len, const uint8_t* att, size_t att_len, const uint8_t* key,
                         size_t key_len, void* ctx) noexcept {
    auto* st = static_cast<State*>(ctx);
    ZenohSample sample;
    sample.payload = std::string_view(reinterpret_cast<const char*>(payload), len);
    sample.key = std::string_view(reinterpret_cast<const char*>(key), key_len);
    sample.has_attachment = att != nullptr;
    if (att) sample.attachment = std::string_view(reinterpret_cast<const char*>(att), att_len);
    // An exception must not unwind into Rust; count it, tell once.
    try {
      st->callback(sample);
    } catch (const std::exception& e) {
      if (st->errors.fetch_add(1) == 0)
        std::fprintf(stderr, "rvc: zenoh: subscriber callback failed: %s\n", e.what());
    } catch (...) {
      if (st->errors.fetch_add(1) == 0)
        std::fprintf(stderr, "rvc: zenoh: subscriber callback failed\n");
    }
  }
};

ZenohSubscriber::ZenohSubscriber(std::shared_ptr<ZenohSession> session, const std::string& keyexpr,
                                 ZenohSampleCallback callback, bool announce)
    : session_(std::move(session)), state_(std::make_unique<State>()) {
  if (!session_) throw ZenohError("zenoh: subscriber needs a session");
  state_->callback = std::move(callback);
  check(rvc_zenoh_subscriber_declare(session_->raw(), keyexpr.c_str(), &State::trampoline,
                                     state_.get(), announce ? 1 : 0, &sub_),
        "declaring subscriber on '" + keyexpr + "'");
}

ZenohSubscriber::~ZenohSubscriber() { undeclare(); }

void ZenohSubscriber::undeclare() {
  if (!sub_) return;
  rvc_zenoh_subscriber* s = sub_;
  sub_ = nullptr;
  // Even on error the handle is freed and callbacks are stopped.
  if (rvc_zenoh_subscriber_undeclare(s) < 0)
    std::fprintf(stderr, "rvc: zenoh: undeclaring subscriber: %s\n", rvc_zenoh_last_error());
}

uint64_t ZenohSubscriber::callback_errors() const { return state_->errors.load(); }

// ---- ZenohPublisher --------------------------------------------------------

ZenohPublisher::ZenohPublisher(std::shared_ptr<ZenohSession> session, const std::string& keyexpr,
                               bool express)
    : session_(std::move(session)) {
  if (!session_) throw ZenohError("zenoh: publisher needs a session");
  check(rvc_zenoh_publisher_declare(session_->raw(), keyexpr.c_str(), express ? 1 : 0, &pub_),
        "declaring publisher on '" + keyexpr + "'");
}

std::vector<std::string> ZenohSession::liveliness_get(const std::string& keyexpr,
                                                     std::chrono::milliseconds timeout) const {
  std::vector<std::string> keys;
  auto on_key = [](const uint8_t* key, size_t len, void* ctx) {
    static_cast<std::vector<std::string>*>(ctx)->emplace_back(reinterpret_cast<const char*>(key), len);
  };
  check(rvc_zenoh_liveliness_get(s_, keyexpr.c_str(), static_cast<uint64_t>(timeout.count()), on_key, &keys),
        "liveliness query '" + keyexpr + "'");
  return keys;
}

ZenohLivelinessToken::ZenohLivelinessToken(std::shared_ptr<ZenohSession> session, const std::string& keyexpr)
    : session_(std::move(session)) {
  if (!session_) throw ZenohError("zenoh: liveliness token needs a session");
  check(rvc_zenoh_token_declare(session_->raw(), keyexpr.c_str(), &token_),
        "declaring liveliness token '" + keyexpr + "'");
}

ZenohLivelinessToken::~ZenohLivelinessToken() {
  if (token_ && rvc_zenoh_token_undeclare(token_) < 0)
    std::fprintf(stderr, "rvc: zenoh: undeclaring liveliness token: %s\n", rvc_zenoh_last_error());
}

ZenohPublisher::~ZenohPublisher() {
  if (pub_ && rvc_zenoh_publisher_undeclare(pub_) < 0)
    std::fprintf(stderr, "rvc: zenoh: undeclaring publisher: %s\n", rvc_zenoh_last_error());
}

void ZenohPublisher::put(std::string_view payload, std::optional<std::string_view> attachment) {
  static const uint8_t kEmpty = 0;  // non-NULL pointer for "empty attachment"
  const auto* p = reinterpret_cast<const uint8_t*>(payload.data());
  const uint8_t* a = nullptr;
  size_t alen = 0;
  if (attachment) {
    a = attachment->empty() ? &kEmpty : reinterpret_cast<const uint8_t*>(attachment->data());
    alen = attachment->size();
  }
  check(rvc_zenoh_publisher_put(pub_, p, payload.size(), a, alen), "put");
}

bool ZenohPublisher::matching() const {
  int m = 0;
  check(rvc_zenoh_publisher_matching(pub_, &m, nullptr), "matching status");
  return m != 0;
}

std::size_t ZenohPublisher::announced_subscribers() const {
  size_t n = 0;
  check(rvc_zenoh_publisher_matching(pub_, nullptr, &n), "matching status");
  return n;
}

std::optional<std::size_t> ZenohPublisher::flush(std::chrono::milliseconds timeout) {
  const auto ms = timeout.count() < 0 ? 0 : static_cast<uint64_t>(timeout.count());
  size_t confirmed = 0;
  const int rc = rvc_zenoh_publisher_flush(pub_, ms, &confirmed);
  check(rc, "flush");
  if (rc == 0) return std::nullopt;
  return confirmed;
}

bool ZenohPublisher::wait_matched(std::size_t n, std::chrono::milliseconds timeout) {
  const auto ms = timeout.count() < 0 ? 0 : static_cast<uint64_t>(timeout.count());
  int rc = rvc_zenoh_publisher_wait_matched(pub_, n, ms);
  check(rc, "waiting for subscribers");
  return rc == 1;
}

}  // namespace rvc::transport
