//! Compact RINEX (Hatanaka) 1.0 and 3.0 expanded to RINEX 2 / 3 text on the fly, so
//! the observation readers read a `.crx` / `.d` file (also gzipped) as they read the
//! plain file. Format as described by Hatanaka (2008), "A Compression Format and
//! Tools for GNSS Observation Data", Bulletin of the GSI 55, and the RNXCMP
//! documentation ("CRINEX 3.0"):
//!
//! - header: `CRINEX VERS / TYPE` (1.0: RINEX 2, 3.0: RINEX 3/4), `CRINEX PROG /
//!   DATE`, then the RINEX header unchanged;
//! - epoch line: text difference against the previous one (a blank keeps the old
//!   character, `&` writes a blank, any other character replaces it); a line starting
//!   with `>` (3.0) or `&` (1.0) starts afresh. The satellites follow the epoch
//!   fields without a break (column 42 in 3.0, column 33 in 1.0, all of them on one
//!   line), the clock offset is on the next line;
//! - clock line and each observation: an integer (value x 1000, clock x 1e12 in 3.0,
//!   x 1e9 in 1.0). `M&V` starts an arc of difference order M with value V; a plain
//!   integer is the min(n, M)-th difference, n the values since the arc started; an
//!   empty field is a blank observation (the arc ends);
//! - per satellite one line: its types' fields separated by one blank, then the LLI
//!   and SSI characters of all types as a text difference against the satellite's
//!   previous flags;
//! - event epochs (flags 2-5) are written as in RINEX, their records verbatim.
//!
//! Errors are `std::io::Error`s (InvalidData) naming the Compact RINEX line and the
//! satellite and observation.

use std::collections::HashMap;
use std::io::{self, BufRead, Read};

/// Highest difference order accepted (RNX2CRX writes 3).
const MAX_ORDER: usize = 9;

/// One arc of differences: `d[0]` the last value, `d[j]` its j-th difference.
#[derive(Clone, Copy, Debug)]
struct Arc {
    order: usize,
    seen: usize,
    d: [i64; MAX_ORDER + 1],
}

impl Arc {
    fn start(order: usize, v: i64) -> Arc {
        let mut d = [0; MAX_ORDER + 1];
        d[0] = v;
        Arc { order, seen: 0, d }
    }

    /// Add the next difference; returns the value.
    fn next(&mut self, v: i64) -> Option<i64> {
        let m = (self.seen + 1).min(self.order);
        self.seen = m;
        *self.d.get_mut(m)? = v;
        for j in (0..m).rev() {
            self.d[j] = self.d[j].checked_add(self.d[j + 1])?;
        }
        Some(self.d[0])
    }
}

#[derive(Default)]
struct SatState {
    arcs: Vec<Option<Arc>>,
    flags: Vec<u8>,
}

/// Apply a Compact RINEX text difference to `old`.
fn text_diff(old: &mut Vec<u8>, new: &[u8]) {
    if old.len() < new.len() {
        old.resize(new.len(), b' ');
    }
    for (o, &c) in old.iter_mut().zip(new) {
        match c {
            b' ' => {}
            b'&' => *o = b' ',
            c => *o = c,
        }
    }
}

/// An F14.3 field (or F15.12 / F12.9 for the clock) from a scaled integer.
fn push_scaled(out: &mut Vec<u8>, v: i64, decimals: u32, width: usize) {
    let scale = 10i64.pow(decimals);
    let a = v.unsigned_abs();
    let s = format!(
        "{}{}.{:0w$}",
        if v < 0 { "-" } else { "" },
        a / scale as u64,
        a % scale as u64,
        w = decimals as usize
    );
    out.extend(std::iter::repeat_n(b' ', width.saturating_sub(s.len())));
    out.extend_from_slice(s.as_bytes());
}

