#include "dashboard/server.hpp"

#include <arpa/inet.h>
#include <httplib.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "dashboard/api.hpp"
#include "dashboard/deadline_server.hpp"
#include "store/database.hpp"

namespace rvc::dashboard {

// The page, compiled in from page.html (CMakeLists.txt generates page_data.cpp).
extern const char kPage[];
extern const std::size_t kPageSize;

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kKeepAlive = std::chrono::seconds(2);  // a comment line this often: proxies keep the stream,
                                                      // and a closed client shows as a failed write
constexpr size_t kIdleConnections = 4;
// A connection's whole request (line, headers, body) must arrive within this
// of its accept, however slowly its bytes come (DeadlineServer).
constexpr auto kRequestDeadline = std::chrono::seconds(4);
constexpr auto kWriteTimeout = std::chrono::seconds(5);  // each write of a response
// Server threads besides those of event streams: enough that slow clients
// (each cut off at the deadline) leave threads for the API meanwhile.
constexpr size_t kApiThreads = 56;

// Database connections, one per request at a time (Database is not
// thread-safe); idle ones are kept, so a poll does not reopen the file.
class Pool {
 public:
  explicit Pool(std::string uri) : uri_(std::move(uri)) {}
  std::unique_ptr<store::Database> take() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!idle_.empty()) {
        auto db = std::move(idle_.back());
        idle_.pop_back();
        return db;
      }
    }
    return store::open_database_readonly(uri_);  // it never writes, not even a schema
  }
  void give(std::unique_ptr<store::Database> db) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (idle_.size() < kIdleConnections) idle_.push_back(std::move(db));
  }

 private:
  std::string uri_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<store::Database>> idle_;
};

// One connection for one piece of work. It goes back to the pool only after
// done(): after a DbError the connection may be broken (a PostgreSQL server
// that went away), so the next request opens a fresh one.
class Lease {
 public:
  explicit Lease(Pool& pool) : pool_(pool), db_(pool.take()) {}
  ~Lease() {
    if (done_) pool_.give(std::move(db_));
  }
  store::Database& operator*() { return *db_; }
  void done() { done_ = true; }

 private:
  Pool& pool_;
  std::unique_ptr<store::Database> db_;
  bool done_ = false;
};

void reply(httplib::Response& res, const Response& r) {
  res.status = r.status;
  res.set_content(r.body, "application/json");
}

// The host part of a Host header: "127.0.0.1:8765" -> 127.0.0.1, "[::1]:80" -> ::1.
std::string host_of(const std::string& header) {
  if (!header.empty() && header[0] == '[') {
    const size_t close = header.find(']');
    return close == std::string::npos ? header : header.substr(1, close - 1);
  }
  const size_t colon = header.find(':');
  return colon != std::string::npos && header.find(':', colon + 1) == std::string::npos ? header.substr(0, colon)
                                                                                        : header;
}

// What an event stream carries between polls.
struct Stream {
  EventCursor cursor;
  bool started = false;
  bool failing = false;  // the last poll failed (the error was sent once)
  Clock::time_point last_write = Clock::now();
};

}  // namespace

bool is_loopback_host(const std::string& host) {
  if (strcasecmp(host.c_str(), "localhost") == 0) return true;
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) {
    if (IN6_IS_ADDR_LOOPBACK(&v6)) return true;
    return IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127;
  }
  return false;
}

bool parse_listen(const std::string& text, std::string& host, int& port, std::string& error) {
  size_t colon;
  if (!text.empty() && text[0] == '[') {  // [IPv6]:PORT
    const size_t close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':') {
      error = "--listen '" + text + "': expected [IPv6]:PORT";
      return false;
    }
    host = text.substr(1, close - 1);
    colon = close + 1;
  } else {
    colon = text.rfind(':');
    if (colon == std::string::npos || colon == 0 || text.find(':') != colon) {
      error = "--listen '" + text + "': expected HOST:PORT (127.0.0.1:8765, [::1]:8765)";
      return false;
    }
    host = text.substr(0, colon);
  }
  const std::string digits = text.substr(colon + 1);
  if (digits.empty() || digits.size() > 5 || digits.find_first_not_of("0123456789") != std::string::npos ||
      std::stoi(digits) > 65535) {
    error = "--listen '" + text + "': the port must be 0 to 65535 (0: any free port)";
    return false;
  }
  port = std::stoi(digits);
  return true;
}

struct DashboardServer::Impl {
  explicit Impl(ServerOptions o) : options(std::move(o)), pool(options.db_uri) {}

