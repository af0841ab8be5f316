// RAII C++ wrappers over the rvc_zenoh C ABI (rvc_zenoh.h). Errors become
// ZenohError exceptions carrying the library's message.
//
// Lifetimes: subscribers and publishers hold a shared_ptr to their session,
// so a session is closed only after everything declared on it is gone.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>
#include <string_view>

#include "transport/zenoh/zenoh_options.hpp"

struct rvc_zenoh_config;
struct rvc_zenoh_session;
struct rvc_zenoh_subscriber;
struct rvc_zenoh_publisher;
struct rvc_zenoh_token;

namespace rvc::transport {

class ZenohError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The Zenoh config rvc would open for `opts`, as JSON (for --verbose output
// and tests). `key` selects a sub-tree, e.g. "listen/endpoints"; "" = all.
std::string zenoh_config_json(const ZenohOptions& opts, const std::string& key = "");

// Zenoh's log output to stderr (RUST_LOG overrides `fallback_filter`).
void zenoh_init_logging(const char* fallback_filter = "error");

class ZenohSession {
 public:
  // Opens a new session. Throws ZenohError (bad config, cannot connect...).
  static std::shared_ptr<ZenohSession> open(const ZenohOptions& opts);
  // From a JSON5 config text; nullptr = rvc's loopback-only default.
  static std::shared_ptr<ZenohSession> open_json5(const char* json5 = nullptr);
  // One session per distinct options in this process, shared by every
  // endpoint that asks while it is alive (a monitor reading and writing Zenoh
  // must not open two sessions listening on the same port).
  static std::shared_ptr<ZenohSession> shared(const ZenohOptions& opts);

  ~ZenohSession();
  ZenohSession(const ZenohSession&) = delete;
  ZenohSession& operator=(const ZenohSession&) = delete;

  std::string zid() const;
  rvc_zenoh_session* raw() const { return s_; }
  // The keys of the liveliness tokens alive now that match `keyexpr` (graph
  // discovery), waiting at most `timeout` for the peers' answers.
  std::vector<std::string> liveliness_get(const std::string& keyexpr, std::chrono::milliseconds timeout) const;

 private:
  explicit ZenohSession(rvc_zenoh_session* s) : s_(s) {}
  rvc_zenoh_session* s_;
};

struct ZenohSample {
  std::string_view payload;     // borrowed for the callback only
  std::string_view attachment;  // empty when none
  bool has_attachment = false;
  std::string_view key;         // the sample's key expression, borrowed likewise
};
using ZenohSampleCallback = std::function<void(const ZenohSample&)>;

class ZenohSubscriber {
 public:
  // Declares the subscriber; the callback runs on Zenoh threads, possibly
  // concurrently with itself. With `announce` the subscriber is counted by
  // ZenohPublisher::announced_subscribers() / wait_matched(n > 1).
  ZenohSubscriber(std::shared_ptr<ZenohSession> session, const std::string& keyexpr,
                  ZenohSampleCallback callback, bool announce = true);
  ~ZenohSubscriber();
  ZenohSubscriber(const ZenohSubscriber&) = delete;
  ZenohSubscriber& operator=(const ZenohSubscriber&) = delete;

  // After return the callback is not running and will not run again.
  // Idempotent; must not be called from the callback itself.
  void undeclare();
  // Exceptions thrown by the callback (swallowed: they cannot cross Zenoh).
  uint64_t callback_errors() const;

  struct State;

 private:
  std::shared_ptr<ZenohSession> session_;
  std::unique_ptr<State> state_;
  rvc_zenoh_subscriber* sub_ = nullptr;
};

class ZenohPublisher {
 public:
  // Reliable, congestion control Block: put() waits rather than drops.
  ZenohPublisher(std::shared_ptr<ZenohSession> session, const std::string& keyexpr,
                 bool express = false);
  ~ZenohPublisher();
  ZenohPublisher(const ZenohPublisher&) = delete;
  ZenohPublisher& operator=(const ZenohPublisher&) = delete;

  // nullopt = no attachment at all.
  void put(std::string_view payload, std::optional<std::string_view> attachment = std::nullopt);
  // Any subscriber matches (Zenoh matching status).
  bool matching() const;
  // rvc subscribers that announced themselves on a matching key.
  std::size_t announced_subscribers() const;
  // n <= 1: any subscriber; n > 1: n announced rvc subscribers. False on timeout.
  bool wait_matched(std::size_t n, std::chrono::milliseconds timeout);
  // Flush barrier: waits until every rvc subscriber reachable now has taken
  // every sample put before (see rvc_zenoh_publisher_flush). Returns how many
  // answered; nullopt when `timeout` ran out first.
  std::optional<std::size_t> flush(std::chrono::milliseconds timeout);

 private:
  std::shared_ptr<ZenohSession> session_;
  rvc_zenoh_publisher* pub_ = nullptr;
};

// A liveliness token: liveliness subscribers on a matching key see it while
// it lives, and see it go when it is destroyed or the process dies.
class ZenohLivelinessToken {
 public:
  ZenohLivelinessToken(std::shared_ptr<ZenohSession> session, const std::string& keyexpr);
  ~ZenohLivelinessToken();
  ZenohLivelinessToken(const ZenohLivelinessToken&) = delete;
  ZenohLivelinessToken& operator=(const ZenohLivelinessToken&) = delete;

 private:
  std::shared_ptr<ZenohSession> session_;
  rvc_zenoh_token* token_ = nullptr;
};

}  // namespace rvc::transport