/// Expands a Compact RINEX stream into RINEX text.
pub(super) struct CrxDecoder<R: BufRead> {
    inner: R,
    /// 1 (CRINEX 1.0, RINEX 2) or 3 (CRINEX 3.0).
    version: u8,
    crx_line: usize,
    in_header: bool,
    line: Vec<u8>,
    out: Vec<u8>,
    pos: usize,
    epoch: Vec<u8>,
    clock: Option<Arc>,
    sats: HashMap<[u8; 3], SatState>,
    /// Number of observation types per system letter (RINEX 2: key b' ', all).
    types: Vec<(u8, usize)>,
    current_sys: u8,
}

fn bad(line: usize, msg: impl std::fmt::Display) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("Compact RINEX line {line}: {msg}"),
    )
}

impl<R: BufRead> CrxDecoder<R> {
    pub(super) fn new(inner: R) -> Self {
        CrxDecoder {
            inner,
            version: 0,
            crx_line: 0,
            in_header: true,
            line: Vec::new(),
            out: Vec::new(),
            pos: 0,
            epoch: Vec::new(),
            clock: None,
            sats: HashMap::new(),
            types: Vec::new(),
            current_sys: b' ',
        }
    }

    /// Read the next Compact RINEX line into `self.line`; false at the end.
    fn read_line(&mut self) -> io::Result<bool> {
        self.line.clear();
        let limit = crate::fmt::MAX_LINE_BYTES as u64 + 3;
        let n = (&mut self.inner)
            .take(limit)
            .read_until(b'\n', &mut self.line)?;
        if n == 0 {
            return Ok(false);
        }
        self.crx_line += 1;
        while matches!(self.line.last(), Some(b'\n' | b'\r')) {
            self.line.pop();
        }
        Ok(true)
    }

    fn need_line(&mut self, what: &str) -> io::Result<()> {
        if self.read_line()? {
            Ok(())
        } else {
            Err(bad(
                self.crx_line,
                format!("the file ends where {what} was expected"),
            ))
        }
    }

    fn header_line(&mut self) -> io::Result<()> {
        let label = String::from_utf8_lossy(self.line.get(60..).unwrap_or(&[]))
            .trim()
            .to_string();
        if self.crx_line == 1 {
            if label != "CRINEX VERS   / TYPE" {
                return Err(bad(1, "expected 'CRINEX VERS   / TYPE'"));
            }
            let v = String::from_utf8_lossy(self.line.get(..9).unwrap_or(&[]))
                .trim()
                .to_string();
            self.version = match v.as_str() {
                "1.0" => 1,
                "3.0" => 3,
                _ => return Err(bad(1, format!("CRINEX version {v} (1.0 and 3.0 are read)"))),
            };
            return Ok(());
        }
        if self.crx_line == 2 {
            return Ok(()); // CRINEX PROG / DATE
        }
        let num = |a: usize, b: usize, l: &[u8]| -> Option<usize> {
            String::from_utf8_lossy(l.get(a..b.min(l.len()))?)
                .trim()
                .parse()
                .ok()
        };
        if label == "SYS / # / OBS TYPES" {
            let sys = self.line.first().copied().unwrap_or(b' ');
            if sys != b' ' {
                self.current_sys = sys;
                let n = num(3, 6, &self.line)
                    .ok_or_else(|| bad(self.crx_line, "SYS / # / OBS TYPES: no count"))?;
                self.types.retain(|(s, _)| *s != sys);
                self.types.push((sys, n));
            }
        } else if label == "# / TYPES OF OBSERV" {
            if let Some(n) = num(0, 6, &self.line) {
                self.types = vec![(b' ', n)];
            }
        } else if label == "END OF HEADER" {
            self.in_header = false;
        }
        self.out.extend_from_slice(&self.line);
        self.out.push(b'\n');
        Ok(())
    }

    fn n_types(&self, sys: u8) -> Option<usize> {
        let key = if self.version == 1 { b' ' } else { sys };
        self.types.iter().find(|(s, _)| *s == key).map(|(_, n)| *n)
    }

