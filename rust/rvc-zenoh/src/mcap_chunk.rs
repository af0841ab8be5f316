//! A chunk's records, checked before any of them is read: its declared
//! uncompressed size against what its compressed bytes can hold and against
//! rvc's limit, then its CRC. Decompression itself is the `mcap` crate's (its
//! zstd and lz4 decoders), fed one chunk at a time; nothing is allocated from
//! a size the file declares before that size has been checked.

use crate::mcap_records::{self as rec, crc32};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

/// The most one chunk may hold uncompressed (a compressed chunk is
/// decompressed whole so that its CRC is checked before any message in it is
/// used). Writers cut chunks at a few MiB (rosbag2: 768 KiB, the mcap CLI:
/// 4 MiB); a larger chunk holds one very large message. docs/ros2-types.md.
pub const MAX_UNCOMPRESSED_CHUNK: u64 = 256 << 20;

/// A chunk's records, uncompressed: borrowed from the file when it was
/// stored uncompressed, else owned.
pub enum ChunkRecords {
    Mapped(&'static [u8]),
    Owned(Vec<u8>),
}

impl ChunkRecords {
    pub fn bytes(&self) -> &[u8] {
        match self {
            ChunkRecords::Mapped(b) => b,
            ChunkRecords::Owned(v) => v,
        }
    }

