/* rvc_zenoh.h: the C ABI of rust/rvc-zenoh (static library librvc_zenoh.a).
 *
 * A deliberately narrow surface over the Zenoh Rust crate: sessions,
 * callback subscribers, reliable blocking publishers, matching, config.
 * C++ code should use the RAII wrappers in zenoh_session.hpp instead.
 *
 * Conventions
 *  - Handles are opaque. Each *_close / *_undeclare frees its handle (NULL is
 *    a no-op). Undeclare subscribers and publishers before closing their
 *    session.
 *  - int results: RVC_ZENOH_OK (0) or a negative RVC_ZENOH_E* code; on error
 *    rvc_zenoh_last_error() describes it (thread-local, valid until the next
 *    failing call on the same thread).
 *  - Strings are NUL-terminated UTF-8. Strings returned as char* are freed
 *    with rvc_zenoh_string_free.
 *  - No Rust panic crosses this boundary (reported as RVC_ZENOH_EPANIC).
 *    Conversely, callbacks must not throw or longjmp.
 */
#ifndef RVC_ZENOH_H
#define RVC_ZENOH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define RVC_ZENOH_OK 0
#define RVC_ZENOH_EINVAL (-1) /* NULL handle, bad string, key expression or option */
#define RVC_ZENOH_EZENOH (-2) /* Zenoh refused: config, open, declare, put */
#define RVC_ZENOH_EPANIC (-3) /* internal panic caught at the boundary */

typedef struct rvc_zenoh_config rvc_zenoh_config;
typedef struct rvc_zenoh_session rvc_zenoh_session;
typedef struct rvc_zenoh_subscriber rvc_zenoh_subscriber;
typedef struct rvc_zenoh_publisher rvc_zenoh_publisher;
typedef struct rvc_zenoh_token rvc_zenoh_token;

const char* rvc_zenoh_last_error(void);

/* 1 if some key matches both key expressions, 0 if none, < 0 for a bad one. */
int rvc_zenoh_keyexpr_intersects(const char* a, const char* b);
void rvc_zenoh_string_free(char* s);

/* Zenoh's log output to stderr. RUST_LOG wins over `fallback_filter`
 * (NULL = "error"). Idempotent. */
int rvc_zenoh_init_logging(const char* fallback_filter);

/* ---- configuration ---------------------------------------------------- */

/* rvc's default config (no base file): mode peer; peers listen on
 * tcp/127.0.0.1:0, routers on tcp/127.0.0.1:7447, clients do not listen;
 * multicast scouting off; blocked publications wait up to 60 s before the
 * link is declared dead. Nothing leaves loopback unless asked to. */
typedef struct rvc_zenoh_config_opts {
  const char* base_file;           /* JSON5 Zenoh config file; NULL/"" = rvc default */
  const char* mode;                /* "peer" | "client" | "router"; NULL/"" = keep base */
  const char* const* connect;      /* endpoints, e.g. "tcp/127.0.0.1:7447" */
  size_t n_connect;                /* 0 = keep base */
  const char* const* listen;
  size_t n_listen;                 /* 0 = keep base */
  int multicast_scouting;          /* 0 = off, 1 = on (restricted to interface lo), -1 = keep base (rvc's default base: on, lo) */
} rvc_zenoh_config_opts;

int rvc_zenoh_config_build(const rvc_zenoh_config_opts* opts, rvc_zenoh_config** out);
/* json5 NULL = rvc default. */
int rvc_zenoh_config_from_json5(const char* json5, rvc_zenoh_config** out);
/* key is Zenoh's '/'-separated path, e.g. "scouting/multicast/enabled". */
int rvc_zenoh_config_insert_json5(rvc_zenoh_config* cfg, const char* key, const char* json5_value);
/* JSON of `key` ("" or NULL = whole config); NULL on error. Free the result. */
char* rvc_zenoh_config_get_json(const rvc_zenoh_config* cfg, const char* key);
void rvc_zenoh_config_free(rvc_zenoh_config* cfg);

/* ---- session ---------------------------------------------------------- */

/* json5 NULL = rvc default. */
int rvc_zenoh_session_open(const char* json5, rvc_zenoh_session** out);
/* cfg is not consumed; NULL = rvc default. */
int rvc_zenoh_session_open_config(const rvc_zenoh_config* cfg, rvc_zenoh_session** out);
/* Writes the session id (hex) into buf, truncated to len-1 chars. */
int rvc_zenoh_session_zid(const rvc_zenoh_session* s, char* buf, size_t len);
/* Closes (flushing queued publications) and frees. */
int rvc_zenoh_session_close(rvc_zenoh_session* s);

/* ---- subscriber ------------------------------------------------------- */

/* Called on a Zenoh thread for each put sample (deletes are ignored).
 * payload/attachment/key are borrowed for the call only; attachment is NULL
 * with att_len 0 when the sample has none; key is the sample's own key
 * expression (not NUL-terminated). Zero-copy unless the payload arrived
 * fragmented. Must return quickly and must not throw. */
