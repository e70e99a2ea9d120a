//! RXM-SFRBX pages built by an encoder written here from the ICD tables (bit
//! positions, scale factors, the BeiDou BCH(15,11) parity by its generator matrix,
//! the Galileo CRC-24Q by a lookup table, the GLONASS Hamming code by the ICD's
//! lists of bits), framed as UBX and decoded back by `decode_ubx`: every field as
//! encoded. This code shares no line with the decoder; the ICD reading is the same
//! person's, so a misread table would be misread on both sides (the walk_0827
//! comparisons with convbin in ubx_data.rs check GPS, BeiDou D1 and Galileo against
//! RTKLIB's reading).

use navfuse_io::ubx::decode_ubx;
use navfuse_io::ubx::frame::checksum;

/// The ICDs' pi (truncated on purpose).
#[allow(clippy::approx_constant)]
const SC: f64 = 3.141_592_653_589_8;

/// A bit string written at positions.
struct W(Vec<u8>);

impl W {
    fn new(n: usize) -> W {
        W(vec![0; n])
    }
    /// The low `len` bits of `v` (two's complement) at `pos`.
    fn put(&mut self, pos: usize, len: usize, v: i64) {
        for k in 0..len {
            self.0[pos + k] = ((v >> (len - 1 - k)) & 1) as u8;
        }
    }
    /// Sign-magnitude.
    fn put_sm(&mut self, pos: usize, len: usize, v: i64) {
        self.put(pos, 1, i64::from(v < 0));
        self.put(pos + 1, len - 1, v.abs());
    }
    fn get(&self, pos: usize, len: usize) -> u64 {
        (pos..pos + len).fold(0, |a, k| (a << 1) | u64::from(self.0[k]))
    }
    /// Words of `n` bits (right-aligned in u32), then shifted left by `shift`.
    fn words(&self, n: usize, shift: u32) -> Vec<u32> {
        self.0
            .chunks(n)
            .map(|c| (c.iter().fold(0u32, |a, b| (a << 1) | u32::from(*b))) << shift)
            .collect()
    }
}

fn frame(class: u8, id: u8, p: &[u8]) -> Vec<u8> {
    let mut f = vec![0xB5, 0x62, class, id];
    f.extend_from_slice(&(p.len() as u16).to_le_bytes());
    f.extend_from_slice(p);
    let (a, b) = checksum(&f[2..]);
    f.extend_from_slice(&[a, b]);
    f
}

fn sfrbx(gnss: u8, sv: u8, sig: u8, freq: u8, words: &[u32]) -> Vec<u8> {
    let mut p = vec![gnss, sv, sig, freq, words.len() as u8, 0, 2, 0];
    for w in words {
        p.extend_from_slice(&w.to_le_bytes());
    }
    frame(0x02, 0x13, &p)
}

/// A RAWX epoch without measurements: the receiver's time and leap seconds.
fn rawx(week: u16, tow: f64) -> Vec<u8> {
    let mut p = vec![0u8; 16];
    p[..8].copy_from_slice(&tow.to_le_bytes());
    p[8..10].copy_from_slice(&week.to_le_bytes());
    p[10] = 18;
    p[12] = 1;
    p[13] = 1;
    frame(0x02, 0x15, &p)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-15 * a.abs().max(b.abs()) + 1e-300
}

// ---------------------------------------------------------------- GPS / QZSS

