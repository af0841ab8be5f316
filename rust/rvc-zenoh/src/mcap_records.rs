//! MCAP record framing and the few record bodies rvc reads (schema, channel,
//! message, chunk, data end), parsed here rather than by the `mcap` crate so
//! that every length a file declares is checked against the bytes actually
//! there before anything is allocated or sliced: the crate's streaming reader
//! allocates a declared record length up front (a 248-byte file claiming a
//! 64 GiB record aborted rvc) and reserves declared string lengths.
//!
//! Everything borrows from the bytes it is given; errors say which field
//! claims what and how much is left, and the caller adds the record's offset.

/// The 8 bytes an MCAP file starts (and ends) with.
pub const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

pub const OP_HEADER: u8 = 0x01;
pub const OP_FOOTER: u8 = 0x02;
pub const OP_SCHEMA: u8 = 0x03;
pub const OP_CHANNEL: u8 = 0x04;
pub const OP_MESSAGE: u8 = 0x05;
pub const OP_CHUNK: u8 = 0x06;
pub const OP_DATA_END: u8 = 0x0F;

/// One record: where it starts (its opcode byte), its body, where the next one starts.
pub struct Record<'a> {
    pub opcode: u8,
    pub start: usize,
    pub body: &'a [u8],
    pub next: usize,
}

pub fn op_name(op: u8) -> &'static str {
    match op {
        OP_HEADER => "header",
        OP_FOOTER => "footer",
        OP_SCHEMA => "schema",
        OP_CHANNEL => "channel",
        OP_MESSAGE => "message",
        OP_CHUNK => "chunk",
        0x07 => "message index",
        0x08 => "chunk index",
        0x09 => "attachment",
        0x0A => "attachment index",
        0x0B => "statistics",
        0x0C => "metadata",
        0x0D => "metadata index",
        0x0E => "summary offset",
        OP_DATA_END => "data end",
        _ => "unknown",
    }
}

/// The record at `pos` of `data` (`None` at the end). `what` names `data` in
/// errors ("the file", "the chunk's records"); the caller adds the offsets'
/// origin. A length larger than what is left is an error, never a read.
pub fn record_at<'a>(data: &'a [u8], pos: usize, what: &str) -> Result<Option<Record<'a>>, String> {
    let left = data.len() - pos;
    if left == 0 {
        return Ok(None);
    }
    if left < 9 {
        return Err(format!(
            "{what} ends {left} byte{} into the record at offset {pos} (its opcode and length take 9)",
            if left == 1 { "" } else { "s" }
        ));
    }
    let opcode = data[pos];
    let len = u64::from_le_bytes(data[pos + 1..pos + 9].try_into().unwrap());
    if len > (left - 9) as u64 {
        return Err(format!(
            "the {} record at offset {pos} claims {len} bytes, {what} has {} left",
            op_name(opcode),
            left - 9
        ));
    }
    let end = pos + 9 + len as usize;
    Ok(Some(Record { opcode, start: pos, body: &data[pos + 9..end], next: end }))
}

/// Little-endian fields read one after the other from a record body.
pub struct Fields<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Fields<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Fields { data, pos: 0 }
    }
    fn left(&self) -> usize {
        self.data.len() - self.pos
    }
    pub fn bytes(&mut self, n: u64, field: &str) -> Result<&'a [u8], String> {
        if n > self.left() as u64 {
            return Err(format!("its {field} claims {n} bytes, the record has {} left", self.left()));
        }
        let s = &self.data[self.pos..self.pos + n as usize];
        self.pos += n as usize;
        Ok(s)
    }
    fn fixed<const N: usize>(&mut self, field: &str) -> Result<[u8; N], String> {
        if self.left() < N {
            return Err(format!("the record ends inside its {field}"));
        }
        Ok(self.bytes(N as u64, field)?.try_into().unwrap())
    }
    pub fn u16(&mut self, field: &str) -> Result<u16, String> {
        Ok(u16::from_le_bytes(self.fixed(field)?))
    }
    pub fn u32(&mut self, field: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.fixed(field)?))
    }
    pub fn u64(&mut self, field: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.fixed(field)?))
    }
    /// Bytes after a 4-byte length.
    pub fn prefixed(&mut self, field: &str) -> Result<&'a [u8], String> {
        let n = self.u32(field)?;
        self.bytes(n.into(), field)
    }
    pub fn string(&mut self, field: &str) -> Result<&'a str, String> {
        std::str::from_utf8(self.prefixed(field)?).map_err(|_| format!("its {field} is not UTF-8"))
    }
    pub fn rest(&mut self) -> &'a [u8] {
        let s = &self.data[self.pos..];
        self.pos = self.data.len();
        s
    }
}

pub struct Schema<'a> {
    pub id: u16,
    pub name: &'a str,
    pub encoding: &'a str,
    pub data: &'a [u8],
}

