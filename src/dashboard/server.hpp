// The dashboard's HTTP server (docs/dashboard.md): the page at /, the JSON API
// (api.hpp) under /api/, and server-sent events at /api/events. Read-only: it
// never writes a row. The monitor may write the same database meanwhile
// (SQLite in WAL mode lets readers in), so every request takes its own
// connection from a small pool: a Database is not thread-safe.
#pragma once

#include <functional>
#include <memory>
#include <string>

namespace rvc::dashboard {

struct ServerOptions {
  std::string db_uri;           // sqlite:PATH or postgresql://...
  std::string host = "127.0.0.1";
  int port = 8765;              // 0: any free port (port() tells which)
  double poll_seconds = 0.2;    // how often an event stream looks for new rows
  bool allow_remote = false;    // else: a loopback address only, and loopback Host headers only
  int max_streams = 8;          // event streams at once (each holds a server thread)
};

// "127.0.0.1:8765", "[::1]:0", "localhost:8765" -> host, port. False (and
// `error`) for anything else.
bool parse_listen(const std::string& text, std::string& host, int& port, std::string& error);
// 127.0.0.0/8, ::1 (also as ::ffff:127.x.y.z) and "localhost".
bool is_loopback_host(const std::string& host);

class DashboardServer {
 public:
  explicit DashboardServer(ServerOptions options);
  ~DashboardServer();
  DashboardServer(const DashboardServer&) = delete;
  DashboardServer& operator=(const DashboardServer&) = delete;

  // Opens the database (throws store::DbError: a bad URI, an unreachable
  // server, a missing SQLite file) and binds the address (throws
  // std::runtime_error). Returns the port bound.
  int start();
  int port() const;
  std::string db_description() const;
  // Serves until stop() is called or `should_stop` (checked every 100 ms)
  // returns true; then closes every event stream and returns.
  void run(const std::function<bool()>& should_stop = {});
  void stop();  // from any thread

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rvc::dashboard