    /// Decode one epoch (or header line) into `self.out`; false at the end.
    fn decode_next(&mut self) -> io::Result<bool> {
        if !self.read_line()? {
            return Ok(false);
        }
        if self.in_header {
            self.header_line()?;
            return Ok(true);
        }
        if self.line.is_empty() {
            return Ok(true);
        }
        let v3 = self.version == 3;
        let init = self.line.first() == Some(&if v3 { b'>' } else { b'&' });
        if init {
            self.epoch.clear();
        }
        let line = std::mem::take(&mut self.line);
        text_diff(&mut self.epoch, &line);
        self.line = line;
        let (flag_col, n_cols, sat_col) = if v3 {
            (31, 32..35, 41)
        } else {
            (28, 29..32, 32)
        };
        let ln = self.crx_line;
        let flag = self.epoch.get(flag_col).copied().unwrap_or(b' ');
        let n: usize = self
            .epoch
            .get(n_cols.clone())
            .and_then(|b| String::from_utf8_lossy(b).trim().parse().ok())
            .ok_or_else(|| bad(ln, "epoch line: expected the number of satellites"))?;
        if (b'2'..=b'5').contains(&flag) {
            // An event: its epoch line as written, then n records verbatim.
            let head = self.epoch.get(..n_cols.end).unwrap_or(&self.epoch).to_vec();
            self.out.extend_from_slice(&head);
            self.out.push(b'\n');
            for _ in 0..n {
                self.need_line("an event record")?;
                self.out.extend_from_slice(&self.line);
                self.out.push(b'\n');
            }
            self.epoch.clear();
            return Ok(true);
        }
        // Clock line.
        self.need_line("the receiver clock line")?;
        let clock = if self.line.is_empty() {
            self.clock = None;
            None
        } else {
            let f = std::mem::take(&mut self.line);
            let mut arc = self.clock;
            let v = self.field_arc(&f, &mut arc, "receiver clock");
            self.clock = arc;
            self.line = f;
            Some(v?)
        };
        let ids: Vec<[u8; 3]> = (0..n)
            .map(|k| {
                let a = sat_col + 3 * k;
                match self.epoch.get(a..a + 3) {
                    Some(&[s, x, y]) => Ok([if s == b' ' { b'G' } else { s }, x, y]),
                    _ => Err(bad(
                        ln,
                        format!("epoch line: satellite {} of {n} missing", k + 1),
                    )),
                }
            })
            .collect::<io::Result<_>>()?;
        // Epoch line of the RINEX file.
        let mut head = self.epoch.get(..n_cols.end).unwrap_or(&self.epoch).to_vec();
        if v3 {
            if let Some(c) = clock {
                head.resize(41, b' ');
                push_scaled(&mut head, c, 12, 15);
            }
            self.out.extend_from_slice(&head);
            self.out.push(b'\n');
        } else {
            for (k, id) in ids.iter().enumerate() {
                if k > 0 && k % 12 == 0 {
                    if k == 12 {
                        push_v2_clock(&mut head, clock);
                    }
                    self.out.extend_from_slice(&head);
                    self.out.push(b'\n');
                    head = vec![b' '; 32];
                }
                head.extend_from_slice(id);
            }
            if ids.len() <= 12 {
                push_v2_clock(&mut head, clock);
            }
            self.out.extend_from_slice(&head);
            self.out.push(b'\n');
        }
        let mut old = std::mem::take(&mut self.sats);
        for id in ids {
            let nt = self.n_types(id[0]).ok_or_else(|| {
                bad(
                    ln,
                    format!(
                        "satellite {}: no observation types for system {}",
                        String::from_utf8_lossy(&id),
                        id[0] as char
                    ),
                )
            })?;
            self.need_line("a satellite's observations")?;
            let mut st = old.remove(&id).unwrap_or_default();
            st.arcs.resize(nt, None);
            let line = std::mem::take(&mut self.line);
            let mut values = Vec::with_capacity(nt);
            let mut pos = 0;
            for j in 0..nt {
                let rest = line.get(pos..).unwrap_or(&[]);
                let end = rest.iter().position(|&c| c == b' ').unwrap_or(rest.len());
                let f = rest.get(..end).unwrap_or(&[]);
                pos += end + 1;
                if f.is_empty() {
                    st.arcs[j] = None;
                    values.push(None);
                    continue;
                }
                let what = format!("{} observation {}", String::from_utf8_lossy(&id), j + 1);
                let mut arc = st.arcs[j];
                let v = self.field_arc(f, &mut arc, &what)?;
                st.arcs[j] = arc;
                values.push(Some(v));
            }
            text_diff(&mut st.flags, line.get(pos..).unwrap_or(&[]));
            self.line = line;
            self.push_sat(&id, &values, &st.flags);
            self.sats.insert(id, st);
        }
        Ok(true)
    }

