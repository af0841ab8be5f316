#include "dashboard/deadline_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <string>

namespace rvc::dashboard {
namespace {

using Clock = std::chrono::steady_clock;

// Waits for `events` on the socket for at most `wait`; true if it came.
bool wait_for(socket_t sock, short events, std::chrono::milliseconds wait) {
  if (wait.count() <= 0) return false;
  pollfd p{sock, events, 0};
  for (;;) {
    const int r = ::poll(&p, 1, static_cast<int>(wait.count()));
    if (r < 0 && errno == EINTR) continue;
    return r > 0 && (p.revents & (events | POLLHUP | POLLERR)) != 0;
  }
}

void address_of(const sockaddr_storage& a, std::string& ip, int& port) {
  char text[INET6_ADDRSTRLEN] = {};
  if (a.ss_family == AF_INET) {
    const auto& v4 = reinterpret_cast<const sockaddr_in&>(a);
    ::inet_ntop(AF_INET, &v4.sin_addr, text, sizeof text);
    port = ntohs(v4.sin_port);
  } else if (a.ss_family == AF_INET6) {
    const auto& v6 = reinterpret_cast<const sockaddr_in6&>(a);
    ::inet_ntop(AF_INET6, &v6.sin6_addr, text, sizeof text);
    port = ntohs(v6.sin6_port);
  }
  ip = text;
}

// Reads wait at most until the deadline; after it every read fails (the
// library then answers nothing and the connection closes).
class DeadlineStream final : public httplib::Stream {
 public:
  DeadlineStream(socket_t sock, Clock::time_point deadline, std::chrono::milliseconds write)
      : sock_(sock), deadline_(deadline), write_(write) {}

  bool is_readable() const override {
    return wait_for(sock_, POLLIN, std::chrono::ceil<std::chrono::milliseconds>(deadline_ - Clock::now()));
  }
  bool is_writable() const override { return wait_for(sock_, POLLOUT, write_); }
  ssize_t read(char* ptr, size_t size) override {
    if (!is_readable()) return -1;
    for (;;) {
      const ssize_t n = ::recv(sock_, ptr, size, 0);
      if (n < 0 && errno == EINTR) continue;
      return n;
    }
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (!is_writable()) return -1;
    for (;;) {
      const ssize_t n = ::send(sock_, ptr, size, MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      return n;
    }
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override { name(::getpeername, ip, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { name(::getsockname, ip, port); }
  socket_t socket() const override { return sock_; }

 private:
  template <class Get>
  void name(Get get, std::string& ip, int& port) const {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    ip.clear();
    port = 0;
    if (get(sock_, reinterpret_cast<sockaddr*>(&a), &len) == 0) address_of(a, ip, port);
  }

  socket_t sock_;
  Clock::time_point deadline_;
  std::chrono::milliseconds write_;
};

}  // namespace

bool DeadlineServer::process_and_close_socket(socket_t sock) {
  const Clock::time_point deadline = Clock::now() + request_;
  bool ok = false;
  // A connection that sends nothing by the deadline is closed unanswered.
  if (wait_for(sock, POLLIN, request_)) {
    DeadlineStream stream(sock, deadline, write_);
    bool closed = false;
    ok = process_request(stream, /*close_connection=*/true, closed, nullptr);
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return ok;
}

}  // namespace rvc::dashboard
