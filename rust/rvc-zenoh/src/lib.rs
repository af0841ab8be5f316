//! rvc-zenoh: the narrow C ABI through which rvc's C++ transport talks to Zenoh
//! (and, in `mcap_reader`, reads MCAP bags with the `mcap` crate: one Rust
//! static library per binary, since two would each carry Rust's runtime).
//!
//! Why a Rust shim instead of zenoh-c: Zenoh has no Debian package and zenoh-c
//! is a large generated API. rvc needs five things (open a session, subscribe
//! with a callback, publish reliably, know when subscribers are there, run a
//! router), so this crate exposes exactly those and keeps Zenoh types out of C++.
//!
//! Conventions, mirrored in `src/transport/zenoh/rvc_zenoh.h`:
//! * handles are opaque boxed structs; `*_close`/`*_undeclare` free them;
//! * functions return `RVC_ZENOH_OK` (0) or a negative code, and leave a
//!   message for `rvc_zenoh_last_error()` on the calling thread;
//! * no panic ever unwinds into C: every entry point runs under `catch_unwind`;
//! * every entry point taking pointers is an `unsafe extern "C" fn`: the
//!   caller guarantees what the header documents (valid handles, strings,
//!   buffers); the crate checks what it can (NULL, UTF-8, key syntax).

#![allow(non_camel_case_types)]
// The safety contract of each function is written once, in rvc_zenoh.h.
#![allow(clippy::missing_safety_doc)]
#![deny(unsafe_op_in_unsafe_fn)]

use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::HashSet;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, RwLock};
use std::time::{Duration, Instant};

mod mcap_chunk;
mod mcap_reader;
mod mcap_records;

use zenoh::bytes::ZBytes;
use zenoh::key_expr::KeyExpr;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::{CongestionControl, Priority};
use zenoh::query::{ConsolidationMode, Query, QueryTarget, Queryable};
use zenoh::sample::{Sample, SampleKind};
use zenoh::{Config, Session, Wait};

pub const RVC_ZENOH_OK: c_int = 0;
/// NULL handle, non-UTF-8 string, malformed key expression or option.
pub const RVC_ZENOH_EINVAL: c_int = -1;
/// Zenoh refused: bad config, cannot open/connect, declaration or put failed.
pub const RVC_ZENOH_EZENOH: c_int = -2;
/// A Rust panic was caught at the boundary (a bug in this crate or in Zenoh).
pub const RVC_ZENOH_EPANIC: c_int = -3;

/// Liveliness prefix under which rvc subscribers announce themselves, so a
/// publisher can count them. Zenoh's matching status is only a boolean.
const ANNOUNCE_PREFIX: &str = "rvc/subscribers";

/// Prefix of the flush queryables of rvc subscribers. A publisher's flush is a
/// query on FLUSH_PREFIX/<its key>, sent with the data's priority and
/// congestion control, so it travels behind every sample put before it; each
/// subscriber answers from its receive path, i.e. after its callback has
/// taken every one of those samples. Closing a session does not guarantee
/// that: Zenoh cancels the link's writer mid-batch and drains the rest with a
/// timeout, so samples still queued for a slow subscriber can be lost.
const FLUSH_PREFIX: &str = "rvc/flush";

/// How long a `CongestionControl::Block` put may stay blocked before Zenoh
/// closes the link. Zenoh's default (5 s) turns a briefly stalled monitor into
/// lost messages; rvc prefers back-pressure, a dead peer is caught by the lease.
const BLOCK_WAIT_BEFORE_CLOSE_US: u64 = 60_000_000;

// ---------------------------------------------------------------------------
// Errors and the FFI guard
// ---------------------------------------------------------------------------

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

struct FfiError {
    code: c_int,
    msg: String,
}

type FfiResult<T> = Result<T, FfiError>;

fn einval(msg: impl Into<String>) -> FfiError {
    FfiError {
        code: RVC_ZENOH_EINVAL,
        msg: msg.into(),
    }
}

fn ezenoh(context: &str, err: impl std::fmt::Display) -> FfiError {
    FfiError {
        code: RVC_ZENOH_EZENOH,
        msg: format!("{context}: {err}"),
    }
}

fn set_last_error(msg: &str) {
    // Interior NULs would truncate the C string; replace rather than lose it.
    let c = CString::new(msg.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        format!("internal panic: {s}")
    } else if let Some(s) = payload.downcast_ref::<String>() {
        format!("internal panic: {s}")
    } else {
        "internal panic".to_string()
    }
}

/// Runs an entry point body: converts errors and panics into return codes.
fn guard(body: impl FnOnce() -> FfiResult<c_int>) -> c_int {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(rc)) => rc,
        Ok(Err(e)) => {
            set_last_error(&e.msg);
            e.code
        }
        Err(p) => {
            set_last_error(&panic_message(p));
            RVC_ZENOH_EPANIC
        }
    }
}

/// For entry points that cannot report (destructors): swallow panics.
fn guard_void(body: impl FnOnce()) {
    if let Err(p) = catch_unwind(AssertUnwindSafe(body)) {
        set_last_error(&panic_message(p));
    }
}