    /// The first `n` bytes only: the records before a damaged one.
    fn truncated(self, n: usize) -> ChunkRecords {
        match self {
            ChunkRecords::Mapped(b) => ChunkRecords::Mapped(&b[..n.min(b.len())]),
            ChunkRecords::Owned(mut v) => {
                v.truncate(n);
                ChunkRecords::Owned(v)
            }
        }
    }
}

/// A chunk's records that can be read: all of them, or (`damage`) those
/// before a record whose length is damaged, and why the rest is skipped.
pub struct Opened {
    pub records: ChunkRecords,
    pub damage: Option<String>,
}

/// Where the records' framing breaks: the offset of the first record whose
/// length runs past the records, and why. None when every length holds.
fn framing_break(records: &[u8]) -> Option<(usize, String)> {
    let mut pos = 0;
    loop {
        match rec::record_at(records, pos, "its records") {
            Ok(None) => return None,
            Ok(Some(r)) => pos = r.next,
            Err(e) => return Some((pos, e)),
        }
    }
}

/// Why a chunk is skipped, and how many messages it held if its records
/// could still be told apart (so later messages keep their index).
pub struct ChunkError {
    pub reason: String,
    pub messages: u64,
}

fn refuse(reason: String) -> ChunkError {
    ChunkError { reason, messages: 0 }
}

/// The records of the chunk whose record is `record` (opcode, length and body,
/// as in the file) and whose body is `body`.
///
/// A record whose length is damaged (it runs past the chunk's records) no
/// longer costs the valid records before it: they are read (as the `mcap`
/// readers read them) and the rest of the chunk is skipped, with the
/// record's offset. That holds also when the chunk's CRC fails, provided
/// the framing breaks: the damage is then located at that record. A chunk
/// whose CRC fails while every length holds is refused whole (the damage
/// could be in any of its messages).
pub fn open(record: &'static [u8], body: &'static [u8]) -> Result<Opened, ChunkError> {
    let c = rec::chunk(body).map_err(refuse)?;
    let size = c.uncompressed_size;
    let records = match c.compression {
        "" => {
            if size != c.records.len() as u64 {
                return Err(refuse(format!(
                    "it is stored uncompressed with {} bytes of records but claims {size} uncompressed",
                    c.records.len()
                )));
            }
            ChunkRecords::Mapped(c.records)
        }
        "zstd" | "lz4" => {
            let most = if c.compression == "zstd" { zstd_bound(c.records) } else { lz4_bound(c.records) };
            if size > most {
                return Err(refuse(format!(
                    "it claims {size} bytes uncompressed, its {} data ({} bytes) can hold at most {most}",
                    c.compression,
                    c.records.len()
                )));
            }
            if size > MAX_UNCOMPRESSED_CHUNK {
                return Err(refuse(format!(
                    "it claims {size} bytes uncompressed, over rvc's limit of {} MiB for one chunk",
                    MAX_UNCOMPRESSED_CHUNK >> 20
                )));
            }
            let (records, stopped) = decompress(record, size);
            if let Some(why) = stopped {
                // A record's length runs past the records (or past the chunk's
                // size): the complete records before it are kept, unchecked
                // by the CRC, which covers the whole chunk.
                if records.is_empty() || why.starts_with("its records cannot be decompressed") {
                    return Err(refuse(why));
                }
                let damage = format!("{why}: its records before that one are read, the rest skipped");
                return Ok(Opened { records: ChunkRecords::Owned(records), damage: Some(damage) });
            }
            if records.len() as u64 != size {
                return Err(refuse(format!("it claims {size} bytes uncompressed, its records hold {}", records.len())));
            }
            ChunkRecords::Owned(records)
        }
        other => return Err(refuse(format!("its compression '{other}' is not one rvc reads (zstd, lz4, none)"))),
    };
    let bytes = records.bytes();
    if c.uncompressed_crc != 0 {
        let crc = crc32(bytes);
        if crc != c.uncompressed_crc {
            let altered = format!(
                "the CRC of its records is {crc:#010x}, the chunk records {:#010x} (the chunk was altered)",
                c.uncompressed_crc
            );
            if let Some((at, why)) = framing_break(bytes) {
                if at > 0 {
                    let damage = format!("{altered}, at {why}: its records before that one are read, the rest skipped");
                    return Ok(Opened { records: records.truncated(at), damage: Some(damage) });
                }
            }
            return Err(ChunkError { reason: altered, messages: count_messages(bytes) });
        }
    }
    Ok(Opened { records, damage: None })
}

/// Messages among records that may be damaged: as far as their framing holds.
fn count_messages(records: &[u8]) -> u64 {
    let (mut pos, mut n) = (0, 0);
    while let Ok(Some(r)) = rec::record_at(records, pos, "") {
        n += (r.opcode == rec::OP_MESSAGE) as u64;
        pos = r.next;
    }
    n
}

/// Decompresses a chunk through the crate's streaming reader, given only
/// this chunk record: it allocates per record inside the chunk (each bounded
/// by `size`, already checked), and the records are gathered here as they
/// come, so memory grows with the output actually produced. Returns the
/// records read, and why reading stopped early if it did.
fn decompress(record: &[u8], size: u64) -> (Vec<u8>, Option<String>) {
    let limit = (size as usize).max(4096);
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_skip_end_magic(true)
            .with_record_length_limit(limit),
    );
    let mut out = Vec::new();
    let mut input = record;
    while let Some(event) = reader.next_event() {
        match event {
            Ok(LinearReadEvent::ReadRequest(need)) => {
                let n = need.min(input.len());
                reader.insert(n).copy_from_slice(&input[..n]);
                reader.notify_read(n);
                input = &input[n..];
            }
            Ok(LinearReadEvent::Record { opcode, data }) => {
                if (out.len() + 9 + data.len()) as u64 > size {
                    return (out, Some(format!("its records run past its uncompressed size {size}")));
                }
                out.push(opcode);
                out.extend_from_slice(&(data.len() as u64).to_le_bytes());
                out.extend_from_slice(data);
            }
            Err(mcap::McapError::RecordTooLarge { opcode, len }) => {
                let at = out.len();
                return (
                    out,
                    Some(format!(
                        "the {} record at offset {at} of its records claims {len} bytes, the chunk holds {size} uncompressed",
                        rec::op_name(opcode)
                    )),
                );
            }
            Err(e) => return (out, Some(format!("its records cannot be decompressed: {e}"))),
        }
    }
    (out, None)
}

/// The complete records at the start of the chunk whose record `cut` begins
/// and the end of the file cuts short (a recording that stopped while writing
/// it): what the old streaming reader gave, so nothing valid is lost. Its CRC
/// cannot be checked (it covers the whole chunk); lengths are bounded as in
/// `open`, by the bytes present.
pub fn salvage(cut: &'static [u8]) -> ChunkRecords {
    let mut f = rec::Fields::new(&cut[9.min(cut.len())..]);
    let header = (|| {
        f.u64("")?;
        f.u64("")?;
        let size = f.u64("")?;
        f.u32("")?;
        let compression = f.string("")?;
        f.u64("")?;
        Ok::<_, String>((size, compression, f.rest()))
    })();
    let Ok((size, compression, present)) = header else { return ChunkRecords::Owned(Vec::new()) };
    match compression {
        "" => {
            let mut end = 0;
            while let Ok(Some(r)) = rec::record_at(present, end, "") {
                end = r.next;
            }
            ChunkRecords::Mapped(&present[..end])
        }
        "zstd" | "lz4" => {
            let most = if compression == "zstd" { zstd_bound(present) } else { lz4_bound(present) };
            ChunkRecords::Owned(decompress(cut, size.min(most).min(MAX_UNCOMPRESSED_CHUNK)).0)
        }
        _ => ChunkRecords::Owned(Vec::new()),
    }
}