/// Subframe 4 page 18 (IS-GPS-200 Table 20-X, Figure 20-1 sheet 8): word 3 data ID,
/// SV ID 56, alpha0, alpha1; word 4 alpha2, alpha3, beta0; word 5 beta1-3; word 9
/// delta t_LS. 24 data bits per word in bits 29..6.
#[test]
fn gps_page18_gives_klobuchar_and_leap_seconds() {
    let mut w = W::new(240);
    let at = |word: usize, bit: usize| 24 * (word - 1) + bit - 1;
    w.put(at(1, 1), 8, 0x8B);
    w.put(at(2, 20), 3, 4);
    w.put(at(3, 1), 2, 1);
    w.put(at(3, 3), 6, 56);
    let a = [12i64, -3, -60, 100];
    let b = [80i64, -2, -128, 127];
    for (k, (word, bit)) in [(3, 9), (3, 17), (4, 1), (4, 9)].iter().enumerate() {
        w.put(at(*word, *bit), 8, a[k]);
    }
    for (k, (word, bit)) in [(4, 17), (5, 1), (5, 9), (5, 17)].iter().enumerate() {
        w.put(at(*word, *bit), 8, b[k]);
    }
    w.put(at(9, 1), 8, 18);
    let words = w.words(24, 6);
    let log = decode_ubx(&sfrbx(0, 5, 0, 0, &words), "p18");
    let alpha = log.nav.iono_alpha.expect("alpha");
    let beta = log.nav.iono_beta.expect("beta");
    let sa = [
        2f64.powi(-30),
        2f64.powi(-27),
        2f64.powi(-24),
        2f64.powi(-24),
    ];
    let sb = [2f64.powi(11), 2f64.powi(14), 2f64.powi(16), 2f64.powi(16)];
    for k in 0..4 {
        assert!(close(alpha[k], a[k] as f64 * sa[k]), "alpha{k}");
        assert!(close(beta[k], b[k] as f64 * sb[k]), "beta{k}");
    }
    assert_eq!(log.nav.leap_seconds, Some(18));
    assert_eq!(log.sfrbx.gps.pages, 1);
    // The same page from QZSS goes to its own coefficients.
    let log = decode_ubx(&sfrbx(5, 3, 0, 0, &words), "qzss");
    assert_eq!(log.nav.iono_alpha, None);
    assert_eq!(log.nav.iono.qzss_klobuchar.unwrap().0, alpha);
}

/// QZSS LNAV is GPS's layout: G32's real subframes 1-3 (the fuzz seed) re-tagged
/// as J02 give J02 with the same orbit.
#[test]
fn qzss_lnav_decodes_as_gps() {
    let seed = std::fs::read(
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/fuzz/walk_0827_cut.ubx"),
    )
    .unwrap();
    let g = decode_ubx(&seed, "seed");
    let (frames, _) = navfuse_io::ubx::frame::scan(&seed);
    let mut d = Vec::new();
    for f in frames.iter().filter(|f| (f.class, f.id) == (0x02, 0x13)) {
        if f.payload[0] == 0 {
            let mut p = f.payload.to_vec();
            p[0] = 5;
            p[1] = 2;
            d.extend(frame(0x02, 0x13, &p));
        }
    }
    let j = decode_ubx(&d, "qzss");
    assert_eq!(j.nav.qzss.len(), 1);
    let (e, r) = (&j.nav.qzss[0], &g.nav.gps[0]);
    assert_eq!(e.prn, 2);
    assert_eq!(
        (e.sqrt_a_sqrt_m, e.m0_rad, e.iode, e.toe),
        (r.sqrt_a_sqrt_m, r.m0_rad, r.iode, r.toe)
    );
    assert_eq!(e.fit_interval_h, 4.0);
}

// ---------------------------------------------------------------- BeiDou D2

/// BCH(15,11) parity by the generator matrix: the parity of information bit k
/// (x^(14-k) for k = 0 first) is x^(14-k) mod (x^4 + x + 1), listed.
fn bch(info: u64) -> u64 {
    // x^14..x^4 mod g, MSB info bit first.
    const ROWS: [u64; 11] = [
        0b1001, 0b1101, 0b1111, 0b1110, 0b0111, 0b1010, 0b0101, 0b1011, 0b1100, 0b0110, 0b0011,
    ];
    (0..11).fold(0, |p, k| {
        if (info >> (10 - k)) & 1 == 1 {
            p ^ ROWS[k]
        } else {
            p
        }
    })
}

/// A D2 subframe 1 page: ICD bit N at N - 1, parity filled in.
fn bds_page(fields: &[(usize, usize, i64)], sow: i64, page: i64) -> Vec<u32> {
    let mut w = W::new(300);
    w.put(0, 11, 0b111_0001_0010);
    w.put(15, 3, 1);
    w.put(18, 8, sow >> 12);
    w.put(30, 12, sow & 0xFFF);
    w.put(42, 4, page);
    for &(n, len, v) in fields {
        w.put(n - 1, len, v);
    }
    let p1 = bch(w.get(15, 11));
    w.put(26, 4, p1 as i64);
    for k in 1..10 {
        let o = 30 * k;
        let (a, b) = (bch(w.get(o, 11)), bch(w.get(o + 11, 11)));
        w.put(o + 22, 4, a as i64);
        w.put(o + 26, 4, b as i64);
    }
    w.words(30, 0)
}