fn cstr<'a>(p: *const c_char, what: &str) -> FfiResult<&'a str> {
    if p.is_null() {
        return Err(einval(format!("{what} is NULL")));
    }
    // SAFETY: caller promises a NUL-terminated string alive for the call.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| einval(format!("{what} is not UTF-8")))
}

fn opt_cstr<'a>(p: *const c_char, what: &str) -> FfiResult<Option<&'a str>> {
    if p.is_null() {
        return Ok(None);
    }
    let s = cstr(p, what)?;
    Ok(if s.is_empty() { None } else { Some(s) })
}

fn cstr_array(p: *const *const c_char, n: usize, what: &str) -> FfiResult<Vec<String>> {
    if n == 0 {
        return Ok(Vec::new());
    }
    if p.is_null() {
        return Err(einval(format!("{what} is NULL with count {n}")));
    }
    // SAFETY: caller promises `n` valid string pointers.
    let ptrs = unsafe { std::slice::from_raw_parts(p, n) };
    ptrs.iter()
        .map(|&s| cstr(s, what).map(str::to_owned))
        .collect()
}

fn bytes<'a>(p: *const u8, len: usize, what: &str) -> FfiResult<&'a [u8]> {
    if len == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(einval(format!("{what} is NULL with length {len}")));
    }
    // SAFETY: caller promises `len` readable bytes at `p` for the call.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

fn handle<'a, T>(p: *const T, what: &str) -> FfiResult<&'a T> {
    // SAFETY: non-NULL handles come from this crate's constructors.
    unsafe { p.as_ref() }.ok_or_else(|| einval(format!("{what} handle is NULL")))
}

fn out_ptr<'a, T>(p: *mut T, what: &str) -> FfiResult<&'a mut T> {
    // SAFETY: caller passes writable storage for the result.
    unsafe { p.as_mut() }.ok_or_else(|| einval(format!("{what} is NULL")))
}

/// Returns the message of the last failed call on this thread ("" if none).
/// Valid until the next failing call on the same thread.
#[no_mangle]
pub extern "C" fn rvc_zenoh_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// Frees a string returned by this library.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_string_free(s: *mut c_char) {
    if !s.is_null() {
        // SAFETY: produced by CString::into_raw in this crate.
        guard_void(|| drop(unsafe { CString::from_raw(s) }));
    }
}

/// Routes Zenoh's tracing output to stderr; `RUST_LOG` wins over `fallback`.
/// Idempotent. Without it Zenoh is silent.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_init_logging(fallback: *const c_char) -> c_int {
    guard(|| {
        let filter = opt_cstr(fallback, "fallback filter")?
            .unwrap_or("error")
            .to_owned();
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| zenoh::init_log_from_env_or(filter));
        Ok(RVC_ZENOH_OK)
    })
}

// ---------------------------------------------------------------------------
// Configuration
// ---------------------------------------------------------------------------

pub struct rvc_zenoh_config {
    cfg: Config,
}

/// Mirrors the C struct `rvc_zenoh_config_opts`.
#[repr(C)]
pub struct rvc_zenoh_config_opts {
    pub base_file: *const c_char,
    pub mode: *const c_char,
    pub connect: *const *const c_char,
    pub n_connect: usize,
    pub listen: *const *const c_char,
    pub n_listen: usize,
    pub multicast_scouting: c_int,
}

fn insert(cfg: &mut Config, key: &str, json5: &str) -> FfiResult<()> {
    cfg.insert_json5(key, json5)
        .map_err(|e| ezenoh(&format!("config key '{key}'"), e))
}

fn json_string(s: &str) -> String {
    serde_json::Value::String(s.to_owned()).to_string()
}

fn json_list(items: &[String]) -> String {
    serde_json::Value::from(items.to_vec()).to_string()
}

fn check_mode(mode: &str) -> FfiResult<()> {
    match mode {
        "peer" | "client" | "router" => Ok(()),
        other => Err(einval(format!(
            "unknown Zenoh mode '{other}' (peer|client|router)"
        ))),
    }
}

/// rvc's embedded default. Zenoh's own default listens on every interface and
/// multicasts scouting on the LAN; rvc must never leave loopback unless told,
/// so peers/routers listen on 127.0.0.1 only and multicast scouting runs on
/// the loopback interface only: processes on one host find each other with
/// no flags, nothing goes out on another interface. Gossip scouting stays
/// on: it only runs over links that already exist.
fn rvc_default_config(mode: &str) -> FfiResult<Config> {
    check_mode(mode)?;
    let mut cfg = Config::default();
    insert(&mut cfg, "mode", &json_string(mode))?;
    let listen: &[&str] = match mode {
        "router" => &["tcp/127.0.0.1:7447"],
        "peer" => &["tcp/127.0.0.1:0"],
        _ => &[],
    };
    let listen: Vec<String> = listen.iter().map(|s| s.to_string()).collect();
    insert(&mut cfg, "listen/endpoints", &json_list(&listen))?;
    insert(&mut cfg, "scouting/multicast/enabled", "true")?;
    insert(&mut cfg, "scouting/multicast/interface", "\"lo\"")?;
    insert(
        &mut cfg,
        "transport/link/tx/queue/congestion_control/block/wait_before_close",
        &BLOCK_WAIT_BEFORE_CLOSE_US.to_string(),
    )?;
    Ok(cfg)
}