pub fn schema(body: &[u8]) -> Result<Schema<'_>, String> {
    let mut f = Fields::new(body);
    Ok(Schema {
        id: f.u16("id")?,
        name: f.string("name")?,
        encoding: f.string("encoding")?,
        data: f.prefixed("data")?,
    })
}

pub struct Channel<'a> {
    pub id: u16,
    pub schema_id: u16,
    pub topic: &'a str,
    pub message_encoding: &'a str,
}

pub fn channel(body: &[u8]) -> Result<Channel<'_>, String> {
    let mut f = Fields::new(body);
    let c = Channel {
        id: f.u16("id")?,
        schema_id: f.u16("schema id")?,
        topic: f.string("topic")?,
        message_encoding: f.string("message encoding")?,
    };
    f.prefixed("metadata")?; // not used, but its length must fit like the others'
    Ok(c)
}

pub struct Message<'a> {
    pub channel_id: u16,
    pub sequence: u32,
    pub log_time: u64,
    pub publish_time: u64,
    pub data: &'a [u8],
}

pub fn message(body: &[u8]) -> Result<Message<'_>, String> {
    let mut f = Fields::new(body);
    Ok(Message {
        channel_id: f.u16("channel id")?,
        sequence: f.u32("sequence")?,
        log_time: f.u64("log time")?,
        publish_time: f.u64("publish time")?,
        data: f.rest(),
    })
}

pub struct Chunk<'a> {
    pub uncompressed_size: u64,
    pub uncompressed_crc: u32,
    pub compression: &'a str,
    pub records: &'a [u8],
}

pub fn chunk(body: &[u8]) -> Result<Chunk<'_>, String> {
    let mut f = Fields::new(body);
    f.u64("start time")?;
    f.u64("end time")?;
    let uncompressed_size = f.u64("uncompressed size")?;
    let uncompressed_crc = f.u32("uncompressed CRC")?;
    let compression = f.string("compression")?;
    let n = f.u64("records length")?;
    let records = f.bytes(n, "records")?;
    Ok(Chunk { uncompressed_size, uncompressed_crc, compression, records })
}

/// The data end record: the CRC of everything before it (0: not computed).
pub fn data_end_crc(body: &[u8]) -> Result<u32, String> {
    Fields::new(body).u32("data section CRC")
}

/// CRC-32 (IEEE, as zlib and MCAP compute it), eight bytes per step.
pub struct Crc32(u32);

const fn crc_tables() -> [[u32; 256]; 8] {
    let mut t = [[0u32; 256]; 8];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            k += 1;
        }
        t[0][i] = c;
        i += 1;
    }
    let mut i = 0;
    while i < 256 {
        let mut s = 1;
        while s < 8 {
            t[s][i] = (t[s - 1][i] >> 8) ^ t[0][(t[s - 1][i] & 0xff) as usize];
            s += 1;
        }
        i += 1;
    }
    t
}

static CRC_TABLES: [[u32; 256]; 8] = crc_tables();

impl Crc32 {
    pub fn new() -> Self {
        Crc32(!0)
    }
    pub fn update(&mut self, data: &[u8]) {
        let t = &CRC_TABLES;
        let mut c = self.0;
        let mut words = data.chunks_exact(8);
        for w in &mut words {
            let lo = c ^ u32::from_le_bytes(w[0..4].try_into().unwrap());
            let hi = u32::from_le_bytes(w[4..8].try_into().unwrap());
            c = t[7][(lo & 0xff) as usize]
                ^ t[6][((lo >> 8) & 0xff) as usize]
                ^ t[5][((lo >> 16) & 0xff) as usize]
                ^ t[4][(lo >> 24) as usize]
                ^ t[3][(hi & 0xff) as usize]
                ^ t[2][((hi >> 8) & 0xff) as usize]
                ^ t[1][((hi >> 16) & 0xff) as usize]
                ^ t[0][(hi >> 24) as usize];
        }
        for &b in words.remainder() {
            c = t[0][((c ^ b as u32) & 0xff) as usize] ^ (c >> 8);
        }
        self.0 = c;
    }
    pub fn value(&self) -> u32 {
        !self.0
    }
}

pub fn crc32(data: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(data);
    c.value()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926); // the catalogued check value of CRC-32/ISO-HDLC
        let mut c = Crc32::new();
        c.update(b"1234");
        c.update(b"56789");
        assert_eq!(c.value(), 0xCBF4_3926);
    }

    #[test]
    fn lengths_past_the_end_are_errors() {
        let mut rec = vec![OP_CHUNK];
        rec.extend_from_slice(&(64u64 << 30).to_le_bytes());
        rec.extend_from_slice(&[0; 20]);
        let e = record_at(&rec, 0, "the file").err().unwrap();
        assert_eq!(e, "the chunk record at offset 0 claims 68719476736 bytes, the file has 20 left");
        let mut body = 7u16.to_le_bytes().to_vec();
        body.extend_from_slice(&u32::MAX.to_le_bytes());
        assert_eq!(schema(&body).err().unwrap(), "its name claims 4294967295 bytes, the record has 0 left");
    }
}