#[test]
fn beidou_d2_geo_round_trip() {
    // Raw broadcast integers of a GEO ephemeris (C03).
    let (week, toe8) = (1025i64, 406_800 / 8);
    let (a0, a1, a2) = (-5_000_000i64, -1_200_000i64, 300i64);
    let (dn, cuc, m0, e) = (12_345i64, -100_000i64, -1_500_000_000i64, 1_000_000i64);
    let (cus, sqrta, cic, cis) = (50_000i64, 2_770_000_000u32 as i64, -20_000i64, 30_000i64);
    let (i0, crc, crs, od) = (500_000_000i64, -70_000i64, 60_000i64, -6_000_000i64);
    let (om0, om, idot) = (1_000_000_000i64, -2_000_000_000i64, -5_000i64);
    let (tgd1, tgd2, aode, aodc, urai) = (-25i64, 40i64, 7i64, 3i64, 2i64);
    let s1 = 406_800 + 60;
    let sp = |page: i64| s1 + if page == 1 { 0 } else { 6 + 3 * (page - 3) };
    let mut d = Vec::new();
    type Fields = Vec<(usize, usize, i64)>;
    let pages: Vec<(i64, Fields)> = vec![
        (
            1,
            vec![
                (47, 1, 0),
                (48, 5, aodc),
                (61, 4, urai),
                (65, 13, week),
                (78, 5, toe8 >> 12),
                (91, 12, toe8 & 0xFFF),
                (103, 10, tgd1),
                (121, 10, tgd2),
            ],
        ),
        (
            3,
            vec![
                (101, 12, a0 >> 12),
                (121, 12, a0 & 0xFFF),
                (133, 4, a1 >> 18),
            ],
        ),
        (
            4,
            vec![
                (47, 6, (a1 >> 12) & 0x3F),
                (61, 12, a1 & 0xFFF),
                (73, 10, a2 >> 1),
                (91, 1, a2 & 1),
                (92, 5, aode),
                (97, 16, dn),
                (121, 14, cuc >> 4),
            ],
        ),
        (
            5,
            vec![
                (47, 4, cuc & 0xF),
                (51, 2, m0 >> 30),
                (61, 22, (m0 >> 8) & 0x3F_FFFF),
                (91, 8, m0 & 0xFF),
                (99, 14, cus >> 4),
                (121, 4, cus & 0xF),
                (125, 10, e >> 22),
            ],
        ),
        (
            6,
            vec![
                (47, 6, (e >> 16) & 0x3F),
                (61, 16, e & 0xFFFF),
                (77, 6, sqrta >> 26),
                (91, 22, (sqrta >> 4) & 0x3F_FFFF),
                (121, 4, sqrta & 0xF),
                (125, 10, cic >> 8),
            ],
        ),
        (
            7,
            vec![
                (47, 6, (cic >> 2) & 0x3F),
                (61, 2, cic & 3),
                (63, 18, cis),
                (81, 2, toe8 >> 15),
                (91, 15, toe8 & 0x7FFF),
                (106, 7, i0 >> 25),
                (121, 14, (i0 >> 11) & 0x3FFF),
            ],
        ),
        (
            8,
            vec![
                (47, 6, (i0 >> 5) & 0x3F),
                (61, 5, i0 & 0x1F),
                (66, 17, crc >> 1),
                (91, 1, crc & 1),
                (92, 18, crs),
                (110, 3, od >> 21),
                (121, 16, (od >> 5) & 0xFFFF),
            ],
        ),
        (
            9,
            vec![
                (47, 5, od & 0x1F),
                (52, 1, om0 >> 31),
                (61, 22, (om0 >> 9) & 0x3F_FFFF),
                (91, 9, om0 & 0x1FF),
                (100, 13, om >> 19),
                (121, 14, (om >> 5) & 0x3FFF),
            ],
        ),
        (
            10,
            vec![
                (47, 5, om & 0x1F),
                (52, 1, idot >> 13),
                (61, 13, idot & 0x1FFF),
            ],
        ),
    ];
    for (page, f) in &pages {
        d.extend(sfrbx(3, 3, 1, 0, &bds_page(f, sp(*page), *page)));
    }
    let log = decode_ubx(&d, "d2");
    assert_eq!(log.sfrbx.beidou.rejected, 0, "{:?}", log.warnings);
    assert_eq!(log.nav.beidou.len(), 1, "{:?}", log.sfrbx);
    let x = &log.nav.beidou[0];
    let o = &x.orbit;
    let p2 = |n: i32| 2f64.powi(n);
    assert_eq!(x.prn, 3);
    assert_eq!(
        (x.toe.week, x.toe.sow, x.toc.sow),
        (1025, 406_800.0, 406_800.0)
    );
    assert_eq!(x.transmission_time.unwrap().sow, s1 as f64);
    assert_eq!((x.aode, x.aodc, x.sv_accuracy_m), (7, 3, 4.0));
    let checks = [
        (x.af0_s, a0 as f64 * p2(-33)),
        (x.af1_s_per_s, a1 as f64 * p2(-50)),
        (x.af2_s_per_s2, a2 as f64 * p2(-66)),
        (x.tgd1_s, tgd1 as f64 * 0.1e-9),
        (x.tgd2_s, tgd2 as f64 * 0.1e-9),
        (o.delta_n_rad_per_s, dn as f64 * p2(-43) * SC),
        (o.cuc_rad, cuc as f64 * p2(-31)),
        (o.m0_rad, m0 as f64 * p2(-31) * SC),
        (o.e, e as f64 * p2(-33)),
        (o.cus_rad, cus as f64 * p2(-31)),
        (o.sqrt_a_sqrt_m, sqrta as f64 * p2(-19)),
        (o.cic_rad, cic as f64 * p2(-31)),
        (o.cis_rad, cis as f64 * p2(-31)),
        (o.i0_rad, i0 as f64 * p2(-31) * SC),
        (o.crc_m, crc as f64 * p2(-6)),
        (o.crs_m, crs as f64 * p2(-6)),
        (o.omega_dot_rad_per_s, od as f64 * p2(-43) * SC),
        (o.omega0_rad, om0 as f64 * p2(-31) * SC),
        (o.omega_rad, om as f64 * p2(-31) * SC),
        (o.idot_rad_per_s, idot as f64 * p2(-43) * SC),
    ];
    for (k, (a, b)) in checks.iter().enumerate() {
        assert!(close(*a, *b), "field {k}: {a} {b}");
    }
    // One flipped bit: the page is rejected by its parity.
    let mut words = bds_page(&pages[0].1, sp(1), 1);
    words[4] ^= 1 << 20;
    let log = decode_ubx(&sfrbx(3, 3, 1, 0, &words), "bad");
    assert_eq!(log.sfrbx.beidou.rejected, 1);
}