fn config_from_json5(json5: Option<&str>) -> FfiResult<Config> {
    match json5 {
        None => rvc_default_config("peer"),
        Some(text) => Config::from_json5(text).map_err(|e| ezenoh("parsing JSON5 config", e)),
    }
}

fn build_config(o: &rvc_zenoh_config_opts) -> FfiResult<Config> {
    let file = opt_cstr(o.base_file, "base_file")?;
    let mode = opt_cstr(o.mode, "mode")?;
    if let Some(m) = mode {
        check_mode(m)?;
    }
    let connect = cstr_array(o.connect, o.n_connect, "connect endpoint")?;
    let listen = cstr_array(o.listen, o.n_listen, "listen endpoint")?;

    let mut cfg = match file {
        Some(path) => Config::from_file(path)
            .map_err(|e| ezenoh(&format!("reading Zenoh config '{path}'"), e))?,
        None => rvc_default_config(mode.unwrap_or("peer"))?,
    };
    if let Some(m) = mode {
        insert(&mut cfg, "mode", &json_string(m))?;
    }
    if !connect.is_empty() {
        insert(&mut cfg, "connect/endpoints", &json_list(&connect))?;
    }
    if !listen.is_empty() {
        insert(&mut cfg, "listen/endpoints", &json_list(&listen))?;
    }
    match o.multicast_scouting {
        0 => insert(&mut cfg, "scouting/multicast/enabled", "false")?,
        // Opting in still keeps the scouting datagrams on the loopback device.
        1 => {
            insert(&mut cfg, "scouting/multicast/enabled", "true")?;
            insert(&mut cfg, "scouting/multicast/interface", "\"lo\"")?;
        }
        _ => {} // keep what the base says
    }
    Ok(cfg)
}

/// Builds a config: the JSON5 file `base_file` (or rvc's loopback-only default
/// when NULL/""), then the overrides in `opts`.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_config_build(
    opts: *const rvc_zenoh_config_opts,
    out: *mut *mut rvc_zenoh_config,
) -> c_int {
    guard(|| {
        let o = handle(opts, "opts")?;
        let out = out_ptr(out, "out")?;
        let cfg = build_config(o)?;
        *out = Box::into_raw(Box::new(rvc_zenoh_config { cfg }));
        Ok(RVC_ZENOH_OK)
    })
}

/// Parses a JSON5 config; NULL gives rvc's default (peer, loopback only).
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_config_from_json5(
    json5: *const c_char,
    out: *mut *mut rvc_zenoh_config,
) -> c_int {
    guard(|| {
        let text = if json5.is_null() {
            None
        } else {
            Some(cstr(json5, "json5")?)
        };
        let out = out_ptr(out, "out")?;
        let cfg = config_from_json5(text)?;
        *out = Box::into_raw(Box::new(rvc_zenoh_config { cfg }));
        Ok(RVC_ZENOH_OK)
    })
}

/// Sets one key (Zenoh's '/'-separated path) to a JSON5 value.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_config_insert_json5(
    cfg: *mut rvc_zenoh_config,
    key: *const c_char,
    value: *const c_char,
) -> c_int {
    guard(|| {
        // SAFETY: handle from rvc_zenoh_config_*; exclusive use per the header.
        let c = unsafe { cfg.as_mut() }.ok_or_else(|| einval("config handle is NULL"))?;
        insert(&mut c.cfg, cstr(key, "key")?, cstr(value, "value")?)?;
        Ok(RVC_ZENOH_OK)
    })
}

/// Returns the value at `key` ("" = whole config) as JSON; free with
/// rvc_zenoh_string_free. NULL on error.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_config_get_json(
    cfg: *const rvc_zenoh_config,
    key: *const c_char,
) -> *mut c_char {
    let mut result: *mut c_char = std::ptr::null_mut();
    guard(|| {
        let c = handle(cfg, "config")?;
        let key = if key.is_null() { "" } else { cstr(key, "key")? };
        let text = if key.is_empty() {
            c.cfg.to_string()
        } else {
            c.cfg
                .get_json(key)
                .map_err(|e| ezenoh(&format!("config key '{key}'"), e))?
        };
        result = CString::new(text)
            .map_err(|_| einval("config contains NUL"))?
            .into_raw();
        Ok(RVC_ZENOH_OK)
    });
    result
}

#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_config_free(cfg: *mut rvc_zenoh_config) {
    if !cfg.is_null() {
        // SAFETY: produced by Box::into_raw above.
        guard_void(|| drop(unsafe { Box::from_raw(cfg) }));
    }
}

// ---------------------------------------------------------------------------
// Session
// ---------------------------------------------------------------------------

pub struct rvc_zenoh_session {
    session: Session,
}

fn open_session(cfg: Config, out: *mut *mut rvc_zenoh_session) -> FfiResult<c_int> {
    let out = out_ptr(out, "out")?;
    let session = zenoh::open(cfg)
        .wait()
        .map_err(|e| ezenoh("opening Zenoh session", e))?;
    *out = Box::into_raw(Box::new(rvc_zenoh_session { session }));
    Ok(RVC_ZENOH_OK)
}

