// An httplib::Server whose connections have a whole-request deadline: the
// request (line, headers and any body) must be read within `request_seconds`
// of the connection's accept, however its bytes trickle in. cpp-httplib's own
// read timeout bounds each read only, so a client sending a byte every 1.5 s
// held a server thread for minutes, and 40 of them left /api/health
// unanswered (issue 36). Each connection serves one request and closes, as
// the dashboard wants (server.cpp); writes keep cpp-httplib's per-write
// timeout (an event stream writes for as long as it lasts).
//
// cpp-httplib (0.11) handles each accepted socket in the virtual
// process_and_close_socket; this override reads through DeadlineStream and
// hands the request to the library's own process_request.
#pragma once

#include <httplib.h>

#include <chrono>

namespace rvc::dashboard {

class DeadlineServer : public httplib::Server {
 public:
  // `request_seconds`: from accept to the last byte of the request;
  // `write_seconds`: each write.
  DeadlineServer(std::chrono::milliseconds request, std::chrono::milliseconds write)
      : request_(request), write_(write) {}

 private:
  bool process_and_close_socket(socket_t sock) override;

  std::chrono::milliseconds request_, write_;
};

}  // namespace rvc::dashboard