fn u32_at(d: &[u8], p: usize) -> Option<u32> {
    Some(u32::from_le_bytes(d.get(p..p.checked_add(4)?)?.try_into().ok()?))
}

/// A frame that decoders skip (zstd and lz4 share them): its length, if `p` starts one.
fn skippable_frame(d: &[u8], p: usize) -> Option<usize> {
    if u32_at(d, p)? & 0xFFFF_FFF0 != 0x184D_2A50 {
        return None;
    }
    Some(8 + u32_at(d, p + 4)? as usize)
}

/// The most bytes zstd frames can decode to, from their block headers
/// (RFC 8878): a raw or RLE block says its size, a compressed block decodes
/// to at most 128 KiB. Reading stops where the frames stop making sense: a
/// decoder fails there too, having produced no more than the sum so far.
pub fn zstd_bound(d: &[u8]) -> u64 {
    const MAX_BLOCK: u64 = 128 << 10;
    let (mut p, mut total) = (0usize, 0u64);
    'frames: loop {
        if let Some(skip) = skippable_frame(d, p) {
            p = p.saturating_add(skip);
            continue;
        }
        if u32_at(d, p) != Some(0xFD2F_B528) {
            return total;
        }
        p += 4; // u32_at checked that p + 4 fits
        let Some(&fhd) = d.get(p) else { return total };
        let single_segment = fhd & 0x20 != 0;
        let fcs = match fhd >> 6 {
            0 => single_segment as usize,
            1 => 2,
            2 => 4,
            _ => 8,
        };
        p = p.saturating_add(1 + (!single_segment) as usize + [0, 1, 2, 4][(fhd & 3) as usize] + fcs);
        loop {
            let Some(h) = p.checked_add(3).and_then(|e| d.get(p..e)) else { return total };
            let h = h[0] as u32 | (h[1] as u32) << 8 | (h[2] as u32) << 16;
            p += 3;
            let size = (h >> 3) as usize;
            let left = d.len().saturating_sub(p);
            match (h >> 1) & 3 {
                0 => {
                    total += size.min(left) as u64; // raw: a decoder may pass on part of a cut block
                    p = p.saturating_add(size);
                }
                1 => {
                    total += size as u64; // RLE: one byte, repeated `size` times
                    p = p.saturating_add(1);
                }
                2 => {
                    total += MAX_BLOCK;
                    p = p.saturating_add(size);
                }
                _ => return total,
            }
            if h & 1 != 0 {
                break;
            }
        }
        if fhd & 4 != 0 {
            p = p.saturating_add(4); // content checksum
        }
        if p >= d.len() {
            break 'frames;
        }
    }
    total
}

/// The same for lz4 frames: an uncompressed block says its size, a
/// compressed one decodes to at most the frame's block maximum.
pub fn lz4_bound(d: &[u8]) -> u64 {
    let (mut p, mut total) = (0usize, 0u64);
    loop {
        if let Some(skip) = skippable_frame(d, p) {
            p = p.saturating_add(skip);
            continue;
        }
        if u32_at(d, p) != Some(0x184D_2204) {
            return total;
        }
        let (Some(&flg), Some(&bd)) = (d.get(p.saturating_add(4)), d.get(p.saturating_add(5))) else { return total };
        let max_block: u64 = match (bd >> 4) & 7 {
            4 => 64 << 10,
            5 => 256 << 10,
            6 => 1 << 20,
            7 => 4 << 20,
            _ => return total,
        };
        p = p.saturating_add(6 + if flg & 8 != 0 { 8 } else { 0 } + if flg & 1 != 0 { 4 } else { 0 } + 1);
        loop {
            let Some(word) = u32_at(d, p) else { return total };
            p += 4; // u32_at checked that p + 4 fits
            if word == 0 {
                break; // end mark
            }
            let size = (word & 0x7FFF_FFFF) as usize;
            if word & 0x8000_0000 != 0 {
                total += size.min(d.len().saturating_sub(p)) as u64;
            } else {
                total += max_block;
            }
            p = p.saturating_add(size).saturating_add(if flg & 0x10 != 0 { 4 } else { 0 });
        }
        if flg & 4 != 0 {
            p = p.saturating_add(4);
        }
        if p >= d.len() {
            return total;
        }
    }
}