/// Opens a session from a JSON5 config string; NULL = rvc's default.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_session_open(
    json5: *const c_char,
    out: *mut *mut rvc_zenoh_session,
) -> c_int {
    guard(|| {
        let text = if json5.is_null() {
            None
        } else {
            Some(cstr(json5, "json5")?)
        };
        open_session(config_from_json5(text)?, out)
    })
}

/// Opens a session from a config handle (not consumed); NULL = rvc's default.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_session_open_config(
    cfg: *const rvc_zenoh_config,
    out: *mut *mut rvc_zenoh_session,
) -> c_int {
    guard(|| {
        // SAFETY: NULL or a handle from rvc_zenoh_config_*.
        let cfg = match unsafe { cfg.as_ref() } {
            Some(c) => c.cfg.clone(),
            None => rvc_default_config("peer")?,
        };
        open_session(cfg, out)
    })
}

/// Writes the session's Zenoh id (hex, NUL-terminated, truncated to fit).
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_session_zid(
    s: *const rvc_zenoh_session,
    buf: *mut c_char,
    len: usize,
) -> c_int {
    guard(|| {
        let s = handle(s, "session")?;
        if buf.is_null() || len == 0 {
            return Err(einval("buffer is NULL or empty"));
        }
        let zid = s.session.zid().to_string();
        let n = zid.len().min(len - 1);
        // SAFETY: caller provides `len` writable bytes.
        unsafe {
            std::ptr::copy_nonoverlapping(zid.as_ptr(), buf as *mut u8, n);
            *buf.add(n) = 0;
        }
        Ok(RVC_ZENOH_OK)
    })
}

/// Closes the session and frees the handle. Undeclare its subscribers and
/// publishers first. Pending publications are flushed by Zenoh's close.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_session_close(s: *mut rvc_zenoh_session) -> c_int {
    if s.is_null() {
        return RVC_ZENOH_OK;
    }
    guard(|| {
        // SAFETY: produced by Box::into_raw in open_session; freed once here.
        let s = unsafe { Box::from_raw(s) };
        s.session
            .close()
            .wait()
            .map_err(|e| ezenoh("closing Zenoh session", e))?;
        Ok(RVC_ZENOH_OK)
    })
}

// ---------------------------------------------------------------------------
// Subscriber
// ---------------------------------------------------------------------------

pub type rvc_zenoh_sample_cb = unsafe extern "C" fn(
    payload: *const u8,
    len: usize,
    attachment: *const u8,
    att_len: usize,
    key: *const u8,
    key_len: usize,
    ctx: *mut c_void,
);

struct CallbackTarget {
    cb: rvc_zenoh_sample_cb,
    ctx: *mut c_void,
    /// Read-held while the C callback runs; undeclare takes it for writing and
    /// flips it to false, so after undeclare returns no callback is running or
    /// will start. (Zenoh's own `wait_callbacks` is still an unstable API.)
    active: RwLock<bool>,
}

// SAFETY: the C side promises `cb` may be called from any thread with `ctx`.
unsafe impl Send for CallbackTarget {}
unsafe impl Sync for CallbackTarget {}

impl CallbackTarget {
    fn deliver(&self, sample: &Sample) {
        let active = self.active.read().unwrap_or_else(|p| p.into_inner());
        if !*active || sample.kind() != SampleKind::Put {
            return;
        }
        // to_bytes() borrows when the payload sits in one slice (the usual
        // case) and copies only when it arrived fragmented.
        let payload: Cow<[u8]> = sample.payload().to_bytes();
        let att: Option<Cow<[u8]>> = sample.attachment().map(ZBytes::to_bytes);
        let (ap, al) = match &att {
            Some(a) => (a.as_ptr(), a.len()),
            None => (std::ptr::null(), 0),
        };
        // The sample's own key (a subscriber on a wildcard sees many): lets
        // rvc filter by key before the monitor.
        let key = sample.key_expr().as_str();
        // SAFETY: pointers stay valid for the duration of the call.
        unsafe { (self.cb)(payload.as_ptr(), payload.len(), ap, al, key.as_ptr(), key.len(), self.ctx) };
    }
}

pub struct rvc_zenoh_subscriber {
    target: Arc<CallbackTarget>,
    subscriber: Option<Subscriber<()>>,
    flush: Option<Queryable<()>>,
    token: Option<LivelinessToken>,
}

/// Answers a publisher's flush query (see FLUSH_PREFIX) unless the subscriber
/// is being undeclared, in which case later samples would not be delivered.
fn answer_flush(target: &CallbackTarget, query: &Query) {
    let active = target.active.read().unwrap_or_else(|p| p.into_inner());
    if !*active {
        return;
    }
    if let Err(e) = query.reply(query.key_expr().clone(), ZBytes::default()).wait() {
        warn(&format!("answering a flush query: {e}"));
    }
}

fn warn(msg: &str) {
    eprintln!("rvc: zenoh: {msg}");
}

static ANNOUNCE_COUNTER: AtomicU64 = AtomicU64::new(0);

