//! The ULog container (PX4 "ULog File Format"): a 16-byte header (magic `ULog` 01 12
//! 35, version byte, start timestamp u64 µs), then messages of `u16 size, u8 type,
//! payload`, little-endian:
//!
//! - definitions: `B` flag bits (compat/incompat flags, 3 appended-data offsets), `F`
//!   formats (`name:type field;...`, nested types, arrays `t[n]`, `_padding` fields),
//!   `I` info, `M` multi-info, `P` parameters, `Q` default parameters;
//! - data: `A` add-logged (multi_id, msg_id, topic), `R` remove, `D` data (msg_id,
//!   the topic's fields packed), `L` / `C` log strings, `S` sync, `O` dropout (ms).
//!
//! The whole file is read into memory; data messages are kept as byte offsets and
//! decoded on demand by field name ([`Topic`]). A message cut by the end of the file
//! (a log cut mid-write) is dropped with a warning; every other damage is an error
//! naming the byte offset of the message. Unknown message types are skipped (the
//! specification's forward compatibility), but a type byte that is not an ASCII
//! letter means a corrupted size before it and is an error.

use std::collections::HashMap;
use std::fmt;

/// The ULog magic, the first 7 bytes of a file.
pub const MAGIC: [u8; 7] = [b'U', b'L', b'o', b'g', 0x01, 0x12, 0x35];

/// A damaged ULog file: what and where (byte offset from the start of the file).
#[derive(Clone, Debug, PartialEq)]
pub struct UlogError {
    pub offset: usize,
    pub message: String,
}

impl fmt::Display for UlogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "byte {}: {}", self.offset, self.message)
    }
}

fn err<T>(offset: usize, message: impl Into<String>) -> Result<T, UlogError> {
    Err(UlogError {
        offset,
        message: message.into(),
    })
}

/// A scalar type of a format field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    Bool,
    Char,
}

impl Scalar {
    fn of(name: &str) -> Option<Scalar> {
        Some(match name {
            "int8_t" => Scalar::I8,
            "uint8_t" => Scalar::U8,
            "int16_t" => Scalar::I16,
            "uint16_t" => Scalar::U16,
            "int32_t" => Scalar::I32,
            "uint32_t" => Scalar::U32,
            "int64_t" => Scalar::I64,
            "uint64_t" => Scalar::U64,
            "float" => Scalar::F32,
            "double" => Scalar::F64,
            "bool" => Scalar::Bool,
            "char" => Scalar::Char,
            _ => return None,
        })
    }

    pub fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 | Scalar::Bool | Scalar::Char => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// The value at the start of `b` (at least `size()` bytes) as f64.
    fn read(self, b: &[u8]) -> f64 {
        let a = |n: usize| -> [u8; 8] {
            let mut x = [0u8; 8];
            x[..n].copy_from_slice(&b[..n]);
            x
        };
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 | Scalar::Bool | Scalar::Char => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::I64 => i64::from_le_bytes(a(8)) as f64,
            Scalar::U64 => u64::from_le_bytes(a(8)) as f64,
            Scalar::F64 => f64::from_le_bytes(a(8)),
        }
    }
}

/// One field of a format as written: type name, array length (None: not an array).
#[derive(Clone, Debug, PartialEq)]
struct RawField {
    type_name: String,
    array: Option<usize>,
    name: String,
}

/// A flattened scalar field of a topic: `gyro_rad[0]`, `nested.field`.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: String,
    pub scalar: Scalar,
    /// Byte offset inside the data payload after msg_id.
    pub offset: usize,
}

/// A subscription (`A`): a topic instance.
#[derive(Clone, Debug, PartialEq)]
pub struct Subscription {
    pub name: String,
    pub multi_id: u8,
    /// Payload offsets (after the msg_id) of its data messages, in file order.
    pub records: Vec<usize>,
}

/// A parsed ULog file.
#[derive(Clone, Debug, Default)]
pub struct Ulog {
    pub bytes: Vec<u8>,
    pub version: u8,
    /// The header's timestamp \[µs since boot\].
    pub start_us: u64,
    formats: HashMap<String, Vec<RawField>>,
    /// Flattened layouts and the bytes a record needs, per format name.
    layouts: HashMap<String, (Vec<Field>, usize)>,
    /// Subscriptions by msg_id.
    pub subscriptions: HashMap<u16, Subscription>,
    /// Subscriptions whose msg_id a later `A` message took over, with their records.
    pub retired: Vec<Subscription>,
    /// `I` info strings (char arrays) and other info values as text.
    pub info: HashMap<String, String>,
    /// `P` parameters (last value).
    pub params: HashMap<String, f64>,
    /// Counts per message type.
    pub counts: HashMap<u8, usize>,
    /// Dropouts: count and total duration \[ms\].
    pub dropouts: (usize, u64),
    /// `L` / `C` log strings (timestamp µs, text).
    pub log_messages: Vec<(u64, String)>,
    /// Damage that did not stop the read (a message cut by the end of the file).
    pub warnings: Vec<String>,
}

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}