// ---------------------------------------------------------------- Galileo

/// CRC-24Q by a 256-entry table (byte-wise), over bits padded at the front to bytes.
fn crc24q_table(bits: &[u8]) -> u32 {
    let mut table = [0u32; 256];
    for (i, t) in table.iter_mut().enumerate() {
        let mut c = (i as u32) << 16;
        for _ in 0..8 {
            c <<= 1;
            if c & 0x100_0000 != 0 {
                c ^= 0x186_4CFB;
            }
        }
        *t = c & 0xFF_FFFF;
    }
    let mut v = vec![0u8; (8 - bits.len() % 8) % 8];
    v.extend_from_slice(bits);
    let mut crc = 0u32;
    for byte in v.chunks(8) {
        let b = byte.iter().fold(0u32, |a, x| (a << 1) | u32::from(*x));
        crc = ((crc << 8) & 0xFF_FFFF) ^ table[(((crc >> 16) ^ b) & 0xFF) as usize];
    }
    crc
}

/// An I/NAV nominal page pair carrying the 128-bit data word `data` in 8 words.
fn inav_page(data: &W) -> Vec<u32> {
    let mut w = W::new(256);
    w.put(0, 1, 0);
    w.put(1, 1, 0);
    for k in 0..112 {
        w.0[2 + k] = data.0[k];
    }
    w.put(128, 1, 1);
    w.put(129, 1, 0);
    for k in 0..16 {
        w.0[130 + k] = data.0[112 + k];
    }
    let mut crc_in: Vec<u8> = w.0[..114].to_vec();
    crc_in.extend_from_slice(&w.0[128..128 + 82]);
    let crc = crc24q_table(&crc_in);
    w.put(128 + 82, 24, i64::from(crc));
    w.words(32, 0)
}