/// A declaration after the subscriber failed: the caller frees ctx on error,
/// so fence callbacks before the subscriber goes, and pass the error on.
fn abandon(target: &CallbackTarget, subscriber: Subscriber<()>, e: FfiError) -> FfiError {
    *target.active.write().unwrap_or_else(|p| p.into_inner()) = false;
    drop(subscriber);
    e
}

fn keyexpr(s: &str) -> FfiResult<KeyExpr<'static>> {
    KeyExpr::autocanonize(s.to_owned()).map_err(|e| einval(format!("key expression '{s}': {e}")))
}

/// 1 if some key matches both key expressions (a subscriber on `a` would
/// receive what is put on `b`), 0 if none does, negative on a bad expression.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_keyexpr_intersects(a: *const c_char, b: *const c_char) -> c_int {
    guard(|| {
        let ka = keyexpr(cstr(a, "keyexpr a")?)?;
        let kb = keyexpr(cstr(b, "keyexpr b")?)?;
        Ok(ka.intersects(&kb) as c_int)
    })
}

/// Declares a subscriber on `keyexpr`. `cb` runs on a Zenoh thread with
/// borrowed buffers; it must not block for long nor call back into this
/// library for the same subscriber. With `announce` != 0 the subscriber also
/// declares a liveliness token so publishers can count it.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_subscriber_declare(
    s: *const rvc_zenoh_session,
    key: *const c_char,
    cb: Option<rvc_zenoh_sample_cb>,
    ctx: *mut c_void,
    announce: c_int,
    out: *mut *mut rvc_zenoh_subscriber,
) -> c_int {
    guard(|| {
        let s = handle(s, "session")?;
        let ke = keyexpr(cstr(key, "keyexpr")?)?;
        let cb = cb.ok_or_else(|| einval("callback is NULL"))?;
        let out = out_ptr(out, "out")?;
        let target = Arc::new(CallbackTarget {
            cb,
            ctx,
            active: RwLock::new(true),
        });
        let t = target.clone();
        let subscriber = s
            .session
            .declare_subscriber(ke.clone())
            .callback(move |sample: Sample| {
                // A panic must not escape into Zenoh's receive task.
                let _ = catch_unwind(AssertUnwindSafe(|| t.deliver(&sample)));
            })
            .wait()
            .map_err(|e| ezenoh(&format!("declaring subscriber on '{ke}'"), e))?;
        // The flush queryable and then the token are declared after the
        // subscriber: all travel in order on the same links, so a publisher
        // that sees the token also routes samples and flush queries to it.
        let flush = if announce != 0 {
            let t = target.clone();
            let declared = keyexpr(&format!("{FLUSH_PREFIX}/{ke}")).and_then(|fk| {
                s.session
                    .declare_queryable(fk)
                    .callback(move |query: Query| {
                        let _ = catch_unwind(AssertUnwindSafe(|| answer_flush(&t, &query)));
                    })
                    .wait()
                    .map_err(|e| ezenoh("declaring flush queryable", e))
            });
            match declared {
                Ok(q) => Some(q),
                Err(e) => return Err(abandon(&target, subscriber, e)),
            }
        } else {
            None
        };
        let token = if announce != 0 {
            let id = format!(
                "{}-{}",
                s.session.zid(),
                ANNOUNCE_COUNTER.fetch_add(1, Ordering::Relaxed)
            );
            let declared = keyexpr(&format!("{ANNOUNCE_PREFIX}/{id}/{ke}")).and_then(|tk| {
                s.session
                    .liveliness()
                    .declare_token(tk)
                    .wait()
                    .map_err(|e| ezenoh("declaring liveliness token", e))
            });
            match declared {
                Ok(token) => Some(token),
                Err(e) => return Err(abandon(&target, subscriber, e)),
            }
        } else {
            None
        };
        *out = Box::into_raw(Box::new(rvc_zenoh_subscriber {
            target,
            subscriber: Some(subscriber),
            flush,
            token,
        }));
        Ok(RVC_ZENOH_OK)
    })
}

/// Undeclares and frees. On return no callback is running or will run.
/// Must not be called from inside the subscriber's own callback.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_subscriber_undeclare(sub: *mut rvc_zenoh_subscriber) -> c_int {
    if sub.is_null() {
        return RVC_ZENOH_OK;
    }
    guard(|| {
        // SAFETY: produced by Box::into_raw in declare; freed once here.
        let mut sub = unsafe { Box::from_raw(sub) };
        *sub.target.active.write().unwrap_or_else(|p| p.into_inner()) = false;
        if let Some(t) = sub.token.take() {
            t.undeclare()
                .wait()
                .map_err(|e| ezenoh("undeclaring liveliness token", e))?;
        }
        if let Some(q) = sub.flush.take() {
            q.undeclare()
                .wait()
                .map_err(|e| ezenoh("undeclaring flush queryable", e))?;
        }
        if let Some(s) = sub.subscriber.take() {
            s.undeclare()
                .wait()
                .map_err(|e| ezenoh("undeclaring subscriber", e))?;
        }
        Ok(RVC_ZENOH_OK)
    })
}