fn u64_at(b: &[u8], i: usize) -> u64 {
    let mut x = [0u8; 8];
    x.copy_from_slice(&b[i..i + 8]);
    u64::from_le_bytes(x)
}

/// Parse `type_name:type field;...` into its name and fields.
fn parse_format(text: &str, at: usize) -> Result<(String, Vec<RawField>), UlogError> {
    let Some((name, rest)) = text.split_once(':') else {
        return err(at, format!("format {text:?}: no ':' after the name"));
    };
    let mut fields = Vec::new();
    for f in rest.split(';').filter(|f| !f.trim().is_empty()) {
        let Some((ty, fname)) = f.trim().split_once(' ') else {
            return err(
                at,
                format!("format {name}: field {f:?} is not \"type name\""),
            );
        };
        let (type_name, array) = match ty.split_once('[') {
            Some((t, n)) => {
                let n = n.strip_suffix(']').and_then(|n| n.parse::<usize>().ok());
                match n {
                    Some(n) if n <= 65535 => (t.to_string(), Some(n)),
                    _ => return err(at, format!("format {name}: bad array type {ty:?}")),
                }
            }
            None => (ty.to_string(), None),
        };
        fields.push(RawField {
            type_name,
            array,
            name: fname.trim().to_string(),
        });
    }
    Ok((name.to_string(), fields))
}

