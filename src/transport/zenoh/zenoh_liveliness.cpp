#include "transport/zenoh/zenoh_liveliness.hpp"

#include <cstdio>

#include "transport/zenoh/rvc_zenoh.h"

namespace rvc::transport {
namespace {

void trampoline(const uint8_t* key, size_t key_len, int alive, void* ctx) {
  try {
    (*static_cast<ZenohLivelinessSubscriber::Callback*>(ctx))(
        std::string_view(reinterpret_cast<const char*>(key), key_len), alive != 0);
  } catch (...) {
    std::fprintf(stderr, "rvc: zenoh: a liveliness callback failed\n");  // nothing may cross into Rust
  }
}

}  // namespace

ZenohLivelinessSubscriber::ZenohLivelinessSubscriber(std::shared_ptr<ZenohSession> session,
                                                     const std::string& keyexpr, bool history, Callback callback)
    : session_(std::move(session)), callback_(std::make_unique<Callback>(std::move(callback))) {
  if (!session_) throw ZenohError("zenoh: liveliness subscriber needs a session");
  if (rvc_zenoh_liveliness_subscribe(session_->raw(), keyexpr.c_str(), history ? 1 : 0, &trampoline, callback_.get(),
                                     &sub_) < 0)
    throw ZenohError("zenoh: liveliness subscriber on '" + keyexpr + "': " + rvc_zenoh_last_error());
}

ZenohLivelinessSubscriber::~ZenohLivelinessSubscriber() {
  if (sub_ && rvc_zenoh_liveliness_unsubscribe(sub_) < 0)
    std::fprintf(stderr, "rvc: zenoh: undeclaring liveliness subscriber: %s\n", rvc_zenoh_last_error());
}

}  // namespace rvc::transport