  ServerOptions options;
  Pool pool;
  DeadlineServer http{kRequestDeadline, kWriteTimeout};
  int port = -1;
  std::string description;
  std::atomic<int> streams{0};
  // stop(): wakes run() and every event stream waiting for its next poll.
  std::mutex mutex;
  std::condition_variable wake;
  bool stopping = false;

  // Waits one poll interval; false if the server is stopping.
  bool wait_poll() {
    std::unique_lock<std::mutex> lock(mutex);
    return !wake.wait_for(lock, std::chrono::duration<double>(options.poll_seconds), [&] { return stopping; });
  }

  void routes();
  void serve_api(const httplib::Request& req, httplib::Response& res);
  void serve_events(const httplib::Request& req, httplib::Response& res);
  bool pump(Stream& s, httplib::DataSink& sink);
};

void DashboardServer::Impl::routes() {
  // Nothing leaves the machine and nothing is fetched from elsewhere: the
  // page is self-contained, and the CSP says so to the browser too.
  http.set_default_headers({
      {"Cache-Control", "no-store"},
      {"X-Content-Type-Options", "nosniff"},
      {"Referrer-Policy", "no-referrer"},
      {"Content-Security-Policy",
       "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data:; "
       "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'"},
  });
  // DNS rebinding: a web page elsewhere could point its own name at
  // 127.0.0.1 and read the results through the visitor's browser. Its
  // requests carry its name in Host, so a loopback server answers only
  // requests addressed to a loopback name.
  http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    const std::string host = host_of(req.get_header_value("Host"));
    if (options.allow_remote || host.empty() || is_loopback_host(host))
      return httplib::Server::HandlerResponse::Unhandled;
    reply(res, error_response(403, "Host '" + host + "' is not a loopback name (see --allow-remote)"));
    return httplib::Server::HandlerResponse::Handled;
  });
  http.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;  // an API error already said why
    reply(res, error_response(res.status, res.status == 404 ? "not found: " + req.path : "request failed"));
  });
  http.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_content(kPage, kPageSize, "text/html; charset=utf-8");
  });
  http.Get("/api/events", [this](const httplib::Request& req, httplib::Response& res) { serve_events(req, res); });
  http.Get(R"(/api/.*)", [this](const httplib::Request& req, httplib::Response& res) { serve_api(req, res); });
  // Read-only: every other method is 405 with the methods there are (not a
  // 404, which would say the page does not exist). A body is read before the
  // handler, so it is kept small.
  auto read_only = [](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Allow", "GET, HEAD");
    reply(res, error_response(405, req.method + " is not allowed: the dashboard is read-only (GET, HEAD)"));
  };
  http.Post(".*", read_only);
  http.Put(".*", read_only);
  http.Patch(".*", read_only);
  http.Delete(".*", read_only);
  http.Options(".*", read_only);
  http.set_payload_max_length(64 * 1024);
  // httplib's default also sets SO_REUSEPORT: a second dashboard (or any
  // process of this user) could then bind the same port and take part of the
  // traffic. SO_REUSEADDR alone still allows a restart while old connections
  // linger in TIME_WAIT.
  http.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  // A connection holds a server thread from its accept to its close, so no
  // client may keep one without doing anything: its whole request must
  // arrive within kRequestDeadline of the accept (DeadlineServer: a per-read
  // timeout alone let a byte every 1.5 s hold a thread for minutes), and
  // every connection closes after one response (no idle keep-alive; on
  // loopback a new connection costs nothing). Event streams hold a thread
  // each for as long as they last (at most max_streams; more get a 503 and
  // the connection closes); the rest of the pool answers the page and API.
  const size_t threads = static_cast<size_t>(options.max_streams) + kApiThreads;
  http.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
}

void DashboardServer::Impl::serve_api(const httplib::Request& req, httplib::Response& res) {
  try {
    Lease db(pool);
    reply(res, handle_api(*db, req.path, req.params));
    db.done();
  } catch (const store::DbError& e) {
    reply(res, error_response(503, e.what()));
  }
}

