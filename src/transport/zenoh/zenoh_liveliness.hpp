// A liveliness subscriber: the tokens matching a key expression as they come
// and go (rvc monitor --group: the group's member set). RAII over
// rvc_zenoh_liveliness_subscribe.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "transport/zenoh/zenoh_session.hpp"

struct rvc_zenoh_liveliness_subscriber;

namespace rvc::transport {

class ZenohLivelinessSubscriber {
 public:
  // alive: the token appeared (or was alive at declaration, with history) or went.
  using Callback = std::function<void(std::string_view key, bool alive)>;
  // The callback runs on Zenoh threads and must not throw.
  ZenohLivelinessSubscriber(std::shared_ptr<ZenohSession> session, const std::string& keyexpr, bool history,
                            Callback callback);
  ~ZenohLivelinessSubscriber();
  ZenohLivelinessSubscriber(const ZenohLivelinessSubscriber&) = delete;
  ZenohLivelinessSubscriber& operator=(const ZenohLivelinessSubscriber&) = delete;

 private:
  std::shared_ptr<ZenohSession> session_;
  std::unique_ptr<Callback> callback_;
  rvc_zenoh_liveliness_subscriber* sub_ = nullptr;
};

}  // namespace rvc::transport
