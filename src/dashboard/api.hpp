// The dashboard's JSON API (docs/dashboard.md): pure functions from a results
// database and a request (path, query parameters) to a status and a JSON body,
// so they run without HTTP (the server only moves bytes). Every stored value
// comes back as JSON of its kind: numbers as numbers, NULL as null, and the
// JSON kept in text columns (inputs, counters, witnesses) embedded as JSON
// once it has been validated, so a damaged row cannot break a response.
//
//   /api/health                          {"ok":true,"db":"sqlite:results.db","runs":3}
//   /api/runs                            newest first, with counts of violations
//   /api/runs/<run>                      the run, and its properties with their current value
//   /api/runs/<run>/verdicts?after=&property=&limit=
//   /api/runs/<run>/violations?after=&property=&limit=   witness parsed
//   /api/runs/<run>/counters?after=&limit=               rates between snapshots
//
// Errors: {"error":"...","status":404}. Unknown run or property -> 404; a
// bad or unknown query parameter -> 400.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>

#include "store/database.hpp"

namespace rvc::dashboard {

struct Response {
  int status = 200;
  std::string body;  // JSON
};

// Decoded query parameters (the same type as httplib::Params).
using Params = std::multimap<std::string, std::string>;

Response error_response(int status, std::string_view message);

// A run with no end recorded whose last counters snapshot (or, before the
// first, its start) is older than this many seconds is reported "silent":
// its monitor has died or hangs (a live monitor records its counters every
// second). `rvc dashboard --silent-after`; default 10 s.
void set_silent_after(double seconds);

// GET `path` (without its query string) under /api/, except /api/events.
// Throws store::DbError when the database fails (the server answers 503).
Response handle_api(store::Database& db, const std::string& path, const Params& params);

// Server-sent events (/api/events?run=RUN&verdict=ID&violation=ID&counters=ID):
// where a stream is in each table. The ids are the last rows sent; a stream
// that names none starts at the newest rows (it sends what comes after it
// connected). The page passes the ids it has already loaded, so no row falls
// between its first fetch and the stream.
struct EventCursor {
  std::string run;  // "" = only `run` events (runs started or ended)
  int64_t verdict = 0, violation = 0, counters = 0;
  std::string runs_signature;  // what /api/runs looked like at the last poll
  std::string id() const;      // the SSE event id: "verdict,violation,counters"
};

// Checks the parameters and sets `cursor`. `last_event_id`: the header a
// reconnecting EventSource sends; when valid it wins over the parameters, so
// a reconnection resumes where the stream stopped. Returns an error response
// (400/404) or nothing.
bool start_events(store::Database& db, const Params& params, const std::string& last_event_id,
                  EventCursor& cursor, Response& error);

// One poll: "event: verdict|violation|counters|run" blocks, each with the new
// rows as a JSON array in `data:` (rows as the endpoints above return them;
// `run`: the whole runs list, sent when a run starts or ends) and the cursor
// as `id:`; "" when nothing is new. Advances `cursor`. Throws store::DbError
// (the server then sends one `event: db-error`, and `db-ok` once polls work
// again; not `error`, which EventSource keeps for its own connection errors).
std::string poll_events(store::Database& db, EventCursor& cursor);

}  // namespace rvc::dashboard
