//! MCAP (the ROS 2 bag format) reading for `rvc check bag.mcap` and
//! `--input mcap:`. The file is memory-mapped and walked record by record
//! (mcap_records.rs: every declared length is checked against the bytes
//! there); chunks are checked and decompressed whole (mcap_chunk.rs, the
//! `mcap` crate's decoders) before any of their records is used.
//!
//! The C side sees a reader handle and one message at a time, in the order
//! the messages are stored (rosbag2 stores them as they were received), with
//! its channel's topic, message encoding and schema (name, encoding, text):
//! for a ROS 2 bag the schema is the concatenated .msg definitions, which rvc
//! parses instead of needing --msg-path. Pointers stay valid until the next
//! call on the same handle.
//!
//! Bad records come in two kinds. One whose length runs past the end of the
//! file ends the reading (the records after it cannot be found: a recording
//! cut short). Any other (a chunk whose CRC does not match or that does not
//! decompress, a message on a channel never defined, a schema or channel
//! redefined differently) is skipped: rvc_mcap_next says so with
//! RVC_MCAP_SKIPPED and the reason, and the next call goes on after it.

use std::collections::HashMap;
use std::ffi::{c_char, c_int, CString};
use std::sync::Arc;

use crate::mcap_chunk::{self, ChunkRecords};
use crate::mcap_records::{self as rec, Crc32, Record};
use crate::{cstr, einval, guard, guard_void, out_ptr, set_last_error, FfiError, RVC_ZENOH_OK};

/// The file is no MCAP or a record in it is broken (after the messages before it).
pub const RVC_MCAP_EFORMAT: c_int = -4;
/// A record was skipped (the reason is in rvc_zenoh_last_error()); reading goes on.
pub const RVC_MCAP_SKIPPED: c_int = 2;

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

struct Schema {
    body: Vec<u8>, // the record as first defined: a redefinition must be identical
    name: CString,
    encoding: CString,
    data: Vec<u8>,
}

/// A channel's strings as C strings, made once per channel (not per message).
struct Channel {
    body: Vec<u8>,
    topic: CString,
    message_encoding: CString,
    schema: Option<Arc<Schema>>,
}

/// The chunk being read: its offset in the file and its records.
struct OpenChunk {
    offset: usize,
    records: ChunkRecords,
    pos: usize,
    damage: Option<String>, // said after its records: why the chunk's rest is skipped
}

pub struct rvc_mcap_reader {
    bytes: &'static [u8], // the mapped file; lives as long as `_map`
    pos: usize,           // the next record of the file
    chunk: Option<OpenChunk>,
    schemas: HashMap<u16, Arc<Schema>>,
    channels: HashMap<u16, Channel>, // by id: a bag of 65,535 channels costs no more per message than one
    index: u64,
    data_crc: Crc32, // of the file before the data end record
    chunk_refused: bool, // a chunk's CRC failed already: the data section's is then known to fail
    ended: bool,
    cut: Option<String>, // the file ends inside a chunk: said once its complete records are read
    _map: memmap2::Mmap,
}

fn eformat(msg: String) -> FfiError {
    FfiError { code: RVC_MCAP_EFORMAT, msg }
}

fn c_string(s: &str) -> CString {
    // Topic and schema names have no NUL; if one did, cut it there.
    CString::new(s.split('\0').next().unwrap_or("")).unwrap_or_default()
}

/// Where a record is, for errors: in the file, or inside a chunk.
fn place(chunk: Option<usize>, record: &Record) -> String {
    match chunk {
        None => format!("the {} record at offset {}", rec::op_name(record.opcode), record.start),
        Some(c) => format!(
            "the {} record at offset {} of the records of the chunk at offset {c}",
            rec::op_name(record.opcode),
            record.start
        ),
    }
}

/// What one record gave.
enum Step {
    Nothing,
    Message,
    Skipped(String),
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
        // SAFETY: the slice lives as long as `map`, which the reader owns.
        let bytes: &'static [u8] = unsafe { std::slice::from_raw_parts(map.as_ptr(), map.len()) };
        if !bytes.starts_with(rec::MAGIC) {
            return Err(eformat(format!("'{path}' is not an MCAP file: it does not start with MCAP's magic bytes")));
        }
        let mut data_crc = Crc32::new();
        data_crc.update(&bytes[..rec::MAGIC.len()]);
        *out = Box::into_raw(Box::new(rvc_mcap_reader {
            bytes,
            pos: rec::MAGIC.len(),
            chunk: None,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            index: 0,
            data_crc,
            chunk_refused: false,
            ended: false,
            cut: None,
            _map: map,
        }));
        Ok(RVC_ZENOH_OK)
    })
}