void DashboardServer::Impl::serve_events(const httplib::Request& req, httplib::Response& res) {
  if (streams.fetch_add(1) >= options.max_streams) {
    streams--;
    reply(res, error_response(503, "too many event streams (at most " + std::to_string(options.max_streams) + ")"));
    return;  // and the connection closes, as every one does after its response
  }
  auto stream = std::make_shared<Stream>();
  try {
    Lease db(pool);
    Response error;
    const bool ok = start_events(*db, req.params, req.get_header_value("Last-Event-ID"), stream->cursor, error);
    db.done();
    if (!ok) {
      streams--;
      reply(res, error);
      return;
    }
  } catch (const store::DbError& e) {
    streams--;
    reply(res, error_response(503, e.what()));
    return;
  }
  res.set_header("X-Accel-Buffering", "no");  // a proxy in front must not hold the events back
  // httplib calls the provider again after each `true`: one poll per call.
  res.set_chunked_content_provider(
      "text/event-stream", [this, stream](size_t, httplib::DataSink& sink) { return pump(*stream, sink); },
      [this](bool) { streams--; });
}

// One step of an event stream. False ends it: the client has gone (a write
// failed). When the server stops, the stream ends properly (done()).
bool DashboardServer::Impl::pump(Stream& s, httplib::DataSink& sink) {
  std::string out;
  if (!s.started) {
    s.started = true;
    // At once, so the client knows it is connected; EventSource reconnects
    // after a second when the stream breaks.
    out = "retry: 1000\n: rvc dashboard events\n\n";
  } else {
    if (!wait_poll()) {
      sink.done();
      return true;
    }
    try {
      Lease db(pool);
      out = poll_events(*db, s.cursor);
      db.done();
      if (s.failing) out = "event: db-ok\ndata: {}\n\n" + out;  // the page clears its warning
      s.failing = false;
    } catch (const store::DbError& e) {
      if (!s.failing) out = "event: db-error\ndata: " + error_response(503, e.what()).body + "\n\n";
      s.failing = true;
    }
    if (out.empty() && Clock::now() - s.last_write >= kKeepAlive) out = ": keep-alive\n\n";
  }
  if (out.empty()) return true;
  s.last_write = Clock::now();
  return sink.write(out.data(), out.size());
}

DashboardServer::DashboardServer(ServerOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}
DashboardServer::~DashboardServer() { stop(); }

int DashboardServer::start() {
  const ServerOptions& o = impl_->options;
  if (!o.allow_remote && !is_loopback_host(o.host))
    throw std::runtime_error("'" + o.host + "' is not a loopback address: the dashboard has no authentication; "
                             "pass --allow-remote to serve other machines");
  // sqlite:PATH would create an empty database: a mistyped path would show an
  // empty page instead of an error.
  if (o.db_uri.rfind("sqlite:", 0) == 0) {
    struct stat st{};
    const std::string path = o.db_uri.substr(7);
    if (!path.empty() && ::stat(path.c_str(), &st) != 0)
      throw store::DbError("no database file '" + path + "' (write one with rvc check/monitor --output sqlite:" +
                           path + ")");
  }
  {
    Lease db(impl_->pool);  // opens now: a bad URI or an unreachable server fails here, not on the first request
    impl_->description = (*db).describe();
    (*db).query("SELECT COUNT(*) FROM runs");
    db.done();
  }
  impl_->routes();
  errno = 0;
  if (o.port == 0) {
    impl_->port = impl_->http.bind_to_any_port(o.host);
  } else {
    impl_->port = impl_->http.bind_to_port(o.host, o.port) ? o.port : -1;
  }
  if (impl_->port < 0)
    throw std::runtime_error("cannot listen on " + o.host + ":" + std::to_string(o.port) +
                             (errno ? std::string(": ") + std::strerror(errno) : std::string()));
  return impl_->port;
}

int DashboardServer::port() const { return impl_->port; }
std::string DashboardServer::db_description() const { return impl_->description; }

void DashboardServer::run(const std::function<bool()>& should_stop) {
  std::atomic<bool> listening_done{false};
  std::thread listener([&] {
    impl_->http.listen_after_bind();
    listening_done = true;
  });
  {
    std::unique_lock<std::mutex> lock(impl_->mutex);
    while (!impl_->stopping) {
      impl_->wake.wait_for(lock, std::chrono::milliseconds(100));
      if (should_stop && should_stop()) impl_->stopping = true;
    }
  }
  impl_->wake.notify_all();  // event streams end at their next wait
  // httplib's stop() does nothing before listening has started, and must not
  // be called twice: wait until it is listening (or failed to), stop once.
  while (!listening_done) {
    if (impl_->http.is_running()) {
      impl_->http.stop();
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  listener.join();  // after httplib has joined its worker threads
}

void DashboardServer::stop() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->wake.notify_all();
}

}  // namespace rvc::dashboard
