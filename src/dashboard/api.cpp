#include "dashboard/api.hpp"

#include <simdjson.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <initializer_list>
#include <map>

#include "io/json_writer.hpp"

namespace rvc::dashboard {
namespace {

using store::Database;
using store::QueryResult;
using Row = std::vector<std::string>;

// How many rows one request returns at most (the client pages on with
// after=last_id while "more" is true), so one request never has to hold a
// whole long run in memory.
constexpr int64_t kRunsDefault = 500, kRunsMax = 10000;
constexpr int64_t kVerdictsDefault = 10000, kVerdictsMax = 100000;
constexpr int64_t kViolationsDefault = 1000, kViolationsMax = 10000;  // witnesses are larger rows
constexpr int64_t kCountersDefault = 100, kCountersMax = 10000;

// --- stored text -> JSON ----------------------------------------------------

// Every value arrives as text ("" for NULL). Numbers are re-printed by the
// project's writer, so they come out in one form whatever the database.
bool parse_number(const std::string& text, double& v) {
  char* end = nullptr;
  v = std::strtod(text.c_str(), &end);
  return !text.empty() && end != text.c_str();
}

std::string json_number(const std::string& text) {
  double v;
  if (!parse_number(text, v)) return "null";
  std::string out;
  io::append_number(out, v);
  return out;
}

// Wall-clock seconds: fixed, to the microsecond (the shortest form of
// 1795458121.04142 would be scientific).
std::string json_wall(const std::string& text) {
  double v;
  if (!parse_number(text, v)) return "null";
  std::string out;
  io::append_fixed(out, v, 6);
  return out;
}

std::string json_text_or_null(const std::string& text) {
  if (text.empty()) return "null";
  std::string out;
  io::append_json_string(out, text);
  return out;
}

std::string json_bool_or_null(const std::string& text) {
  if (text == "1" || text == "t" || text == "true") return "true";  // SQLite 1, PostgreSQL t
  if (text == "0" || text == "f" || text == "false") return "false";
  return "null";
}

// JSON kept in a text column, validated and minified by simdjson: a row that
// is not JSON comes back as a string, never as broken output.
std::string embedded_json(const std::string& text) {
  if (text.empty()) return "null";
  thread_local simdjson::dom::parser parser;
  simdjson::dom::element element;
  if (parser.parse(text.data(), text.size()).get(element) == simdjson::SUCCESS) return simdjson::minify(element);
  return json_text_or_null(text);
}

// --- query parameters -------------------------------------------------------

struct BadRequest {
  std::string message;
};

// Only `allowed` names, each at most once: a typo (?afer=3) is an error, not
// a silently ignored filter.
void check_params(const Params& params, std::initializer_list<std::string_view> allowed) {
  for (auto it = params.begin(); it != params.end(); it = params.upper_bound(it->first)) {
    bool known = false;
    for (auto name : allowed) known = known || it->first == name;
    if (!known) throw BadRequest{"unknown parameter '" + it->first + "'"};
    if (params.count(it->first) > 1) throw BadRequest{"parameter '" + it->first + "' given twice"};
  }
}

const std::string* param(const Params& params, const std::string& name) {
  auto it = params.find(name);
  return it == params.end() ? nullptr : &it->second;
}

// An integer of plain digits from `min` to `max` (an id, a limit); the one
// message for anything else names that range.
int64_t integer_param(const Params& params, const std::string& name, int64_t fallback, int64_t max,
                      int64_t min = 0) {
  const std::string* text = param(params, name);
  if (!text) return fallback;
  int64_t v = -1;
  const char* end = text->data() + text->size();
  auto [ptr, ec] = std::from_chars(text->data(), end, v);
  if (text->empty() || (*text)[0] == '-' || ec != std::errc() || ptr != end || v > max || v < min)
    throw BadRequest{name + " must be an integer from " + std::to_string(min) + " to " + std::to_string(max) +
                     ", not '" + *text + "'"};
  return v;
}

int64_t limit_param(const Params& params, int64_t fallback, int64_t max) {
  return integer_param(params, "limit", fallback, max, 1);
}

constexpr int64_t kMaxId = INT64_MAX / 2;

// --- runs -------------------------------------------------------------------

std::atomic<double> g_silent_after{10};

// No end recorded and nothing recorded for longer than --silent-after.
bool silent(const Row& r) {
  if (!r[5].empty()) return false;
  const std::string& last = r[11].empty() ? r[4] : r[11];
  double at = 0;
  if (last.empty() || !parse_number(last, at)) return false;
  const double now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  return now - at > g_silent_after.load();
}

bool run_exists(Database& db, const std::string& run) {
  return !db.query("SELECT 1 FROM runs WHERE run = ?", {run}).empty();
}

// One run's columns; the counts and the last snapshot's time come from
// correlated subqueries, each an index range (the *_by_run indexes).
const char* const kRunSelect =
    "SELECT r.run, r.command, r.inputs, r.time_model, r.started_at, r.ended_at, r.exit_status, r.end_reason, "
    "r.counters, (SELECT COUNT(*) FROM violations v WHERE v.run = r.run), "
    "(SELECT COUNT(*) FROM properties p WHERE p.run = r.run), "
    "(SELECT c.wall FROM counters c WHERE c.run = r.run ORDER BY c.id DESC LIMIT 1) FROM runs r";

io::JsonObject run_object(const Row& r) {
  io::JsonObject o;
  o.add("run", r[0])
      .add("command", r[1])
      .add_raw("inputs", embedded_json(r[2]))
      .add("time_model", r[3])
      .add_raw("started_at", json_wall(r[4]))
      .add_raw("ended_at", json_wall(r[5]))
      .add_raw("exit_status", json_number(r[6]))
      .add_raw("end_reason", json_text_or_null(r[7]))
      .add_raw("final_counters", embedded_json(r[8]))
      .add_raw("violations", json_number(r[9]))
      .add_raw("property_count", json_number(r[10]))
      .add_raw("last_counters_at", json_wall(r[11]))
      // No end recorded yet: the monitor is running (or died without one;
      // the page shows how long it has been silent from last_counters_at).
      .add("live", r[5].empty())
      .add("silent", silent(r));
  return o;
}

// Newest first; runs without a start time last (NULLs sort differently in
// SQLite and PostgreSQL, hence the CASE).
std::string runs_array(Database& db, int64_t limit, bool& more) {
  QueryResult rows = db.query(std::string(kRunSelect) +
                              " ORDER BY CASE WHEN r.started_at IS NULL THEN 1 ELSE 0 END, r.started_at DESC, "
                              "r.run DESC LIMIT " + std::to_string(limit + 1));
  more = static_cast<int64_t>(rows.size()) > limit;
  if (more) rows.pop_back();
  io::JsonArray out;
  for (const Row& r : rows) out.add(run_object(r));
  return out.str();
}

Response ok(std::string body) { return Response{200, std::move(body)}; }

Response runs(Database& db, const Params& params) {
  check_params(params, {"limit"});
  bool more = false;
  const std::string list = runs_array(db, limit_param(params, kRunsDefault, kRunsMax), more);
  return ok(io::JsonObject().add_raw("runs", list).add("more", more).str());
}

Response run_detail(Database& db, const std::string& run, const Params& params) {
  check_params(params, {});
  QueryResult r = db.query(std::string(kRunSelect) + " WHERE r.run = ?", {run});
  if (r.empty()) return error_response(404, "no run '" + run + "'");

  // Per property: spec, current value (its latest verdict change), counts.
  struct Property {
    std::string spec, value, since;
    std::string changes = "0", violations = "0";
  };
  std::map<std::string, Property> props;  // by name: a stable order in both databases
  for (const Row& p : db.query("SELECT name, spec FROM properties WHERE run = ?", {run})) props[p[0]].spec = p[1];
  for (const Row& v : db.query("SELECT property, value, time FROM verdicts WHERE id IN "
                               "(SELECT MAX(id) FROM verdicts WHERE run = ? GROUP BY property)",
                               {run})) {
    props[v[0]].value = v[1];
    props[v[0]].since = v[2];
  }
  for (const Row& c : db.query("SELECT property, COUNT(*) FROM verdicts WHERE run = ? GROUP BY property", {run}))
    props[c[0]].changes = c[1];
  for (const Row& c : db.query("SELECT property, COUNT(*) FROM violations WHERE run = ? GROUP BY property", {run}))
    props[c[0]].violations = c[1];

  io::JsonArray list;
  for (const auto& [name, p] : props) {
    list.add(io::JsonObject()
                 .add("name", name)
                 .add_raw("spec", json_text_or_null(p.spec))
                 .add_raw("value", json_bool_or_null(p.value))  // null: no verdict yet
                 .add_raw("since", json_number(p.since))        // stream time of that verdict
                 .add_raw("changes", json_number(p.changes))
                 .add_raw("violations", json_number(p.violations)));
  }
  return ok(io::JsonObject().add("run", run_object(r[0])).add_raw("properties", list.str()).str());
}

// --- rows that follow a table by id -----------------------------------------

// known_at (bounded future, issue 29): the instant a verdict became known;
// null in a database of an older rvc, where every verdict is known at its time.
io::JsonObject verdict_object(const Row& v) {  // id, property, time, value, wall, known_at
  return io::JsonObject()
      .add_raw("id", json_number(v[0]))
      .add("property", v[1])
      .add_raw("time", json_number(v[2]))
      .add_raw("value", json_bool_or_null(v[3]))
      .add_raw("wall", json_wall(v[4]))
      .add_raw("known_at", json_number(v[5]));
}

io::JsonObject violation_object(const Row& v) {  // id, property, time, wall, witness, explanation
  return io::JsonObject()
      .add_raw("id", json_number(v[0]))
      .add("property", v[1])
      .add_raw("time", json_number(v[2]))
      .add_raw("wall", json_wall(v[3]))
      .add_raw("witness", embedded_json(v[4]))
      .add_raw("explanation", embedded_json(v[5]))  // null without --explain
      .add_raw("known_at", json_number(v[6]));
}

// Rows of `table` after id `after` (in id order), at most `limit`.
QueryResult rows_after(Database& db, const char* columns, const char* table, const std::string& run, int64_t after,
                       const std::string* property, int64_t limit) {
  std::string sql = std::string("SELECT ") + columns + " FROM " + table +
                    " WHERE run = ? AND id > CAST(? AS BIGINT)";
  std::vector<std::string> args{run, std::to_string(after)};
  if (property) {
    sql += " AND property = ?";
    args.push_back(*property);
  }
  sql += " ORDER BY id LIMIT " + std::to_string(limit);
  return db.query(sql, args);
}

const char* const kVerdictColumns = "id, property, time, value, wall, known_at";
const char* const kViolationColumns = "id, property, time, wall, witness, explanation, known_at";

// Whether `table` has `column` (a database written by an older rvc may not;
// the dashboard reads databases as they are and never migrates one). A lost
// connection is not an answer: it is thrown.
bool has_column(Database& db, const char* table, const char* column) {
  try {
    db.query(std::string("SELECT ") + column + " FROM " + table + " LIMIT 0");
    return true;
  } catch (const store::DbError& e) {
    if (e.connection_lost()) throw;
    return false;
  }
}

// Violations: explanations came later, then known_at (bounded future); a
// missing column reads as null.
const char* violation_columns(Database& db) {
  if (!has_column(db, "violations", "explanation"))
    return "id, property, time, wall, witness, NULL AS explanation, NULL AS known_at";
  if (!has_column(db, "violations", "known_at"))
    return "id, property, time, wall, witness, explanation, NULL AS known_at";
  return kViolationColumns;
}

// The same for verdicts: known_at came later.
const char* verdict_columns(Database& db) {
  return has_column(db, "verdicts", "known_at") ? kVerdictColumns : "id, property, time, value, wall, NULL AS known_at";
}
const char* const kCounterColumns = "id, wall, counters";

// A page of rows: {"run":..,"after":..,"<key>":[..],"last_id":..,"more":..}.
// last_id is what the next request passes as after.
std::string page_body(const std::string& run, int64_t after, const char* key, const std::string& array,
                      int64_t last_id, bool more) {
  return io::JsonObject()
      .add("run", run)
      .add("after", after)
      .add_raw(key, array)
      .add("last_id", last_id)
      .add("more", more)
      .str();
}

bool property_known(Database& db, const std::string& run, const std::string& property) {
  return !db.query("SELECT 1 FROM properties WHERE run = ? AND name = ?", {run, property}).empty() ||
         !db.query("SELECT 1 FROM verdicts WHERE run = ? AND property = ? LIMIT 1", {run, property}).empty();
}

template <typename ToObject>
Response follow(Database& db, const std::string& run, const Params& params, const char* columns, const char* table,
                const char* key, int64_t fallback, int64_t max, ToObject to_object) {
  check_params(params, {"after", "property", "limit"});
  const int64_t after = integer_param(params, "after", 0, kMaxId);
  const int64_t limit = limit_param(params, fallback, max);
  const std::string* property = param(params, "property");
  if (property && property->empty()) throw BadRequest{"property must not be empty"};
  if (!run_exists(db, run)) return error_response(404, "no run '" + run + "'");
  if (property && !property_known(db, run, *property))
    return error_response(404, "run '" + run + "' has no property '" + *property + "'");
  QueryResult rows = rows_after(db, columns, table, run, after, property, limit + 1);
  const bool more = static_cast<int64_t>(rows.size()) > limit;
  if (more) rows.pop_back();
  io::JsonArray out;
  for (const Row& r : rows) out.add(to_object(r));
  const int64_t last = rows.empty() ? after : std::strtoll(rows.back()[0].c_str(), nullptr, 10);
  return ok(page_body(run, after, key, out.str(), last, more));
}

// --- counters and rates -----------------------------------------------------

// The fields of a snapshot the rates need; NaN where absent.
struct Snapshot {
  std::string input;
  double wall = NAN, received = NAN, checked = NAN;
};

Snapshot read_snapshot(const Row& row) {  // id, wall, counters
  Snapshot s;
  s.wall = row[1].empty() ? NAN : std::strtod(row[1].c_str(), nullptr);
  thread_local simdjson::dom::parser parser;
  simdjson::dom::object o;
  if (parser.parse(row[2].data(), row[2].size()).get(o) != simdjson::SUCCESS) return s;
  std::string_view input;
  if (o["input"].get(input) == simdjson::SUCCESS) s.input = std::string(input);
  double v;
  if (o["received"].get_double().get(v) == simdjson::SUCCESS) s.received = v;
  if (o["checked"].get_double().get(v) == simdjson::SUCCESS) s.checked = v;
  return s;
}

// Snapshots in id order, each with messages/s since the previous snapshot of
// the same input (a run with several inputs interleaves their snapshots). The
// previous snapshot of the first row is looked up before it.
std::string counters_array(Database& db, const std::string& run, const QueryResult& rows) {
  std::map<std::string, Snapshot> previous;
  if (!rows.empty()) {
    // The 64 snapshots before: one per input for any run with up to 64 inputs.
    const std::string sql = std::string("SELECT ") + kCounterColumns +
                            " FROM counters WHERE run = ? AND id < CAST(? AS BIGINT) ORDER BY id DESC LIMIT 64";
    QueryResult older = db.query(sql, {run, rows.front()[0]});
    for (auto it = older.rbegin(); it != older.rend(); ++it) {
      Snapshot s = read_snapshot(*it);
      previous[s.input] = s;
    }
  }
  io::JsonArray out;
  for (const Row& r : rows) {
    const Snapshot s = read_snapshot(r);
    io::JsonObject o;
    o.add_raw("id", json_number(r[0])).add_raw("wall", json_wall(r[1])).add_raw("counters", embedded_json(r[2]));
    auto prev = previous.find(s.input);
    const double dt = prev == previous.end() ? NAN : s.wall - prev->second.wall;
    if (dt > 0) {  // NaN compares false: no rate without an earlier snapshot
      o.add("rates", io::JsonObject()
                         .add_fixed("seconds", dt, 3)
                         .add_fixed("received_per_s", (s.received - prev->second.received) / dt, 3)
                         .add_fixed("checked_per_s", (s.checked - prev->second.checked) / dt, 3));
    } else {
      o.add_raw("rates", "null");
    }
    previous[s.input] = s;
    out.add(o);
  }
  return out.str();
}

// Without after: the latest `limit` snapshots (what a page shows first);
// with after: the snapshots after it, in order.
Response counters(Database& db, const std::string& run, const Params& params) {
  check_params(params, {"after", "limit"});
  const bool follow_on = param(params, "after") != nullptr;
  const int64_t after = integer_param(params, "after", 0, kMaxId);
  const int64_t limit = limit_param(params, kCountersDefault, kCountersMax);
  if (!run_exists(db, run)) return error_response(404, "no run '" + run + "'");
  QueryResult rows;
  bool more = false;
  if (follow_on) {
    rows = rows_after(db, kCounterColumns, "counters", run, after, nullptr, limit + 1);
    more = static_cast<int64_t>(rows.size()) > limit;
    if (more) rows.pop_back();
  } else {
    rows = db.query(std::string("SELECT ") + kCounterColumns + " FROM counters WHERE run = ? ORDER BY id DESC LIMIT " +
                        std::to_string(limit),
                    {run});
    std::reverse(rows.begin(), rows.end());
  }
  const int64_t last = rows.empty() ? after : std::strtoll(rows.back()[0].c_str(), nullptr, 10);
  return ok(page_body(run, after, "counters", counters_array(db, run, rows), last, more));
}

Response health(Database& db, const Params& params) {
  check_params(params, {});
  QueryResult n = db.query("SELECT COUNT(*) FROM runs");
  return ok(io::JsonObject()
                .add("ok", true)
                .add("db", db.describe())
                .add_raw("runs", json_number(n.empty() ? "" : n[0][0]))
                .str());
}

bool ends_with(const std::string& s, std::string_view suffix) {
  return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// --- events -----------------------------------------------------------------

int64_t max_id(Database& db, const char* table, const std::string& run) {
  QueryResult r = db.query(std::string("SELECT COALESCE(MAX(id), 0) FROM ") + table + " WHERE run = ?", {run});
  return r.empty() ? 0 : std::strtoll(r[0][0].c_str(), nullptr, 10);
}

// Changes when a run starts, ends or goes silent (or records again): then
// the stream sends the runs again. Only runs with no end can be silent.
std::string runs_signature(Database& db) {
  QueryResult r = db.query("SELECT COUNT(*), MAX(started_at), COUNT(ended_at), MAX(ended_at) FROM runs");
  std::string sig;
  for (const auto& v : r.at(0)) sig += v + ",";
  for (const Row& live : db.query(std::string(kRunSelect) + " WHERE r.ended_at IS NULL"))
    if (silent(live)) sig += "silent:" + live[0] + ",";
  return sig;
}

// "12,3,40" -> cursor ids; false if it is not three ids.
bool parse_event_id(const std::string& text, EventCursor& cursor) {
  int64_t ids[3];
  const char* p = text.data();
  const char* end = p + text.size();
  for (int i = 0; i < 3; ++i) {
    auto [next, ec] = std::from_chars(p, end, ids[i]);
    if (ec != std::errc() || ids[i] < 0 || (i < 2 && (next == end || *next != ',')) || (i == 2 && next != end))
      return false;
    p = next + 1;
  }
  cursor.verdict = ids[0];
  cursor.violation = ids[1];
  cursor.counters = ids[2];
  return true;
}

}  // namespace

void set_silent_after(double seconds) { g_silent_after = seconds; }

Response error_response(int status, std::string_view message) {
  return Response{status, io::JsonObject().add("error", message).add("status", status).str()};
}

Response handle_api(Database& db, const std::string& path, const Params& params) {
  try {
    if (path == "/api/health") return health(db, params);
    if (path == "/api/runs" || path == "/api/runs/") return runs(db, params);
    const std::string prefix = "/api/runs/";
    if (path.rfind(prefix, 0) == 0) {
      // The run is everything between the prefix and a known suffix, so a
      // run id may itself hold slashes.
      const std::string rest = path.substr(prefix.size());
      if (ends_with(rest, "/verdicts"))
        return follow(db, rest.substr(0, rest.size() - 9), params, verdict_columns(db), "verdicts", "verdicts",
                      kVerdictsDefault, kVerdictsMax, verdict_object);
      if (ends_with(rest, "/violations"))
        return follow(db, rest.substr(0, rest.size() - 11), params, violation_columns(db), "violations", "violations",
                      kViolationsDefault, kViolationsMax, violation_object);
      if (ends_with(rest, "/counters")) return counters(db, rest.substr(0, rest.size() - 9), params);
      return run_detail(db, rest, params);
    }
    return error_response(404, "no API endpoint " + path);
  } catch (const BadRequest& e) {
    return error_response(400, e.message);
  }
}

std::string EventCursor::id() const {
  return std::to_string(verdict) + "," + std::to_string(violation) + "," + std::to_string(counters);
}

bool start_events(Database& db, const Params& params, const std::string& last_event_id, EventCursor& cursor,
                  Response& error) {
  try {
    check_params(params, {"run", "verdict", "violation", "counters"});
    cursor = EventCursor{};
    if (const std::string* run = param(params, "run")) {
      if (run->empty()) throw BadRequest{"run must not be empty"};
      if (!run_exists(db, *run)) {
        error = error_response(404, "no run '" + *run + "'");
        return false;
      }
      cursor.run = *run;
      // An id not given: start after the newest row (what comes from now on).
      auto start = [&](const char* name, const char* table) {
        return param(params, name) ? integer_param(params, name, 0, kMaxId) : max_id(db, table, *run);
      };
      cursor.verdict = start("verdict", "verdicts");
      cursor.violation = start("violation", "violations");
      cursor.counters = start("counters", "counters");
      if (!last_event_id.empty()) parse_event_id(last_event_id, cursor);  // a reconnection resumes
    }
    cursor.runs_signature = runs_signature(db);
    return true;
  } catch (const BadRequest& e) {
    error = error_response(400, e.message);
    return false;
  }
}

std::string poll_events(Database& db, EventCursor& cursor) {
  std::string out;
  auto emit = [&](const char* event, const std::string& data) {
    out += "event: ";
    out += event;
    out += "\ndata: ";
    out += data;  // one line: the writer escapes every control character
    out += "\nid: ";
    out += cursor.id();
    out += "\n\n";
  };
  // Bounded per poll; the rest comes with the next poll.
  auto follow_table = [&](const char* event, const char* columns, const char* table, int64_t& last, int64_t limit,
                          auto to_array) {
    QueryResult rows = rows_after(db, columns, table, cursor.run, last, nullptr, limit);
    if (rows.empty()) return;
    last = std::strtoll(rows.back()[0].c_str(), nullptr, 10);
    emit(event, to_array(rows));
  };
  if (!cursor.run.empty()) {
    follow_table("verdict", verdict_columns(db), "verdicts", cursor.verdict, 2000, [](const QueryResult& rows) {
      io::JsonArray a;
      for (const Row& r : rows) a.add(verdict_object(r));
      return a.str();
    });
    follow_table("violation", violation_columns(db), "violations", cursor.violation, 200, [](const QueryResult& rows) {
      io::JsonArray a;
      for (const Row& r : rows) a.add(violation_object(r));
      return a.str();
    });
    follow_table("counters", kCounterColumns, "counters", cursor.counters, 200,
                 [&](const QueryResult& rows) { return counters_array(db, cursor.run, rows); });
  }
  std::string sig = runs_signature(db);
  if (sig != cursor.runs_signature) {
    cursor.runs_signature = sig;
    bool more = false;
    emit("run", runs_array(db, kRunsDefault, more));
  }
  return out;
}

}  // namespace rvc::dashboard