impl rvc_mcap_reader {
    /// A schema, channel or message record (in the file or in a chunk).
    fn record(&mut self, r: &Record<'static>, chunk: Option<usize>, out: &mut rvc_mcap_message) -> Step {
        let bad = |e: String| Step::Skipped(format!("{}: {e} (record skipped)", place(chunk, r)));
        match r.opcode {
            rec::OP_SCHEMA => {
                let s = match rec::schema(r.body) {
                    Ok(s) => s,
                    Err(e) => return bad(e),
                };
                if s.id == 0 {
                    return bad("schema id 0 is reserved for 'no schema'".into());
                }
                match self.schemas.get(&s.id) {
                    Some(old) if old.body != r.body => bad(format!(
                        "schema {} is redefined differently ('{}', first '{}'): the first definition stays",
                        s.id,
                        s.name,
                        old.name.to_string_lossy()
                    )),
                    Some(_) => Step::Nothing,
                    None => {
                        self.schemas.insert(
                            s.id,
                            Arc::new(Schema {
                                body: r.body.to_vec(),
                                name: c_string(s.name),
                                encoding: c_string(s.encoding),
                                data: s.data.to_vec(),
                            }),
                        );
                        Step::Nothing
                    }
                }
            }
            rec::OP_CHANNEL => {
                let c = match rec::channel(r.body) {
                    Ok(c) => c,
                    Err(e) => return bad(e),
                };
                if let Some(old) = self.channels.get(&c.id) {
                    return if old.body == r.body {
                        Step::Nothing
                    } else {
                        bad(format!(
                            "channel {} is redefined differently ('{}', first '{}'): the first definition stays",
                            c.id,
                            c.topic,
                            old.topic.to_string_lossy()
                        ))
                    };
                }
                let schema = match c.schema_id {
                    0 => None,
                    id => match self.schemas.get(&id) {
                        Some(s) => Some(s.clone()),
                        None => return bad(format!("channel {} ('{}') names schema {id}, which is not defined", c.id, c.topic)),
                    },
                };
                self.channels.insert(
                    c.id,
                    Channel {
                        body: r.body.to_vec(),
                        topic: c_string(c.topic),
                        message_encoding: c_string(c.message_encoding),
                        schema,
                    },
                );
                Step::Nothing
            }
            rec::OP_MESSAGE => {
                self.index += 1;
                let m = match rec::message(r.body) {
                    Ok(m) => m,
                    Err(e) => return Step::Skipped(format!("message {} ({}): {e} (message skipped)", self.index, place(chunk, r))),
                };
                let Some(ch) = self.channels.get(&m.channel_id) else {
                    return Step::Skipped(format!(
                        "message {} ({}): its channel {} is not defined (message skipped)",
                        self.index,
                        place(chunk, r),
                        m.channel_id
                    ));
                };
                static EMPTY: &[u8; 1] = b"\0";
                let (schema_name, schema_encoding, schema_data, schema_len) = match &ch.schema {
                    Some(s) => (s.name.as_ptr(), s.encoding.as_ptr(), s.data.as_ptr(), s.data.len()),
                    None => (EMPTY.as_ptr() as *const c_char, EMPTY.as_ptr() as *const c_char, std::ptr::null(), 0),
                };
                *out = rvc_mcap_message {
                    topic: ch.topic.as_ptr(),
                    message_encoding: ch.message_encoding.as_ptr(),
                    schema_name,
                    schema_encoding,
                    schema_data,
                    schema_len,
                    data: m.data.as_ptr(),
                    len: m.data.len(),
                    channel_id: m.channel_id,
                    sequence: m.sequence,
                    log_time: m.log_time,
                    publish_time: m.publish_time,
                    index: self.index,
                };
                Step::Message
            }
            _ => Step::Nothing, // indexes, attachments, metadata, and opcodes of later MCAP versions
        }
    }

