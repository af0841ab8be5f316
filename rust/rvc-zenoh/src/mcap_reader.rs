//! MCAP (the ROS 2 bag format) reading for `rvc check bag.mcap` and
//! `--input mcap:`, through the `mcap` crate: chunk compression (zstd, lz4),
//! CRCs and record framing are the library's business, not rvc's.
//!
//! The C side sees a reader handle and one message at a time, in the order
//! the messages are stored (rosbag2 stores them as they were received), with
//! its channel's topic, message encoding and schema (name, encoding, text):
//! for a ROS 2 bag the schema is the concatenated .msg definitions, which rvc
//! parses instead of needing --msg-path. Pointers stay valid until the next
//! call on the same handle.

use std::ffi::{c_char, c_int, CString};
use std::sync::Arc;

use crate::{cstr, einval, guard, guard_void, out_ptr, FfiError, RVC_ZENOH_OK};

/// The file is no MCAP or a record in it is broken (after the messages before it).
pub const RVC_MCAP_EFORMAT: c_int = -4;

#[repr(C)]
pub struct rvc_mcap_message {
    pub topic: *const c_char,
    pub message_encoding: *const c_char,
    pub schema_name: *const c_char,     // "" if the channel has no schema
    pub schema_encoding: *const c_char, // "ros2msg", "ros2idl", "jsonschema", ...
    pub schema_data: *const u8,
    pub schema_len: usize,
    pub data: *const u8,
    pub len: usize,
    pub channel_id: u16,
    pub sequence: u32,
    pub log_time: u64,     // ns
    pub publish_time: u64, // ns
    pub index: u64,        // 1-based position in the file, over all topics
}

/// The channel strings of the current message as C strings, kept per channel
/// so that a file of one topic does not allocate per message.
struct ChannelText {
    id: u16,
    topic: CString,
    message_encoding: CString,
    schema_name: CString,
    schema_encoding: CString,
}

pub struct rvc_mcap_reader {
    // Field order matters: the stream borrows the map and is dropped first.
    stream: mcap::MessageStream<'static>,
    current: Option<mcap::Message<'static>>,
    channels: Vec<ChannelText>,
    index: u64,
    _map: memmap2::Mmap,
}

fn eformat(msg: String) -> FfiError {
    FfiError { code: RVC_MCAP_EFORMAT, msg }
}

fn c_string(s: &str) -> CString {
    // Topic and schema names have no NUL; if one did, cut it there.
    CString::new(s.split('\0').next().unwrap_or("")).unwrap_or_default()
}

/// Opens an MCAP file: checks its magic and prepares to read messages.
#[no_mangle]
pub unsafe extern "C" fn rvc_mcap_open(path: *const c_char, out: *mut *mut rvc_mcap_reader) -> c_int {
    guard(|| {
        let path = cstr(path, "path")?;
        let out = out_ptr(out, "out")?;
        let file = std::fs::File::open(path).map_err(|e| einval(format!("cannot open '{path}': {e}")))?;
        // SAFETY: the map is read-only; a file truncated by another process
        // while it is read is the one case this cannot guard against (as for
        // every memory-mapped reader, including the mcap CLI).
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| einval(format!("cannot map '{path}': {e}")))?;
        // SAFETY: the slice lives as long as `map`, which the reader owns and
        // drops after the stream (field order).
        let bytes: &'static [u8] = unsafe { std::slice::from_raw_parts(map.as_ptr(), map.len()) };
        let stream = mcap::MessageStream::new(bytes).map_err(|e| eformat(format!("'{path}' is not an MCAP file: {e}")))?;
        *out = Box::into_raw(Box::new(rvc_mcap_reader {
            stream,
            current: None,
            channels: Vec::new(),
            index: 0,
            _map: map,
        }));
        Ok(RVC_ZENOH_OK)
    })
}

/// Reads the next message into `out`: returns 1, 0 at the end of the file,
/// or a negative code (the message is in rvc_zenoh_last_error()).
#[no_mangle]
pub unsafe extern "C" fn rvc_mcap_next(reader: *mut rvc_mcap_reader, out: *mut rvc_mcap_message) -> c_int {
    guard(|| {
        // SAFETY: a handle from rvc_mcap_open, used by one thread at a time.
        let r = unsafe { reader.as_mut() }.ok_or_else(|| einval("reader handle is NULL"))?;
        let out = out_ptr(out, "out")?;
        r.current = None;
        let message = match r.stream.next() {
            None => return Ok(0),
            Some(Err(e)) => {
                return Err(eformat(format!("after message {}: {e}", r.index)));
            }
            Some(Ok(m)) => m,
        };
        r.index += 1;
        let ch: &Arc<mcap::Channel<'static>> = &message.channel;
        let pos = match r.channels.iter().position(|c| c.id == ch.id) {
            Some(p) => p,
            None => {
                let (name, encoding) = match &ch.schema {
                    Some(s) => (s.name.as_str(), s.encoding.as_str()),
                    None => ("", ""),
                };
                r.channels.push(ChannelText {
                    id: ch.id,
                    topic: c_string(&ch.topic),
                    message_encoding: c_string(&ch.message_encoding),
                    schema_name: c_string(name),
                    schema_encoding: c_string(encoding),
                });
                r.channels.len() - 1
            }
        };
        let text = &r.channels[pos];
        let (schema_data, schema_len) = match &ch.schema {
            Some(s) => (s.data.as_ptr(), s.data.len()),
            None => (std::ptr::null(), 0),
        };
        *out = rvc_mcap_message {
            topic: text.topic.as_ptr(),
            message_encoding: text.message_encoding.as_ptr(),
            schema_name: text.schema_name.as_ptr(),
            schema_encoding: text.schema_encoding.as_ptr(),
            schema_data,
            schema_len,
            data: message.data.as_ptr(),
            len: message.data.len(),
            channel_id: ch.id,
            sequence: message.sequence,
            log_time: message.log_time,
            publish_time: message.publish_time,
            index: r.index,
        };
        r.current = Some(message); // keeps data and schema alive until the next call
        Ok(1)
    })
}

#[no_mangle]
pub unsafe extern "C" fn rvc_mcap_close(reader: *mut rvc_mcap_reader) {
    if !reader.is_null() {
        // SAFETY: produced by Box::into_raw in rvc_mcap_open.
        guard_void(|| drop(unsafe { Box::from_raw(reader) }));
    }
}