// ---------------------------------------------------------------------------
// Publisher
// ---------------------------------------------------------------------------

#[derive(Default)]
struct MatchState {
    /// Keys of live announcement tokens of rvc subscribers matching us.
    announced: HashSet<String>,
    /// Bumped on every matching/liveliness event to wake waiters.
    generation: u64,
}

type Shared = Arc<(Mutex<MatchState>, Condvar)>;

pub struct rvc_zenoh_publisher {
    publisher: Publisher<'static>,
    session: Session,
    flush_key: KeyExpr<'static>,
    state: Shared,
    announcements: Option<Subscriber<()>>,
}

fn bump(state: &Shared, f: impl FnOnce(&mut MatchState)) {
    let (m, cv) = &**state;
    let mut g = m.lock().unwrap_or_else(|p| p.into_inner());
    f(&mut g);
    g.generation += 1;
    cv.notify_all();
}

/// Declares a publisher: reliable (Zenoh's default reliability, carried over
/// TCP), CongestionControl::Block so a slow subscriber slows the publisher
/// down instead of losing messages. `express` != 0 skips batching.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_publisher_declare(
    s: *const rvc_zenoh_session,
    key: *const c_char,
    express: c_int,
    out: *mut *mut rvc_zenoh_publisher,
) -> c_int {
    guard(|| {
        let s = handle(s, "session")?;
        let ke = keyexpr(cstr(key, "keyexpr")?)?;
        let out = out_ptr(out, "out")?;
        let publisher = s
            .session
            .declare_publisher(ke.clone())
            .congestion_control(CongestionControl::Block)
            .express(express != 0)
            .wait()
            .map_err(|e| ezenoh(&format!("declaring publisher on '{ke}'"), e))?;
        let state: Shared = Arc::default();

        // The listener only wakes waiters; the status itself is re-read on
        // wake-up so a late notification can never leave a stale value.
        let st = state.clone();
        publisher
            .matching_listener()
            .callback(move |_status| bump(&st, |_| {}))
            .background()
            .wait()
            .map_err(|e| ezenoh("declaring matching listener", e))?;

        let st = state.clone();
        let watch = keyexpr(&format!("{ANNOUNCE_PREFIX}/*/{ke}"))?;
        let announcements = s
            .session
            .liveliness()
            .declare_subscriber(watch)
            .history(true)
            .callback(move |sample: Sample| {
                let key = sample.key_expr().to_string();
                let put = sample.kind() == SampleKind::Put;
                bump(&st, |g| {
                    if put {
                        g.announced.insert(key);
                    } else {
                        g.announced.remove(&key);
                    }
                });
            })
            .wait()
            .map_err(|e| ezenoh("declaring liveliness subscriber", e))?;

        *out = Box::into_raw(Box::new(rvc_zenoh_publisher {
            publisher,
            session: s.session.clone(),
            flush_key: keyexpr(&format!("{FLUSH_PREFIX}/{ke}"))?,
            state,
            announcements: Some(announcements),
        }));
        Ok(RVC_ZENOH_OK)
    })
}

/// Publishes one sample. Blocks while the link is congested. `attachment`
/// NULL with `att_len` 0 sends no attachment.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_publisher_put(
    p: *const rvc_zenoh_publisher,
    payload: *const u8,
    len: usize,
    attachment: *const u8,
    att_len: usize,
) -> c_int {
    guard(|| {
        let p = handle(p, "publisher")?;
        let body = ZBytes::from(bytes(payload, len, "payload")?.to_vec());
        let mut put = p.publisher.put(body);
        if !attachment.is_null() {
            put = put.attachment(ZBytes::from(
                bytes(attachment, att_len, "attachment")?.to_vec(),
            ));
        }
        put.wait().map_err(|e| ezenoh("put", e))?;
        Ok(RVC_ZENOH_OK)
    })
}

fn matching_now(p: &rvc_zenoh_publisher) -> FfiResult<bool> {
    p.publisher
        .matching_status()
        .wait()
        .map(|s| s.matching())
        .map_err(|e| ezenoh("matching status", e))
}

fn announced_now(p: &rvc_zenoh_publisher) -> usize {
    p.state
        .0
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .announced
        .len()
}

/// Reports whether any subscriber (rvc or not) matches, and how many rvc
/// subscribers announced themselves on a matching key.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_publisher_matching(
    p: *const rvc_zenoh_publisher,
    matching: *mut c_int,
    announced: *mut usize,
) -> c_int {
    guard(|| {
        let p = handle(p, "publisher")?;
        let m = matching_now(p)?;
        if let Some(out) = unsafe { matching.as_mut() } {
            *out = m as c_int;
        }
        if let Some(out) = unsafe { announced.as_mut() } {
            *out = announced_now(p);
        }
        Ok(RVC_ZENOH_OK)
    })
}