#[test]
fn galileo_inav_round_trip() {
    let iod = 77i64;
    let (toe60, m0, e, sqrta) = (
        6780i64,
        -1_234_567_890i64,
        12_345_678i64,
        2_852_000_000u32 as i64,
    );
    let (om0, i0, om, idot) = (987_654_321i64, 650_000_000i64, -1_111_111_111i64, -4_000i64);
    let (od, dn, cuc, cus, crc, crs, sisa) = (
        -5_000_000i64,
        9_000i64,
        -300i64,
        700i64,
        4_000i64,
        -2_500i64,
        107i64,
    );
    let (cic, cis, toc60, af0, af1, af2) =
        (55i64, -66i64, 6780i64, -300_000_000i64, -400_000i64, 0i64);
    let (ai0, ai1, ai2, bgd_a, bgd_b) = (120i64, -30i64, 100i64, -13i64, -12i64);
    let (wn, tow) = (1357i64, 408_655i64);
    let mut words = Vec::new();
    let mut dw = |fields: &[(usize, usize, i64)]| {
        let mut w = W::new(128);
        for &(p, l, v) in fields {
            w.put(p, l, v);
        }
        words.push(inav_page(&w));
    };
    dw(&[
        (0, 6, 1),
        (6, 10, iod),
        (16, 14, toe60),
        (30, 32, m0),
        (62, 32, e),
        (94, 32, sqrta),
    ]);
    dw(&[
        (0, 6, 2),
        (6, 10, iod),
        (16, 32, om0),
        (48, 32, i0),
        (80, 32, om),
        (112, 14, idot),
    ]);
    dw(&[
        (0, 6, 3),
        (6, 10, iod),
        (16, 24, od),
        (40, 16, dn),
        (56, 16, cuc),
        (72, 16, cus),
        (88, 16, crc),
        (104, 16, crs),
        (120, 8, sisa),
    ]);
    dw(&[
        (0, 6, 4),
        (6, 10, iod),
        (16, 6, 11),
        (22, 16, cic),
        (38, 16, cis),
        (54, 14, toc60),
        (68, 31, af0),
        (99, 21, af1),
        (120, 6, af2),
    ]);
    dw(&[
        (0, 6, 5),
        (6, 11, ai0),
        (17, 11, ai1),
        (28, 14, ai2),
        (47, 10, bgd_a),
        (57, 10, bgd_b),
        (67, 2, 0),
        (69, 2, 1),
        (71, 1, 0),
        (72, 1, 1),
        (73, 12, wn),
        (85, 20, tow),
    ]);
    let d: Vec<u8> = words.iter().flat_map(|w| sfrbx(2, 11, 5, 0, w)).collect();
    let log = decode_ubx(&d, "inav");
    assert_eq!(log.sfrbx.galileo_crc_failures, 0, "{:?}", log.warnings);
    assert_eq!(log.nav.galileo.len(), 1, "{:?}", log.sfrbx);
    let x = &log.nav.galileo[0];
    let o = &x.orbit;
    let p2 = |n: i32| 2f64.powi(n);
    assert_eq!((x.prn, x.iodnav, x.data_sources), (11, 77, 0x204));
    assert_eq!(
        (x.toe.week, x.toe.sow, x.toc.sow),
        (2381, 406_800.0, 406_800.0)
    );
    assert_eq!(x.transmission_time.unwrap().sow, tow as f64);
    assert_eq!(x.health, 0b11);
    assert!(close(x.sisa_m, 3.12));
    let checks = [
        (x.af0_s, af0 as f64 * p2(-34)),
        (x.af1_s_per_s, af1 as f64 * p2(-46)),
        (x.bgd_e1_e5a_s, bgd_a as f64 * p2(-32)),
        (x.bgd_e1_e5b_s, bgd_b as f64 * p2(-32)),
        (o.m0_rad, m0 as f64 * p2(-31) * SC),
        (o.e, e as f64 * p2(-33)),
        (o.sqrt_a_sqrt_m, sqrta as f64 * p2(-19)),
        (o.omega0_rad, om0 as f64 * p2(-31) * SC),
        (o.i0_rad, i0 as f64 * p2(-31) * SC),
        (o.omega_rad, om as f64 * p2(-31) * SC),
        (o.idot_rad_per_s, idot as f64 * p2(-43) * SC),
        (o.omega_dot_rad_per_s, od as f64 * p2(-43) * SC),
        (o.delta_n_rad_per_s, dn as f64 * p2(-43) * SC),
        (o.cuc_rad, cuc as f64 * p2(-29)),
        (o.cus_rad, cus as f64 * p2(-29)),
        (o.crc_m, crc as f64 * p2(-5)),
        (o.crs_m, crs as f64 * p2(-5)),
        (o.cic_rad, cic as f64 * p2(-29)),
        (o.cis_rad, cis as f64 * p2(-29)),
    ];
    for (k, (a, b)) in checks.iter().enumerate() {
        assert!(close(*a, *b), "field {k}: {a} {b}");
    }
    let nq = log.nav.iono.galileo_nequick.unwrap();
    assert!(close(nq[0], 30.0) && close(nq[1], -30.0 / 256.0) && close(nq[2], 100.0 * p2(-15)));
    // A flipped data bit fails the CRC.
    let mut bad = words[0].clone();
    bad[2] ^= 1 << 7;
    let log = decode_ubx(&sfrbx(2, 11, 1, 0, &bad), "crc");
    assert_eq!(log.sfrbx.galileo_crc_failures, 1);
}

