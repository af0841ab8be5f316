#include "transport/zenoh/zenoh_endpoint.hpp"

#include <cstdio>
#include <random>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

#include "transport/zenoh/rmw_zenoh_format.hpp"
#include "transport/zenoh/seq_attachment.hpp"

namespace rvc::transport {

// ---- ZenohSource -----------------------------------------------------------

ZenohSource::ZenohSource(std::shared_ptr<ZenohSession> session, std::string keyexpr, ZenohAttachmentFormat format)
    : session_(std::move(session)), keyexpr_(std::move(keyexpr)), format_(format) {}

ZenohSource::~ZenohSource() { stop(); }

void ZenohSource::start(FrameHandler handler) {
  if (sub_) throw std::logic_error("ZenohSource::start called twice");
  // Zenoh may deliver from several threads at once (one per link); the seam
  // promises a single transport thread's worth of calls, so serialise them.
  auto on_sample = [handler = std::move(handler), rmw = format_ == ZenohAttachmentFormat::RmwZenoh,
                    mu = std::make_shared<std::mutex>()](const ZenohSample& s) {
    if (rmw) {
      // rmw_zenoh: no end-of-stream marker; a sample without a valid
      // attachment is counted with seq 0 (not accounted), like a plain one.
      const auto a = rmw_zenoh::decode_attachment(reinterpret_cast<const uint8_t*>(s.attachment.data()),
                                                  s.attachment.size());
      Frame f;
      if (a && a->seq > 0) {
        f.seq = static_cast<uint64_t>(a->seq);
        f.publisher = rmw_zenoh::publisher_id(a->gid);
      }
      f.payload = s.payload;
      f.key = s.key;
      std::lock_guard lock(*mu);
      handler(f);
      return;
    }
    const auto a = decode_seq_attachment(reinterpret_cast<const uint8_t*>(s.attachment.data()),
                                         s.attachment.size());
    Frame f;
    f.seq = a.seq;
    f.eos = a.eos;
    f.publisher = a.publisher;
    if (!a.eos) f.payload = s.payload;  // an EOS marker carries no data
    f.key = s.key;
    std::lock_guard lock(*mu);
    handler(f);
  };
  // Announced, so a replayer waiting for n monitors can count this one.
  sub_ = std::make_unique<ZenohSubscriber>(session_, keyexpr_, std::move(on_sample), true);
}

void ZenohSource::stop() {
  if (sub_) sub_->undeclare();
  sub_.reset();
}

// ---- ZenohSink -------------------------------------------------------------

ZenohSink::ZenohSink(std::shared_ptr<ZenohSession> session, std::string keyexpr, bool express)
    : session_(session), keyexpr_(keyexpr), pub_(std::move(session), keyexpr, express), id_(random_publisher_id()) {}

uint64_t ZenohSink::random_publisher_id() {
  std::random_device rd;
  uint64_t id = 0;
  while (id == 0) id = (static_cast<uint64_t>(rd()) << 32) ^ rd();  // 0 means "unknown"
  return id;
}

void ZenohSink::put(std::string_view payload, uint64_t seq) {
  const auto att = encode_seq_attachment(seq, false, id_);
  pub_.put(payload, std::string_view(reinterpret_cast<const char*>(att.data()), att.size()));
}

void ZenohSink::put_eos(uint64_t last_seq) {
  const auto att = encode_seq_attachment(last_seq, true, id_);
  pub_.put({}, std::string_view(reinterpret_cast<const char*>(att.data()), att.size()));
}

void ZenohSink::flush() {
  const std::size_t announced = pub_.announced_subscribers();
  const auto confirmed = pub_.flush(std::chrono::seconds(60));
  if (!confirmed)
    std::fprintf(stderr, "rvc: zenoh: flush of '%s' not confirmed within 60 s (a subscriber is stalled?)\n",
                 keyexpr_.c_str());
  else if (*confirmed < announced)
    std::fprintf(stderr, "rvc: zenoh: flush of '%s' confirmed by %zu of %zu rvc subscribers\n", keyexpr_.c_str(),
                 *confirmed, announced);
}

bool ZenohSink::wait_matched(size_t n, std::chrono::milliseconds timeout) {
  return pub_.wait_matched(n, timeout);
}

// ---- factories ---------------------------------------------------------------

std::unique_ptr<Source> make_zenoh_source(std::string keyexpr, const ZenohOptions& opts) {
  return std::make_unique<ZenohSource>(ZenohSession::shared(opts), std::move(keyexpr));
}

std::shared_ptr<void> make_zenoh_liveliness_token(const std::string& keyexpr, const ZenohOptions& opts) {
  return std::make_shared<ZenohLivelinessToken>(ZenohSession::shared(opts), keyexpr);
}

std::unique_ptr<Sink> make_zenoh_sink(std::string keyexpr, const ZenohOptions& opts) {
  auto sink = std::make_unique<ZenohSink>(ZenohSession::shared(opts), std::move(keyexpr), opts.express);
  sink->set_discovery(zenoh_discovery_summary(opts));
  return sink;
}

std::string zenoh_discovery_summary(const ZenohOptions& opts) {
  auto unquote = [](std::string s) {
    if (s.size() >= 2 && s.front() == '"') s = s.substr(1, s.size() - 2);
    return s;
  };
  std::string text = "Zenoh " + unquote(zenoh_config_json(opts, "mode"));
  const std::string listen = zenoh_config_json(opts, "listen/endpoints"),
                    connect = zenoh_config_json(opts, "connect/endpoints");
  if (listen != "[]") text += ", listening on " + listen + (listen.find(":0\"") != std::string::npos ? " (:0 = a free port)" : "");
  if (connect != "[]") text += ", connecting to " + connect;
  if (zenoh_config_json(opts, "scouting/multicast/enabled") == "true")
  {
    std::string address = unquote(zenoh_config_json(opts, "scouting/multicast/address"));
    if (address == "null") address = "224.0.0.224:7446";  // Zenoh's default group
    text += ", multicast scouting on " + address + " via " +
            unquote(zenoh_config_json(opts, "scouting/multicast/interface"));
  }
  else
    text += ", no multicast scouting";
  text += ". Peers meet by multicast scouting on this host, or by --connect to a --listen endpoint "
          "(or a router: rvc router, --connect tcp/HOST:7447)";
  return text;
}

// ---- router ------------------------------------------------------------------

int run_zenoh_router(const ZenohOptions& opts, std::atomic<bool>& stop) {
  ZenohOptions o = opts;
  o.mode = "router";
  o.mode_explicit = true;
  try {
    auto session = ZenohSession::open(o);
    const std::string listen = zenoh_config_json(o, "listen/endpoints");
    std::fprintf(stderr, "rvc router: %s listening on %s\n", session->zid().c_str(),
                 listen.c_str());
    std::fflush(stderr);
    while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rvc router: %s\n", e.what());
    return 1;
  }
}

}  // namespace rvc::transport
