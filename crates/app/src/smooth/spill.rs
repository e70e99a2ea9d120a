//! A scratch file of variable-length entries, written once front to back and read
//! back front to back or back to front, so that the smoother's memory does not grow
//! with the length of the run. Each entry is `len (u32) payload len (u32)`, little
//! endian; the file is removed when the [`Spill`] is dropped.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Bytes read at a time when reading backwards.
const CHUNK: usize = 4 << 20;

static NEXT_ID: AtomicU64 = AtomicU64::new(0);

/// An append-only scratch file.
pub(crate) struct Spill {
    path: PathBuf,
    out: Option<BufWriter<File>>,
    entries: u64,
    bytes: u64,
}

impl Spill {
    /// A new scratch file `navfuse-NAME-PID-N.tmp` in `dir`.
    pub fn create(dir: &Path, name: &str) -> std::io::Result<Spill> {
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        let path = dir.join(format!(".navfuse-{name}-{}-{id}.tmp", std::process::id()));
        let f = File::create(&path)?;
        Ok(Spill {
            path,
            out: Some(BufWriter::with_capacity(1 << 20, f)),
            entries: 0,
            bytes: 0,
        })
    }

    pub fn push(&mut self, payload: &[u8]) -> std::io::Result<()> {
        let out = self
            .out
            .as_mut()
            .ok_or_else(|| std::io::Error::other("scratch file already closed"))?;
        let len = u32::try_from(payload.len())
            .map_err(|_| std::io::Error::other("scratch entry too large"))?;
        out.write_all(&len.to_le_bytes())?;
        out.write_all(payload)?;
        out.write_all(&len.to_le_bytes())?;
        self.entries += 1;
        self.bytes += payload.len() as u64 + 8;
        Ok(())
    }

    /// The directory the file is in.
    pub fn dir(&self) -> Option<PathBuf> {
        self.path.parent().map(Path::to_path_buf)
    }

    pub fn len(&self) -> u64 {
        self.entries
    }

    /// Bytes written so far.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Stop writing (flush).
    pub fn close(&mut self) -> std::io::Result<()> {
        if let Some(mut out) = self.out.take() {
            out.flush()?;
        }
        Ok(())
    }

    /// Read the entries front to back.
    pub fn forward(&mut self) -> std::io::Result<Forward> {
        self.close()?;
        Ok(Forward {
            r: BufReader::with_capacity(1 << 20, File::open(&self.path)?),
            left: self.entries,
            buf: Vec::new(),
        })
    }

    /// Read the entries back to front.
    pub fn backward(&mut self) -> std::io::Result<Backward> {
        self.close()?;
        let f = File::open(&self.path)?;
        let end = f.metadata()?.len();
        Ok(Backward {
            f,
            buf: Vec::new(),
            buf_start: end,
            pos: end,
        })
    }
}

impl Drop for Spill {
    fn drop(&mut self) {
        self.out = None;
        let _ = std::fs::remove_file(&self.path);
    }
}

pub(crate) struct Forward {
    r: BufReader<File>,
    left: u64,
    buf: Vec<u8>,
}

impl Forward {
    /// The next entry, None after the last.
    pub fn next_entry(&mut self) -> std::io::Result<Option<&[u8]>> {
        if self.left == 0 {
            return Ok(None);
        }
        let mut len = [0u8; 4];
        self.r.read_exact(&mut len)?;
        let len = u32::from_le_bytes(len) as usize;
        self.buf.resize(len + 4, 0);
        self.r.read_exact(&mut self.buf)?;
        self.left -= 1;
        Ok(Some(&self.buf[..len]))
    }
}

pub(crate) struct Backward {
    f: File,
    /// Bytes \[buf_start, buf_start + buf.len()) of the file.
    buf: Vec<u8>,
    buf_start: u64,
    /// End of the entries not yet read.
    pos: u64,
}

impl Backward {
    /// Make sure bytes \[from, self.pos) are in the buffer.
    fn have(&mut self, from: u64) -> std::io::Result<()> {
        if from >= self.buf_start {
            return Ok(());
        }
        let start = from.min(self.pos.saturating_sub(CHUNK as u64));
        let mut buf = vec![0u8; (self.pos - start) as usize];
        self.f.seek(SeekFrom::Start(start))?;
        self.f.read_exact(&mut buf)?;
        self.buf = buf;
        self.buf_start = start;
        Ok(())
    }

    /// The previous entry, None before the first.
    pub fn next_entry(&mut self) -> std::io::Result<Option<&[u8]>> {
        if self.pos == 0 {
            return Ok(None);
        }
        if self.pos < 8 {
            return Err(std::io::Error::other("scratch file truncated"));
        }
        self.have(self.pos - 4)?;
        let o = (self.pos - 4 - self.buf_start) as usize;
        let len = u32::from_le_bytes(self.buf[o..o + 4].try_into().unwrap()) as u64;
        let start = self
            .pos
            .checked_sub(len + 8)
            .ok_or_else(|| std::io::Error::other("scratch file corrupt"))?;
        self.have(start)?;
        let a = (start + 4 - self.buf_start) as usize;
        self.pos = start;
        Ok(Some(&self.buf[a..a + len as usize]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_back_both_ways_across_chunks() {
        let dir = std::env::temp_dir();
        let mut s = Spill::create(&dir, "test").unwrap();
        // Entries of varying size, some larger than a chunk.
        let sizes: Vec<usize> = (0..300)
            .map(|i| (i * 7919) % 50_000 + (i % 97) * 1000)
            .collect();
        let big = CHUNK + 123;
        let mut all: Vec<Vec<u8>> = sizes
            .iter()
            .map(|&n| (0..n).map(|k| (k % 251) as u8).collect())
            .collect();
        all.insert(150, (0..big).map(|k| (k % 13) as u8).collect());
        for e in &all {
            s.push(e).unwrap();
        }
        let mut f = s.forward().unwrap();
        for e in &all {
            assert_eq!(f.next_entry().unwrap().unwrap(), &e[..]);
        }
        assert!(f.next_entry().unwrap().is_none());
        let mut b = s.backward().unwrap();
        for e in all.iter().rev() {
            assert_eq!(b.next_entry().unwrap().unwrap(), &e[..]);
        }
        assert!(b.next_entry().unwrap().is_none());
        let path = s.path.clone();
        drop(s);
        assert!(!path.exists());
    }
}