// ---------------------------------------------------------------- GLONASS

/// The check bits of a string (ICD 5.1 §4.7, the lists as printed there):
/// beta_k is the parity of the listed data bits; beta_8 makes the whole string even.
fn hamming(s: &mut W) {
    let r = |a: usize, b: usize| (a..=b).collect::<Vec<_>>();
    let lists: [Vec<usize>; 7] = [
        [
            9, 10, 12, 13, 15, 17, 19, 20, 22, 24, 26, 28, 30, 32, 34, 35, 37, 39, 41, 43, 45, 47,
            49, 51, 53, 55, 57, 59, 61, 63, 65, 66, 68, 70, 72, 74, 76, 78, 80, 82, 84,
        ]
        .to_vec(),
        [
            9, 11, 12, 14, 15, 18, 19, 21, 22, 25, 26, 29, 30, 33, 34, 36, 37, 40, 41, 44, 45, 48,
            49, 52, 53, 56, 57, 60, 61, 64, 65, 67, 68, 71, 72, 75, 76, 79, 80, 83, 84,
        ]
        .to_vec(),
        [
            r(10, 12),
            r(16, 19),
            r(23, 26),
            r(31, 34),
            r(38, 41),
            r(46, 49),
            r(54, 57),
            r(62, 65),
            r(69, 72),
            r(77, 80),
            vec![85],
        ]
        .concat(),
        [r(13, 19), r(27, 34), r(42, 49), r(58, 65), r(73, 80)].concat(),
        [r(20, 34), r(50, 65), r(81, 85)].concat(),
        r(35, 65),
        r(66, 85),
    ];
    let bit = |s: &W, n: usize| s.0[85 - n] as i64;
    for (k, l) in lists.iter().enumerate() {
        let p = l.iter().fold(0, |a, n| a ^ bit(s, *n));
        s.put(85 - (k + 1), 1, p);
    }
    let all = (2..=85).fold(0, |a, n| a ^ bit(s, n));
    s.put(85 - 8, 1, all);
}

/// String `m` with (ICD bit of the field's MSB, length, value, sign-magnitude).
fn glo_string(m: i64, fields: &[(usize, usize, i64, bool)]) -> Vec<u32> {
    let mut s = W::new(85);
    s.put(85 - 84, 4, m);
    for &(hi, len, v, sm) in fields {
        if sm {
            s.put_sm(85 - hi, len, v);
        } else {
            s.put(85 - hi, len, v);
        }
    }
    hamming(&mut s);
    let mut w = W::new(96);
    w.0[..85].copy_from_slice(&s.0);
    let mut words = w.words(32, 0);
    words.push(0x0003_0000); // frame 3
    words
}