    fn field_arc(&self, f: &[u8], arc: &mut Option<Arc>, what: &str) -> io::Result<i64> {
        let ln = self.crx_line;
        let text = String::from_utf8_lossy(f);
        let int = |s: &str| -> io::Result<i64> {
            s.parse::<i64>()
                .map_err(|_| bad(ln, format!("{what}: expected an integer, found \"{s}\"")))
        };
        if let Some((ord, val)) = text.split_once('&') {
            let order: usize = ord.parse().ok().filter(|&o| o <= MAX_ORDER).ok_or_else(|| {
                bad(ln, format!("{what}: expected an arc order 0-{MAX_ORDER} before '&', found \"{ord}\""))
            })?;
            let v = int(val)?;
            *arc = Some(Arc::start(order, v));
            return Ok(v);
        }
        let d = int(&text)?;
        let a = arc.as_mut().ok_or_else(|| {
            bad(
                ln,
                format!("{what}: a difference without an arc started ('M&V')"),
            )
        })?;
        a.next(d)
            .ok_or_else(|| bad(ln, format!("{what}: value out of range")))
    }

    /// One satellite's RINEX record(s).
    fn push_sat(&mut self, id: &[u8; 3], values: &[Option<i64>], flags: &[u8]) {
        let start = self.out.len();
        if self.version == 3 {
            self.out.extend_from_slice(id);
        }
        for (j, v) in values.iter().enumerate() {
            if self.version == 1 && j % 5 == 0 && j > 0 {
                trim_end(&mut self.out, start);
                self.out.push(b'\n');
            }
            match v {
                Some(v) => push_scaled(&mut self.out, *v, 3, 14),
                None => self.out.extend_from_slice(&[b' '; 14]),
            }
            for k in [2 * j, 2 * j + 1] {
                self.out.push(flags.get(k).copied().unwrap_or(b' '));
            }
        }
        trim_end(&mut self.out, start);
        self.out.push(b'\n');
    }
}

/// The RINEX 2 clock offset (F12.9, columns 69-80) on the first epoch line.
fn push_v2_clock(head: &mut Vec<u8>, clock: Option<i64>) {
    if let Some(c) = clock {
        head.resize(68, b' ');
        push_scaled(head, c, 9, 12);
    }
}

/// Drop trailing blanks after `start` (RINEX lines end at their last field).
fn trim_end(out: &mut Vec<u8>, start: usize) {
    while out.len() > start && out.last() == Some(&b' ') {
        out.pop();
    }
}

impl<R: BufRead> Read for CrxDecoder<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        while self.pos >= self.out.len() {
            self.out.clear();
            self.pos = 0;
            if !self.decode_next()? {
                return Ok(0);
            }
        }
        let src = self.out.get(self.pos..).unwrap_or(&[]);
        let n = src.len().min(buf.len());
        buf[..n].copy_from_slice(&src[..n]);
        self.pos += n;
        Ok(n)
    }
}

/// Expand a whole Compact RINEX text (tests, tools).
pub fn crx_to_rinex(crx: &[u8]) -> io::Result<Vec<u8>> {
    let mut out = Vec::new();
    CrxDecoder::new(crx).read_to_end(&mut out)?;
    Ok(out)
}