/// Waits until at least `n` subscribers match: n <= 1 needs Zenoh's matching
/// status (any subscriber, e.g. plain Python); n > 1 additionally needs n
/// announced rvc subscribers. Returns 1 when reached, 0 on timeout.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_publisher_wait_matched(
    p: *const rvc_zenoh_publisher,
    n: usize,
    timeout_ms: u64,
) -> c_int {
    guard(|| {
        let p = handle(p, "publisher")?;
        if n == 0 {
            return Ok(1);
        }
        let deadline = Instant::now() + Duration::from_millis(timeout_ms);
        let (m, cv) = &*p.state;
        loop {
            let generation = m.lock().unwrap_or_else(|e| e.into_inner()).generation;
            if matching_now(p)? && (n <= 1 || announced_now(p) >= n) {
                return Ok(1);
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(0);
            }
            // Sleep until an event changes the generation. The cap is only a
            // safety net should a status change ever come without an event.
            let cap = (deadline - now).min(Duration::from_millis(200));
            let g = m.lock().unwrap_or_else(|e| e.into_inner());
            let _ = cv
                .wait_timeout_while(g, cap, |s| s.generation == generation)
                .unwrap_or_else(|e| e.into_inner());
        }
    })
}

/// Waits until every rvc subscriber reachable now has taken every sample this
/// publisher put before the call (see FLUSH_PREFIX). `*confirmed` receives the
/// number of subscribers that answered; non-rvc subscribers cannot answer.
/// Returns 1 when the query completed, 0 when `timeout_ms` ran out first.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_publisher_flush(
    p: *const rvc_zenoh_publisher,
    timeout_ms: u64,
    confirmed: *mut usize,
) -> c_int {
    guard(|| {
        let p = handle(p, "publisher")?;
        let deadline = Instant::now() + Duration::from_millis(timeout_ms);
        let replies = p
            .session
            .get(p.flush_key.clone())
            .target(QueryTarget::All)
            .consolidation(ConsolidationMode::None)
            .congestion_control(CongestionControl::Block)
            .priority(Priority::default())
            // Zenoh's own query timeout comes later, so the deadline below
            // tells a timeout from completion.
            .timeout(Duration::from_millis(timeout_ms) + Duration::from_secs(1))
            .wait()
            .map_err(|e| ezenoh("flush query", e))?;
        let mut n = 0usize;
        let complete = loop {
            match replies.recv_deadline(deadline) {
                Ok(Some(reply)) => {
                    if reply.result().is_ok() {
                        n += 1;
                    }
                }
                Ok(None) => break false, // timed out
                Err(_) => break true,    // all queryables answered (or none exists)
            }
        };
        if let Some(out) = unsafe { confirmed.as_mut() } {
            *out = n;
        }
        Ok(complete as c_int)
    })
}

/// Undeclares and frees the publisher.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_publisher_undeclare(p: *mut rvc_zenoh_publisher) -> c_int {
    if p.is_null() {
        return RVC_ZENOH_OK;
    }
    guard(|| {
        // SAFETY: produced by Box::into_raw in declare; freed once here.
        let mut p = unsafe { Box::from_raw(p) };
        if let Some(a) = p.announcements.take() {
            a.undeclare()
                .wait()
                .map_err(|e| ezenoh("undeclaring liveliness subscriber", e))?;
        }
        let rvc_zenoh_publisher { publisher, .. } = *p;
        publisher
            .undeclare()
            .wait()
            .map_err(|e| ezenoh("undeclaring publisher", e))?;
        Ok(RVC_ZENOH_OK)
    })
}

// ---------------------------------------------------------------------------
// Liveliness token (a monitor announcing itself)
// ---------------------------------------------------------------------------

pub struct rvc_zenoh_token {
    token: Option<LivelinessToken>,
}

/// Declares a liveliness token on `key`: liveliness subscribers see it appear
/// now and disappear when it is undeclared or the session is gone (including
/// the process being killed: its peers' transport lease expires).
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_token_declare(
    s: *const rvc_zenoh_session,
    key: *const c_char,
    out: *mut *mut rvc_zenoh_token,
) -> c_int {
    guard(|| {
        let s = handle(s, "session")?;
        let ke = keyexpr(cstr(key, "keyexpr")?)?;
        let out = out_ptr(out, "out")?;
        let token = s
            .session
            .liveliness()
            .declare_token(ke.clone())
            .wait()
            .map_err(|e| ezenoh(&format!("declaring liveliness token '{ke}'"), e))?;
        *out = Box::into_raw(Box::new(rvc_zenoh_token { token: Some(token) }));
        Ok(RVC_ZENOH_OK)
    })
}

/// Undeclares the token and frees the handle.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_token_undeclare(t: *mut rvc_zenoh_token) -> c_int {
    if t.is_null() {
        return RVC_ZENOH_OK;
    }
    guard(|| {
        // SAFETY: produced by Box::into_raw in declare; freed once here.
        let mut t = unsafe { Box::from_raw(t) };
        if let Some(token) = t.token.take() {
            token
                .undeclare()
                .wait()
                .map_err(|e| ezenoh("undeclaring liveliness token", e))?;
        }
        Ok(RVC_ZENOH_OK)
    })
}

// ---------------------------------------------------------------------------
// Liveliness query (graph discovery: the tokens alive now)
// ---------------------------------------------------------------------------

pub type rvc_zenoh_key_cb = unsafe extern "C" fn(key: *const u8, key_len: usize, ctx: *mut c_void);

