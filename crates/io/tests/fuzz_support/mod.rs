//! Mutator for the fuzz suite (tests/fuzz.rs): a seeded SplitMix64 generator and
//! byte/field mutations of real seed files. Deterministic for a given seed.

/// SplitMix64: small, fast, reproducible.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that break number handling: overflow after scaling, underflow of squares,
/// NaN, week limits, huge times.
const TOKENS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "1e300",
    "1e-300",
    "5e-324",
    "1e-160",
    "0",
    "-0",
    "-1",
    "1e12",
    "604800",
    "604799.999",
    "604800.5",
    "-604800",
    "9999999999",
    "1e20",
    "0.0000001",
    "1e154",
    "1e-154",
    "3e-310",
    "",
    " ",
    ",",
    ",,",
    "\t",
    "\n",
    "\r\n",
    "#",
    "%",
    "D+99",
    "E-99",
    "1D300",
    "G01",
    "9",
    "99999",
    "-99999",
    "0.1",
    "1.5",
    "360",
    "-180",
    "90.0001",
    "1.",
    ".",
    "-",
    "+",
];

/// Most bytes a mutated input may have (keeps every case fast: no hang by size).
pub const MAX_LEN: usize = 64 * 1024;

/// One mutated copy of `seed`: 1-4 mutations.
pub fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut d = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        mutate_once(&mut d, rng);
    }
    d.truncate(MAX_LEN);
    d
}

fn mutate_once(d: &mut Vec<u8>, rng: &mut Rng) {
    let n = d.len();
    let at = rng.below(n + 1);
    match rng.below(10) {
        // Replace one field (a run of non-separators) with a token: the most useful.
        0..=3 => {
            let (s, e) = field_at(d, at);
            let tok = TOKENS[rng.below(TOKENS.len())].as_bytes();
            d.splice(s..e, tok.iter().copied());
        }
        4 => {
            if n > 0 {
                let i = rng.below(n);
                d[i] ^= 1 << rng.below(8);
            }
        }
        5 => {
            let b = b"0123456789.-+eE ,\n#%DGx\0\xff"[rng.below(25)];
            d.insert(at, b);
        }
        6 => {
            let len = rng.below(64).min(n - at.min(n));
            d.drain(at..at + len);
        }
        // Cut the file (a log cut mid-write).
        7 => d.truncate(at),
        // Duplicate or swap a line.
        8 => {
            let lines: Vec<&[u8]> = d.split(|&b| b == b'\n').collect();
            if lines.len() > 2 {
                let mut v: Vec<Vec<u8>> = lines.iter().map(|l| l.to_vec()).collect();
                let i = rng.below(v.len());
                let j = rng.below(v.len());
                if rng.below(2) == 0 {
                    v.swap(i, j);
                } else {
                    let l = v[i].clone();
                    v.insert(j, l);
                }
                *d = v.join(&b'\n');
            }
        }
        // Repeat a chunk (long lines, many records).
        _ => {
            let len = rng.below(256).min(n - at.min(n));
            let chunk = d[at..at + len].to_vec();
            for _ in 0..rng.below(16) {
                d.splice(at..at, chunk.iter().copied());
            }
        }
    }
}

/// The field (maximal run of non-separator bytes) around `at`, or an empty range.
fn field_at(d: &[u8], at: usize) -> (usize, usize) {
    let sep = |b: u8| matches!(b, b' ' | b'\t' | b',' | b'\n' | b'\r');
    let mut s = at.min(d.len());
    while s > 0 && !sep(d[s - 1]) {
        s -= 1;
    }
    let mut e = s;
    while e < d.len() && !sep(d[e]) {
        e += 1;
    }
    (s, e)
}