impl Ulog {
    /// Parse a whole file; see the module documentation.
    pub fn parse(bytes: Vec<u8>) -> Result<Ulog, UlogError> {
        if bytes.len() < 16 {
            if bytes.len() >= 7 && bytes[..7] != MAGIC {
                return err(0, "not a ULog file (no 'ULog' magic)");
            }
            return err(
                0,
                format!(
                    "{} bytes: shorter than the 16-byte ULog header",
                    bytes.len()
                ),
            );
        }
        if bytes[..7] != MAGIC {
            return err(0, "not a ULog file (no 'ULog' magic 55 4c 6f 67 01 12 35)");
        }
        let mut u = Ulog {
            version: bytes[7],
            start_us: u64_at(&bytes, 8),
            ..Ulog::default()
        };
        let mut appended: Vec<usize> = Vec::new();
        let mut pos = 16;
        let n = bytes.len();
        let mut in_definitions = true;
        while pos < n {
            if n - pos < 3 {
                u.warnings.push(format!(
                    "byte {pos}: {} bytes left, cut before a message header: dropped",
                    n - pos
                ));
                break;
            }
            let size = u16_at(&bytes, pos) as usize;
            let ty = bytes[pos + 2];
            let start = pos + 3;
            let end = start + size;
            // A message crossing the start of appended data: the main part was cut
            // there; go on at the appended data.
            if let Some(&a) = appended.iter().find(|&&a| a > pos && a < end) {
                u.warnings.push(format!(
                    "byte {pos}: message cut by the appended data at byte {a}: dropped"
                ));
                pos = a;
                continue;
            }
            if end > n {
                u.warnings.push(format!(
                    "byte {pos}: last message (type '{}', {size} bytes) cut by the end of the \
                     file at byte {n}: dropped",
                    ty as char
                ));
                break;
            }
            if !ty.is_ascii_alphabetic() {
                return err(
                    pos,
                    format!(
                        "message type byte 0x{ty:02x} is not a ULog message type (a corrupted \
                         message size before it?)"
                    ),
                );
            }
            let p = &bytes[start..end];
            *u.counts.entry(ty).or_insert(0) += 1;
            match ty {
                b'B' => {
                    if !in_definitions || pos != 16 {
                        // Only valid as the first message; ignored elsewhere.
                    } else if p.len() >= 40 {
                        let incompat = p[8];
                        if incompat & !1 != 0 || p[9..16].iter().any(|&b| b != 0) {
                            return err(
                                pos,
                                "flag bits: unknown incompatible flags set (a newer ULog \
                                 version this reader cannot read)",
                            );
                        }
                        if incompat & 1 != 0 {
                            for k in 0..3 {
                                let a = u64_at(p, 16 + 8 * k);
                                if a != 0 {
                                    if a as usize <= end || a > n as u64 {
                                        u.warnings.push(format!(
                                            "byte {pos}: appended-data offset {a} outside the \
                                             file's data: ignored"
                                        ));
                                    } else {
                                        appended.push(a as usize);
                                    }
                                }
                            }
                        }
                    } else {
                        return err(
                            pos,
                            format!("flag bits message of {size} bytes: expected 40"),
                        );
                    }
                }
                b'F' => {
                    let text = String::from_utf8_lossy(p);
                    let (name, fields) = parse_format(&text, pos)?;
                    u.formats.insert(name, fields);
                }
                b'I' | b'M' | b'P' | b'Q' => {
                    let skip = match ty {
                        b'M' | b'Q' => 1,
                        _ => 0,
                    };
                    if p.len() < skip + 1 || p.len() < skip + 1 + p[skip] as usize {
                        return err(
                            pos,
                            format!("'{}' message: key longer than the message", ty as char),
                        );
                    }
                    let kl = p[skip] as usize;
                    let key = String::from_utf8_lossy(&p[skip + 1..skip + 1 + kl]).to_string();
                    let value = &p[skip + 1 + kl..];
                    let Some((tyname, kname)) = key.split_once(' ') else {
                        return err(
                            pos,
                            format!("'{}' message: key {key:?} is not \"type name\"", ty as char),
                        );
                    };
                    let kname = kname.to_string();
                    if tyname.starts_with("char[") {
                        let s = String::from_utf8_lossy(value)
                            .trim_end_matches('\0')
                            .to_string();
                        if ty == b'I' {
                            u.info.insert(kname, s);
                        }
                    } else if let Some(sc) = Scalar::of(tyname) {
                        if value.len() >= sc.size() {
                            let v = sc.read(value);
                            match ty {
                                b'P' => {
                                    u.params.insert(kname, v);
                                }
                                b'I' => {
                                    u.info.insert(kname, v.to_string());
                                }
                                _ => {}
                            }
                        }
                    }
                }
                b'A' => {
                    in_definitions = false;
                    if p.len() < 3 {
                        return err(pos, "add-logged message shorter than 3 bytes");
                    }
                    let multi_id = p[0];
                    let msg_id = u16_at(p, 1);
                    let name = String::from_utf8_lossy(&p[3..]).to_string();
                    if !u.formats.contains_key(&name) {
                        return err(
                            pos,
                            format!("add-logged topic {name:?}: no format 'F' for it"),
                        );
                    }
                    u.layout(&name, pos)?;
                    let old = u.subscriptions.insert(
                        msg_id,
                        Subscription {
                            name,
                            multi_id,
                            records: Vec::new(),
                        },
                    );
                    // A msg_id used again: the earlier topic keeps its records.
                    u.retired.extend(old.filter(|o| !o.records.is_empty()));
                }
                b'R' => {}
                b'D' => {
                    if p.len() < 2 {
                        return err(pos, "data message shorter than its msg_id");
                    }
                    let msg_id = u16_at(p, 0);
                    let Some(sub) = u.subscriptions.get(&msg_id) else {
                        return err(
                            pos,
                            format!("data message for msg_id {msg_id}, which no 'A' message added"),
                        );
                    };
                    let need = u.layouts[&sub.name].1;
                    if p.len() - 2 < need {
                        return err(
                            pos,
                            format!(
                                "data message of {} bytes for {} (msg_id {msg_id}): its format needs {need}",
                                p.len() - 2,
                                sub.name
                            ),
                        );
                    }
                    u.subscriptions
                        .get_mut(&msg_id)
                        .expect("checked above")
                        .records
                        .push(start + 2);
                }
                b'L' | b'C' => {
                    let (h, tsat) = if ty == b'L' { (9, 1) } else { (11, 3) };
                    if p.len() >= h {
                        let ts = u64_at(p, tsat);
                        let s = String::from_utf8_lossy(&p[h..]).to_string();
                        u.log_messages.push((ts, s));
                    }
                }
                b'O' if p.len() >= 2 => {
                    u.dropouts.0 += 1;
                    u.dropouts.1 += u16_at(p, 0) as u64;
                }
                _ => {} // 'S' sync and unknown types.
            }
            pos = end;
        }
        u.bytes = bytes;
        Ok(u)
    }