    /// The next record inside the open chunk, if one is open.
    fn chunk_step(&mut self, out: &mut rvc_mcap_message) -> Option<Step> {
        let c = self.chunk.as_mut()?;
        // SAFETY: the records live until the chunk is closed, which happens
        // at the earliest in the call after the one handing out pointers into them.
        let bytes: &'static [u8] = unsafe { std::mem::transmute::<&[u8], &'static [u8]>(c.records.bytes()) };
        let offset = c.offset;
        match rec::record_at(bytes, c.pos, "its records") {
            Ok(None) => {
                let damage = c.damage.take();
                self.chunk = None;
                Some(match damage {
                    Some(why) => Step::Skipped(format!("the chunk at offset {offset}: {why}")),
                    None => Step::Nothing,
                })
            }
            Ok(Some(r)) => {
                c.pos = r.next;
                Some(self.record(&r, Some(offset), out))
            }
            Err(e) => {
                self.chunk = None;
                Some(Step::Skipped(format!("the chunk at offset {offset}: {e}; its remaining records are skipped")))
            }
        }
    }

    /// The next record of the file; Err: reading cannot go on.
    fn file_step(&mut self, out: &mut rvc_mcap_message) -> Result<Step, FfiError> {
        let bytes = self.bytes;
        let r = match rec::record_at(bytes, self.pos, "the file") {
            Ok(Some(r)) => r,
            Ok(None) => {
                return Err(eformat(format!(
                    "the file ends at offset {} without its data end record (a recording cut short?)",
                    self.pos
                )))
            }
            Err(e) => {
                let e = format!("{e} (a recording cut short, or a damaged length)");
                if bytes.len() - self.pos >= 9 && bytes[self.pos] == rec::OP_CHUNK {
                    // A chunk being written when the recording stopped: its
                    // complete records are read first, then the cut is said.
                    self.chunk = Some(OpenChunk {
                        offset: self.pos,
                        records: mcap_chunk::salvage(&bytes[self.pos..]),
                        pos: 0,
                        damage: None,
                    });
                    self.pos = bytes.len();
                    self.ended = true;
                    self.cut = Some(e);
                    return Ok(Step::Nothing);
                }
                return Err(eformat(e));
            }
        };
        self.pos = r.next;
        match r.opcode {
            rec::OP_DATA_END | rec::OP_FOOTER => {
                self.ended = true;
                if r.opcode == rec::OP_DATA_END {
                    if let Ok(saved) = rec::data_end_crc(r.body) {
                        let crc = self.data_crc.value();
                        if saved != 0 && saved != crc && !self.chunk_refused {
                            return Ok(Step::Skipped(format!(
                                "the CRC of the data section is {crc:#010x}, the data end record at offset {} \
                                 records {saved:#010x} (a record outside the chunks was altered)",
                                r.start
                            )));
                        }
                    }
                }
                return Ok(Step::Nothing);
            }
            _ => self.data_crc.update(&bytes[r.start..r.next]),
        }
        if r.opcode != rec::OP_CHUNK {
            return Ok(self.record(&r, None, out));
        }
        match mcap_chunk::open(&bytes[r.start..r.next], r.body) {
            Ok(opened) => {
                if opened.damage.is_some() {
                    self.chunk_refused = true; // the data section's CRC is then known to fail too
                }
                self.chunk = Some(OpenChunk { offset: r.start, records: opened.records, pos: 0, damage: opened.damage });
                Ok(Step::Nothing)
            }
            Err(e) => {
                self.chunk_refused = true;
                let first = self.index + 1;
                self.index += e.messages;
                let skipped = match e.messages {
                    0 => "its records are skipped".to_string(),
                    1 => format!("its message {first} is skipped"),
                    n => format!("its messages {first}-{} ({n}) are skipped", self.index),
                };
                Ok(Step::Skipped(format!("the chunk at offset {}: {}; {skipped}", r.start, e.reason)))
            }
        }
    }
}

/// Reads the next message into `out`: returns 1, 0 at the end of the file,
/// RVC_MCAP_SKIPPED for a record skipped (reason in rvc_zenoh_last_error();
/// call again to go on), or a negative code when reading cannot go on.
#[no_mangle]
pub unsafe extern "C" fn rvc_mcap_next(reader: *mut rvc_mcap_reader, out: *mut rvc_mcap_message) -> c_int {
    guard(|| {
        // SAFETY: a handle from rvc_mcap_open, used by one thread at a time.
        let r = unsafe { reader.as_mut() }.ok_or_else(|| einval("reader handle is NULL"))?;
        let out = out_ptr(out, "out")?;
        loop {
            let step = match r.chunk_step(out) {
                Some(step) => step,
                None if r.cut.is_some() => return Err(eformat(r.cut.take().unwrap_or_default())),
                None if r.ended => return Ok(0),
                None => r.file_step(out)?,
            };
            match step {
                Step::Nothing => continue,
                Step::Message => return Ok(1),
                Step::Skipped(reason) => {
                    set_last_error(&reason);
                    return Ok(RVC_MCAP_SKIPPED);
                }
            }
        }
    })
}

#[no_mangle]
pub unsafe extern "C" fn rvc_mcap_close(reader: *mut rvc_mcap_reader) {
    if !reader.is_null() {
        // SAFETY: produced by Box::into_raw in rvc_mcap_open.
        guard_void(|| drop(unsafe { Box::from_raw(reader) }));
    }
}