typedef void (*rvc_zenoh_sample_cb)(const uint8_t* payload, size_t len,
                                    const uint8_t* attachment, size_t att_len,
                                    const uint8_t* key, size_t key_len, void* ctx);

/* announce != 0 also declares the liveliness token
 * "rvc/subscribers/<unique id>/<keyexpr>" so publishers can count rvc
 * subscribers (see rvc_zenoh_publisher_wait_matched). */
int rvc_zenoh_subscriber_declare(const rvc_zenoh_session* s, const char* keyexpr,
                                 rvc_zenoh_sample_cb cb, void* ctx, int announce,
                                 rvc_zenoh_subscriber** out);
/* After return no callback is running or will run. Not from inside cb. */
int rvc_zenoh_subscriber_undeclare(rvc_zenoh_subscriber* sub);

/* ---- publisher -------------------------------------------------------- */

/* Reliable, CongestionControl::Block (put blocks instead of dropping);
 * express != 0 sends each sample immediately instead of batching. */
int rvc_zenoh_publisher_declare(const rvc_zenoh_session* s, const char* keyexpr, int express,
                                rvc_zenoh_publisher** out);
/* attachment NULL = no attachment. May block under congestion. */
int rvc_zenoh_publisher_put(const rvc_zenoh_publisher* p, const uint8_t* payload, size_t len,
                            const uint8_t* attachment, size_t att_len);
/* *matching: 1 if any subscriber matches (Zenoh matching status, boolean).
 * *announced: number of rvc subscribers announced on a matching key.
 * Either out pointer may be NULL. */
int rvc_zenoh_publisher_matching(const rvc_zenoh_publisher* p, int* matching, size_t* announced);
/* 1 once n subscribers match, 0 on timeout, <0 on error. n <= 1 uses the
 * matching status (works with any subscriber); n > 1 also needs n announced
 * rvc subscribers. */
int rvc_zenoh_publisher_wait_matched(const rvc_zenoh_publisher* p, size_t n, uint64_t timeout_ms);
/* Flush barrier: waits until every rvc subscriber reachable now has taken
 * every sample put before the call (a query that travels behind the data,
 * answered by the subscribers' receive path). *confirmed (may be NULL) gets
 * the number that answered. 1 when complete, 0 on timeout, <0 on error. */
int rvc_zenoh_publisher_flush(const rvc_zenoh_publisher* p, uint64_t timeout_ms, size_t* confirmed);
int rvc_zenoh_publisher_undeclare(rvc_zenoh_publisher* p);

/* ---- liveliness token ------------------------------------------------- */

/* Declares a liveliness token on keyexpr (rvc monitor: "rvc/monitors/<name>").
 * Liveliness subscribers see it until it is undeclared or the session ends
 * (a killed process: when its peers' lease on it expires). */
int rvc_zenoh_token_declare(const rvc_zenoh_session* s, const char* keyexpr, rvc_zenoh_token** out);
int rvc_zenoh_token_undeclare(rvc_zenoh_token* t);


/* ---- liveliness query ------------------------------------------------- */

/* Called once per live token, on the calling thread; key borrowed for the call. */
typedef void (*rvc_zenoh_key_cb)(const uint8_t* key, size_t key_len, void* ctx);
/* The liveliness tokens alive now whose key matches keyexpr (e.g. rmw_zenoh's
 * graph of domain 0, "@ros2_lv/0/" and any key below it). Blocks until every peer answered or timeout_ms ran
 * out. Returns the number of tokens (>= 0) or a negative error code. */
int rvc_zenoh_liveliness_get(const rvc_zenoh_session* s, const char* keyexpr, uint64_t timeout_ms,
                             rvc_zenoh_key_cb cb, void* ctx);

/* ---- liveliness subscriber -------------------------------------------- */

/* alive: 1 the token appeared (or was alive at declaration, with history),
 * 0 it went (undeclared, or its session's lease expired). Zenoh thread; key
 * borrowed for the call; must return quickly and not throw. */
typedef void (*rvc_zenoh_liveliness_cb)(const uint8_t* key, size_t key_len, int alive, void* ctx);
typedef struct rvc_zenoh_liveliness_subscriber rvc_zenoh_liveliness_subscriber;
/* The tokens matching keyexpr as they come and go (rvc monitor --group: the
 * members "@rvc/group/<NAME>/<replica>"); history != 0 also reports those
 * alive now. */
int rvc_zenoh_liveliness_subscribe(const rvc_zenoh_session* s, const char* keyexpr, int history,
                                   rvc_zenoh_liveliness_cb cb, void* ctx, rvc_zenoh_liveliness_subscriber** out);
/* After return no callback is running or will run. Not from inside cb. */
int rvc_zenoh_liveliness_unsubscribe(rvc_zenoh_liveliness_subscriber* sub);

#ifdef __cplusplus
}
#endif

#endif /* RVC_ZENOH_H */