/// Asks the network for the liveliness tokens alive now whose key matches
/// `key` (rmw_zenoh's graph: "@ros2_lv/0/**"), calling `cb` once per token
/// on the calling thread. Waits until every peer answered or `timeout_ms`
/// ran out. Returns the number of tokens (>= 0) or an error code.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_liveliness_get(
    s: *const rvc_zenoh_session,
    key: *const c_char,
    timeout_ms: u64,
    cb: Option<rvc_zenoh_key_cb>,
    ctx: *mut c_void,
) -> c_int {
    guard(|| {
        let s = handle(s, "session")?;
        let ke = keyexpr(cstr(key, "keyexpr")?)?;
        let cb = cb.ok_or_else(|| einval("callback is NULL"))?;
        let deadline = Instant::now() + Duration::from_millis(timeout_ms);
        let replies = s
            .session
            .liveliness()
            .get(ke.clone())
            .timeout(Duration::from_millis(timeout_ms))
            .wait()
            .map_err(|e| ezenoh(&format!("liveliness query '{ke}'"), e))?;
        let mut n: c_int = 0;
        loop {
            match replies.recv_deadline(deadline) {
                Ok(Some(reply)) => {
                    if let Ok(sample) = reply.result() {
                        let k = sample.key_expr().as_str();
                        // SAFETY: the callback borrows the key for the call only.
                        unsafe { cb(k.as_ptr(), k.len(), ctx) };
                        n = n.saturating_add(1);
                    }
                }
                Ok(None) => break, // timed out: report what answered
                Err(_) => break,   // every peer answered
            }
        }
        Ok(n)
    })
}

// ---------------------------------------------------------------------------
// Liveliness subscriber (a group's member set: rvc monitor --group)
// ---------------------------------------------------------------------------

/// `alive` is 1 when the token appeared (or was alive at declaration, with
/// history), 0 when it went (undeclared, or its session's lease expired).
pub type rvc_zenoh_liveliness_cb =
    unsafe extern "C" fn(key: *const u8, key_len: usize, alive: c_int, ctx: *mut c_void);

struct LivelinessTarget {
    cb: rvc_zenoh_liveliness_cb,
    ctx: *mut c_void,
    /// As CallbackTarget::active: undeclare fences the callbacks.
    active: RwLock<bool>,
}

// SAFETY: the C side promises `cb` may be called from any thread with `ctx`.
unsafe impl Send for LivelinessTarget {}
unsafe impl Sync for LivelinessTarget {}

pub struct rvc_zenoh_liveliness_subscriber {
    target: Arc<LivelinessTarget>,
    subscriber: Option<Subscriber<()>>,
}

/// Subscribes to the liveliness tokens matching `key`: `cb` runs on a Zenoh
/// thread for each token that appears or goes; `history` != 0 also reports
/// the tokens alive at declaration.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_liveliness_subscribe(
    s: *const rvc_zenoh_session,
    key: *const c_char,
    history: c_int,
    cb: Option<rvc_zenoh_liveliness_cb>,
    ctx: *mut c_void,
    out: *mut *mut rvc_zenoh_liveliness_subscriber,
) -> c_int {
    guard(|| {
        let s = handle(s, "session")?;
        let ke = keyexpr(cstr(key, "keyexpr")?)?;
        let cb = cb.ok_or_else(|| einval("callback is NULL"))?;
        let out = out_ptr(out, "out")?;
        let target = Arc::new(LivelinessTarget { cb, ctx, active: RwLock::new(true) });
        let t = target.clone();
        let subscriber = s
            .session
            .liveliness()
            .declare_subscriber(ke.clone())
            .history(history != 0)
            .callback(move |sample: Sample| {
                let active = t.active.read().unwrap_or_else(|p| p.into_inner());
                if !*active {
                    return;
                }
                let k = sample.key_expr().as_str();
                let alive = (sample.kind() == SampleKind::Put) as c_int;
                // SAFETY: the key is borrowed for the call only.
                unsafe { (t.cb)(k.as_ptr(), k.len(), alive, t.ctx) };
            })
            .wait()
            .map_err(|e| ezenoh(&format!("declaring liveliness subscriber on '{ke}'"), e))?;
        *out = Box::into_raw(Box::new(rvc_zenoh_liveliness_subscriber {
            target,
            subscriber: Some(subscriber),
        }));
        Ok(RVC_ZENOH_OK)
    })
}

/// After return no callback is running or will run. Frees the handle.
#[no_mangle]
pub unsafe extern "C" fn rvc_zenoh_liveliness_unsubscribe(sub: *mut rvc_zenoh_liveliness_subscriber) -> c_int {
    if sub.is_null() {
        return RVC_ZENOH_OK;
    }
    guard(|| {
        // SAFETY: produced by Box::into_raw in subscribe; freed once here.
        let mut sub = unsafe { Box::from_raw(sub) };
        *sub.target.active.write().unwrap_or_else(|p| p.into_inner()) = false;
        if let Some(s) = sub.subscriber.take() {
            s.undeclare()
                .wait()
                .map_err(|e| ezenoh("undeclaring liveliness subscriber", e))?;
        }
        Ok(RVC_ZENOH_OK)
    })
}