    /// The flattened scalar fields and payload size of format `name`.
    fn layout(&mut self, name: &str, at: usize) -> Result<(), UlogError> {
        if self.layouts.contains_key(name) {
            return Ok(());
        }
        let mut fields = Vec::new();
        self.flatten(name, "", 0, &mut fields, 0, at)?;
        // Trailing `_padding` is not logged: a record needs the bytes up to the end
        // of its last real field.
        let size = fields
            .iter()
            .map(|f| f.offset + f.scalar.size())
            .max()
            .unwrap_or(0);
        self.layouts.insert(name.to_string(), (fields, size));
        Ok(())
    }

    fn flatten(
        &self,
        name: &str,
        prefix: &str,
        base: usize,
        out: &mut Vec<Field>,
        depth: usize,
        at: usize,
    ) -> Result<usize, UlogError> {
        if depth > 16 {
            return err(
                at,
                format!("format {name}: nested more than 16 deep (a cycle?)"),
            );
        }
        let Some(raw) = self.formats.get(name) else {
            return err(at, format!("type {name:?}: no format 'F' for it"));
        };
        let mut off = base;
        for f in raw {
            let padding = f.name.starts_with("_padding");
            let count = f.array.unwrap_or(1);
            for i in 0..count {
                let fname = match f.array {
                    Some(_) => format!("{prefix}{}[{i}]", f.name),
                    None => format!("{prefix}{}", f.name),
                };
                match Scalar::of(&f.type_name) {
                    Some(sc) => {
                        if !padding {
                            out.push(Field {
                                name: fname,
                                scalar: sc,
                                offset: off,
                            });
                        }
                        off += sc.size();
                    }
                    None => {
                        let p = format!("{fname}.");
                        let before = off;
                        off = self.flatten(&f.type_name, &p, off, out, depth + 1, at)?;
                        // Each element must take bytes, so the size guard below
                        // bounds the work (an empty type in an array would not).
                        if off == before {
                            return err(
                                at,
                                format!(
                                    "format {name}: field {} of type {} has no bytes",
                                    f.name, f.type_name
                                ),
                            );
                        }
                    }
                }
                if off > 1 << 20 {
                    return err(at, format!("format {name}: larger than 1 MiB"));
                }
            }
        }
        Ok(off)
    }

    /// Topic `name`, instance `multi_id`, if logged.
    pub fn topic(&self, name: &str, multi_id: u8) -> Option<Topic<'_>> {
        let mut subs: Vec<&Subscription> = self
            .subscriptions
            .values()
            .chain(&self.retired)
            .filter(|s| s.name == name && s.multi_id == multi_id)
            .collect();
        if subs.is_empty() {
            return None;
        }
        // A topic re-added under another msg_id: all its records in file order.
        let mut records: Vec<usize> = subs.iter_mut().flat_map(|s| s.records.clone()).collect();
        records.sort_unstable();
        let (fields, _) = &self.layouts[name];
        Some(Topic {
            log: self,
            name: name.to_string(),
            fields,
            records,
        })
    }

    /// (topic, multi_id, records) of every subscription, sorted by name.
    pub fn topic_counts(&self) -> Vec<(String, u8, usize)> {
        let mut v: Vec<_> = self
            .subscriptions
            .values()
            .chain(&self.retired)
            .map(|s| (s.name.clone(), s.multi_id, s.records.len()))
            .collect();
        v.sort();
        v
    }
}

/// One topic instance's data messages, decoded by field name.
pub struct Topic<'a> {
    log: &'a Ulog,
    pub name: String,
    fields: &'a [Field],
    /// Payload offsets of its records.
    pub records: Vec<usize>,
}

impl Topic<'_> {
    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The field called `name`, if the format has it.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// Whether the format has a field `name`.
    pub fn has(&self, name: &str) -> bool {
        self.field(name).is_some()
    }

    /// Field `f` of record `k` as f64.
    pub fn value(&self, k: usize, f: &Field) -> f64 {
        let at = self.records[k] + f.offset;
        f.scalar.read(&self.log.bytes[at..at + f.scalar.size()])
    }

    /// The u64 `timestamp` of record `k` exactly \[µs\] (every topic starts with it).
    pub fn timestamp_us(&self, k: usize) -> Option<u64> {
        let f = self.field("timestamp")?;
        let at = self.records[k] + f.offset;
        (f.scalar == Scalar::U64).then(|| u64_at(&self.log.bytes, at))
    }

    /// The file offset of record `k`'s message (for error messages).
    pub fn message_offset(&self, k: usize) -> usize {
        self.records[k] - 5
    }
}