#[test]
fn glonass_strings_round_trip() {
    // 2025-08-28 17:30 UTC is GPST week 2381, 408618 s; Moscow 20:30.
    let (week, tow) = (2381u16, 408_618.0);
    let (x, vx, ax) = (-5_432_100i64, 1_234_567i64, -3i64);
    let (y, vy, ay) = (20_000_000i64, -654_321i64, 2i64);
    let (z, vz, az) = (40_000_000i64, 99_999i64, 0i64);
    let (tb, tau, gamma, en, slot) = (82i64, -123_456i64, -300i64, 2i64, 7i64); // tb 20:30 MSK
    let strings = [
        glo_string(
            1,
            &[
                (76, 5, 20, false),
                (71, 6, 27, false),
                (65, 1, 0, false),
                (64, 24, vx, true),
                (40, 5, ax, true),
                (35, 27, x, true),
            ],
        ),
        glo_string(
            2,
            &[
                (80, 3, 0, false),
                (76, 7, tb, false),
                (64, 24, vy, true),
                (40, 5, ay, true),
                (35, 27, y, true),
            ],
        ),
        glo_string(
            3,
            &[
                (79, 11, gamma, true),
                (64, 24, vz, true),
                (40, 5, az, true),
                (35, 27, z, true),
            ],
        ),
        glo_string(
            4,
            &[
                (80, 22, tau, true),
                (53, 5, en, false),
                (15, 5, slot, false),
            ],
        ),
    ];
    let mut d = rawx(week, tow);
    for s in &strings {
        d.extend(sfrbx(6, 7, 0, 7 + 3, s));
    }
    let log = decode_ubx(&d, "glo");
    assert_eq!(log.sfrbx.glonass_hamming_failures, 0, "{:?}", log.warnings);
    assert_eq!(log.nav.glonass.len(), 1, "{:?}", log.sfrbx);
    let g = &log.nav.glonass[0];
    let p2 = |n: i32| 2f64.powi(n);
    assert_eq!((g.slot, g.freq_channel, g.health), (7, 3, 0));
    // tb 82 x 15 min = 20:30 Moscow = 17:30 UTC = GPST 17:30:18.
    assert_eq!((g.tb.week, g.tb.sow), (2381, 408_618.0));
    assert_eq!(g.tb_utc_sod_s, 63_000.0);
    // tk 20:27:00 Moscow = 17:27 UTC, Thursday.
    assert_eq!(g.frame_time_s, 4.0 * 86_400.0 + 62_820.0);
    assert!(close(g.pos_m.x, x as f64 * p2(-11) * 1e3));
    assert!(close(g.pos_m.y, y as f64 * p2(-11) * 1e3));
    assert!(close(g.vel_mps.x, vx as f64 * p2(-20) * 1e3));
    assert!(close(g.vel_mps.y, vy as f64 * p2(-20) * 1e3));
    assert!(close(g.vel_mps.z, vz as f64 * p2(-20) * 1e3));
    assert!(close(g.acc_mps2.x, ax as f64 * p2(-30) * 1e3));
    assert!(close(g.tau_n_s, tau as f64 * p2(-30)));
    assert!(close(g.gamma_n, gamma as f64 * p2(-40)));
    assert_eq!(g.age_days, 2.0);
    // A flipped data bit fails the Hamming check; a flipped check bit is accepted.
    let mut bad = strings[0].clone();
    bad[1] ^= 1 << 9;
    let log = decode_ubx(&[rawx(week, tow), sfrbx(6, 7, 0, 10, &bad)].concat(), "ham");
    assert_eq!(log.sfrbx.glonass_hamming_failures, 1);
    let mut chk = strings[0].clone();
    chk[2] ^= 1 << (31 - (83 - 64)); // ICD bit 2 (beta_2) sits at position 83
    let log = decode_ubx(&[rawx(week, tow), sfrbx(6, 7, 0, 10, &chk)].concat(), "chk");
    assert_eq!(log.sfrbx.glonass_hamming_failures, 0);
    // Strings 1-3, then string 4 a minute later (same frame number in word 3): not
    // one frame, no ephemeris.
    let mut d = rawx(week, tow);
    for s in &strings[..3] {
        d.extend(sfrbx(6, 7, 0, 10, s));
    }
    d.extend(rawx(week, tow + 60.0));
    d.extend(sfrbx(6, 7, 0, 10, &strings[3]));
    assert!(decode_ubx(&d, "late").nav.glonass.is_empty());
}
