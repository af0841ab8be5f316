// The Zenoh implementation of rvc's transport seam (transport/endpoint.hpp).
// Sequence numbers and the end-of-stream marker travel in the attachment
// (seq_attachment.hpp, docs/zenoh.md); payloads are passed through untouched.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "transport/endpoint.hpp"
#include "transport/zenoh/zenoh_options.hpp"
#include "transport/zenoh/zenoh_session.hpp"

namespace rvc::transport {

// Subscribes to a key expression. Samples with an rvc attachment carry their
// seq (and EOS flag); samples without one get seq 0. Delete samples are ignored.
// Handler calls never overlap (serialised even when several links deliver).
// Which attachment the samples carry: rvc's own (seq_attachment.hpp) or
// rmw_zenoh's (seq, source timestamp, GID: rmw_zenoh_format.hpp), whose GID
// becomes the frame's publisher.
enum class ZenohAttachmentFormat { Rvc, RmwZenoh };

class ZenohSource : public Source {
 public:
  ZenohSource(std::shared_ptr<ZenohSession> session, std::string keyexpr,
              ZenohAttachmentFormat format = ZenohAttachmentFormat::Rvc);
  ~ZenohSource() override;
  void start(FrameHandler handler) override;
  void stop() override;
  bool handler_may_block() const override { return true; }
  const std::string& keyexpr() const { return keyexpr_; }

 private:
  std::shared_ptr<ZenohSession> session_;
  std::string keyexpr_;
  ZenohAttachmentFormat format_;
  std::unique_ptr<ZenohSubscriber> sub_;
};

// Publishes on a key: reliable, blocking under congestion, seq attached.
class ZenohSink : public Sink {
 public:
  ZenohSink(std::shared_ptr<ZenohSession> session, std::string keyexpr, bool express = false);
  void put(std::string_view payload, uint64_t seq) override;
  void put_eos(uint64_t last_seq) override;
  // n <= 1: any subscriber (also non-rvc ones); n > 1: n rvc subscribers.
  bool wait_matched(size_t n, std::chrono::milliseconds timeout) override;
  // Waits (up to 60 s) until every announced rvc subscriber has taken every
  // sample put so far: closing the session right after the last put can lose
  // samples still queued for a slow subscriber. Warns on stderr when fewer
  // subscribers answered than had announced themselves, or on timeout.
  void flush() override;
  ZenohPublisher& publisher() { return pub_; }
  std::string discovery() const override { return discovery_; }
  void set_discovery(std::string text) { discovery_ = std::move(text); }

 private:
  std::shared_ptr<ZenohSession> session_;
  std::string keyexpr_;
  ZenohPublisher pub_;
  std::string discovery_;
  uint64_t id_;  // this publisher's id in every attachment (seq_attachment.hpp)
  static uint64_t random_publisher_id();
};

// One line on how a session with these options meets others: its mode,
// where it listens and connects, whether it scouts by multicast and where.
std::string zenoh_discovery_summary(const ZenohOptions& opts);

// Both share one session per distinct ZenohOptions in the process. Throw
// ZenohError when the session cannot be opened or the key is invalid.
std::unique_ptr<Source> make_zenoh_source(std::string keyexpr, const ZenohOptions& opts);
std::unique_ptr<Sink> make_zenoh_sink(std::string keyexpr, const ZenohOptions& opts);
// A liveliness token on `keyexpr` in the shared session (rvc monitor
// announcing itself); it lives as long as the returned object.
std::shared_ptr<void> make_zenoh_liveliness_token(const std::string& keyexpr, const ZenohOptions& opts);

// `rvc router`: a Zenoh router (mode forced to router; listens on
// tcp/127.0.0.1:7447 unless --listen or a config file says otherwise) until
// `stop` becomes true (poll period 50 ms, so a signal handler may set it).
// Prints one line "rvc router: <zid> listening on <endpoints>" to stderr once
// ready. Returns a process exit code: 0 after stop, 1 if it cannot start.
int run_zenoh_router(const ZenohOptions& opts, std::atomic<bool>& stop);

}  // namespace rvc::transport
