//! A small UBX encoder for tests and the fuzz seed (as `ulog::synth`): frames, the
//! ESF-RAW / ESF-MEAS fields with u-blox's scale factors, NAV-PVT and
//! NAV-RELPOSNED (versions 0 and 1), and a message stream ordered by output time so
//! that a test can model the receiver's output latencies. [`synthetic_esf_log`]
//! is a complete short log of every message the ESF and heading readers take.

use super::esf::{ACCEL_MPS2_PER_COUNT, GYRO_DPS_PER_COUNT, SPEED_MPS_PER_COUNT};
use super::frame::checksum;

/// NAV-RELPOSNED flags.
pub const GNSS_FIX_OK: u32 = 1;
pub const REL_POS_VALID: u32 = 4;
pub const CARR_FLOAT: u32 = 1 << 3;
pub const CARR_FIXED: u32 = 2 << 3;
pub const HEADING_VALID: u32 = 0x100;
/// A usable version-1 heading with fixed ambiguities.
pub const RELPOS_OK: u32 = GNSS_FIX_OK | REL_POS_VALID | CARR_FIXED | HEADING_VALID;

/// GPS week of [`synthetic_esf_log`] (2024-03-18, a Monday) and its first epoch
/// [ms of week]: Monday 10:00:18 GPST = 10:00:00 UTC.
pub const WEEK: i32 = 2306;
pub const ITOW0_MS: u32 = (86_400 + 36_000 + 18) * 1000;

/// One UBX frame: sync, class, id, length, payload, checksum.
pub fn frame(class: u8, id: u8, payload: &[u8]) -> Vec<u8> {
    let mut f = vec![0xB5, 0x62, class, id];
    f.extend_from_slice(&(payload.len() as u16).to_le_bytes());
    f.extend_from_slice(payload);
    let (a, b) = checksum(&f[2..]);
    f.extend_from_slice(&[a, b]);
    f
}

/// A value in counts of `scale`, rounded and clamped to 24-bit signed, as a field.
pub fn field24(value: f64, scale: f64) -> u32 {
    let c = (value / scale).round().clamp(-8_388_608.0, 8_388_607.0) as i32;
    (c as u32) & 0x00FF_FFFF
}

/// Gyro [rad/s] as a 24-bit field (2^-12 deg/s).
pub fn gyro_field(rad_s: f64) -> u32 {
    field24(rad_s.to_degrees(), GYRO_DPS_PER_COUNT)
}

/// Accelerometer [m/s^2] as a 24-bit field (2^-10 m/s^2).
pub fn accel_field(mps2: f64) -> u32 {
    field24(mps2, ACCEL_MPS2_PER_COUNT)
}

/// Speed [m/s] as a type-11 field (1e-3 m/s).
pub fn speed_field(mps: f64) -> u32 {
    field24(mps, SPEED_MPS_PER_COUNT)
}

/// A wheel-tick field: 23-bit count (wrapped) and the direction bit.
pub fn tick_field(count: u64, backward: bool) -> u32 {
    (count as u32 & 0x7F_FFFF) | (u32::from(backward) << 23)
}

/// One IMU sample to encode: sensor time tag, gyro [rad/s], accel [m/s^2].
#[derive(Clone, Copy, Debug)]
pub struct ImuRate {
    pub tag: u32,
    pub gyro: [f64; 3],
    pub accel: [f64; 3],
}

/// The six (type, field) pairs of one sample: gyro x y z (14, 13, 5), accel x y z
/// (16, 17, 18).
pub fn imu_fields(s: &ImuRate) -> [(u8, u32); 6] {
    [
        (14, gyro_field(s.gyro[0])),
        (13, gyro_field(s.gyro[1])),
        (5, gyro_field(s.gyro[2])),
        (16, accel_field(s.accel[0])),
        (17, accel_field(s.accel[1])),
        (18, accel_field(s.accel[2])),
    ]
}

/// ESF-RAW from (type, field, sTtag) blocks.
pub fn esf_raw_blocks(blocks: &[(u8, u32, u32)]) -> Vec<u8> {
    let mut p = vec![0u8; 4];
    for &(ty, field, tag) in blocks {
        p.extend_from_slice(&((u32::from(ty) << 24) | (field & 0x00FF_FFFF)).to_le_bytes());
        p.extend_from_slice(&tag.to_le_bytes());
    }
    frame(0x10, 0x03, &p)
}

/// ESF-RAW holding `samples` (six blocks each).
pub fn esf_raw(samples: &[ImuRate]) -> Vec<u8> {
    let blocks: Vec<(u8, u32, u32)> = samples
        .iter()
        .flat_map(|s| imu_fields(s).map(|(t, f)| (t, f, s.tag)))
        .collect();
    esf_raw_blocks(&blocks)
}

/// ESF-MEAS with time tag `tag` and (type, field) measurements (no calibTtag).
pub fn esf_meas(tag: u32, data: &[(u8, u32)]) -> Vec<u8> {
    let mut p = tag.to_le_bytes().to_vec();
    p.extend_from_slice(&((data.len() as u16) << 11).to_le_bytes());
    p.extend_from_slice(&0u16.to_le_bytes());
    for &(ty, field) in data {
        p.extend_from_slice(&((u32::from(ty & 0x3F) << 24) | (field & 0x00FF_FFFF)).to_le_bytes());
    }
    frame(0x10, 0x02, &p)
}

/// A valid 3D NAV-PVT at `itow_ms` of [`WEEK`]; see [`nav_pvt_at`].
pub fn nav_pvt(itow_ms: u32) -> Vec<u8> {
    nav_pvt_at(WEEK, itow_ms)
}

/// A valid 3D NAV-PVT at `itow_ms` of GPS week `week` (its UTC date and time with
/// 18 leap seconds, as from 2017), static at 47.4 N 8.5 E 500 m.
pub fn nav_pvt_at(week: i32, itow_ms: u32) -> Vec<u8> {
    let mut p = vec![0u8; super::pvt::LEN];
    p[0..4].copy_from_slice(&itow_ms.to_le_bytes());
    let utc_s = i64::from(week) * 604_800 + i64::from(itow_ms / 1000) - 18;
    // Civil date of Unix day z (H. Hinnant's civil_from_days); GPS day 0 = Unix 3657.
    let z = 3657 + utc_s.div_euclid(86_400) + 719_468;
    let sod = utc_s.rem_euclid(86_400);
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    p[4..6].copy_from_slice(&(year as u16).to_le_bytes());
    p[6] = month as u8;
    p[7] = day as u8;
    p[8] = (sod / 3600) as u8;
    p[9] = (sod / 60 % 60) as u8;
    p[10] = (sod % 60) as u8;
    p[11] = 7; // validDate, validTime, fullyResolved
    p[20] = 3; // 3D
    p[21] = 1; // gnssFixOK
    p[23] = 12;
    p[24..28].copy_from_slice(&85_000_000i32.to_le_bytes());
    p[28..32].copy_from_slice(&474_000_000i32.to_le_bytes());
    p[32..36].copy_from_slice(&500_000i32.to_le_bytes());
    p[40..44].copy_from_slice(&1500u32.to_le_bytes());
    p[44..48].copy_from_slice(&2500u32.to_le_bytes());
    p[68..72].copy_from_slice(&100u32.to_le_bytes());
    frame(0x01, 0x07, &p)
}

/// NAV-RELPOSNED version 1: a 1.2 m baseline at `heading_deg` with accHeading
/// `acc_deg`, `flags`.
pub fn relposned_v1(itow_ms: u32, heading_deg: f64, acc_deg: f64, flags: u32) -> Vec<u8> {
    let mut p = vec![0u8; 64];
    p[0] = 1;
    p[4..8].copy_from_slice(&itow_ms.to_le_bytes());
    let (n, e) = (
        1.2 * heading_deg.to_radians().cos(),
        1.2 * heading_deg.to_radians().sin(),
    );
    p[8..12].copy_from_slice(&((n * 100.0).round() as i32).to_le_bytes());
    p[12..16].copy_from_slice(&((e * 100.0).round() as i32).to_le_bytes());
    p[20..24].copy_from_slice(&120i32.to_le_bytes());
    p[24..28].copy_from_slice(&((heading_deg * 1e5).round() as i32).to_le_bytes());
    for o in [36, 40, 44, 48] {
        p[o..o + 4].copy_from_slice(&100u32.to_le_bytes());
    }
    p[52..56].copy_from_slice(&((acc_deg * 1e5).round() as u32).to_le_bytes());
    p[60..64].copy_from_slice(&flags.to_le_bytes());
    frame(0x01, 0x3C, &p)
}

/// NAV-RELPOSNED version 0 (no heading field): relative position N, E, D \[m\]
/// (cm + 0.1 mm parts) with accuracies N, E \[m\], `flags`.
pub fn relposned_v0(itow_ms: u32, ned_m: [f64; 3], acc_ne_m: [f64; 2], flags: u32) -> Vec<u8> {
    let mut p = vec![0u8; 40];
    p[4..8].copy_from_slice(&itow_ms.to_le_bytes());
    for (k, v) in ned_m.iter().enumerate() {
        let tenth_mm = (v * 1e4).round() as i64;
        let cm = tenth_mm / 100;
        let hp = tenth_mm - cm * 100;
        p[8 + 4 * k..12 + 4 * k].copy_from_slice(&(cm as i32).to_le_bytes());
        p[20 + k] = hp as i8 as u8;
    }
    for (k, a) in acc_ne_m.iter().enumerate() {
        p[24 + 4 * k..28 + 4 * k].copy_from_slice(&((a * 1e4).round() as u32).to_le_bytes());
    }
    p[32..36].copy_from_slice(&100u32.to_le_bytes());
    p[36..40].copy_from_slice(&flags.to_le_bytes());
    frame(0x01, 0x3C, &p)
}

/// Messages ordered by their output time (stable for equal times).
#[derive(Default)]
pub struct Stream {
    msgs: Vec<(f64, Vec<u8>)>,
}

impl Stream {
    pub fn push(&mut self, out_time_s: f64, bytes: Vec<u8>) {
        self.msgs.push((out_time_s, bytes));
    }
    pub fn finish(mut self) -> Vec<u8> {
        self.msgs.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.msgs.into_iter().flat_map(|m| m.1).collect()
    }
}

/// The truth of [`synthetic_esf_log`] at sensor time `k` x 20 ms: a car at 10 m/s
/// turning at 2 deg/s (gyro z), level, accel (0, 0.35, -9.81) m/s^2.
pub fn synthetic_rate(k: u32) -> ImuRate {
    let s = f64::from(k);
    ImuRate {
        tag: 100_000 + 20 * k,
        gyro: [
            0.001 * (s * 0.1).sin(),
            -0.002,
            2f64.to_radians() + 1e-4 * s.cos(),
        ],
        accel: [0.05 * (s * 0.05).sin(), 0.35, -9.81],
    }
}

/// A log of `seconds` s: 50 Hz IMU in ESF-RAW (5 samples a message, output 1 ms
/// after the last), rear wheel ticks (0.02 m a tick) and the speed in ESF-MEAS at
/// 10 Hz, and at 1 Hz a NAV-PVT and a NAV-RELPOSNED v1 (heading 30 deg + 2 deg/s,
/// accHeading 0.3 deg, fixed) output 40 ms after the epoch, with one version-0
/// RELPOSNED in the second epoch. Sensor tag 100000 is GPS time ITOW0_MS - 0.5 s.
pub fn synthetic_esf_log(seconds: u32) -> Vec<u8> {
    let mut st = Stream::default();
    let t_of = |tag: u32| f64::from(ITOW0_MS) * 1e-3 - 0.5 + f64::from(tag - 100_000) * 1e-3;
    let n = seconds * 50 + 25;
    for k0 in (0..n).step_by(5) {
        let batch: Vec<ImuRate> = (k0..(k0 + 5).min(n)).map(synthetic_rate).collect();
        let last = batch[batch.len() - 1].tag;
        st.push(t_of(last) + 0.001, esf_raw(&batch));
    }
    for k in 0..(seconds * 10 + 5) {
        let tag = 100_000 + 100 * k;
        let ticks = u64::from(k) * 50; // 10 m/s x 0.1 s / 0.02 m
        st.push(
            t_of(tag) + 0.002,
            esf_meas(
                tag,
                &[
                    (8, tick_field(ticks, false)),
                    (9, tick_field(ticks + 7, false)),
                    (11, speed_field(10.0)),
                ],
            ),
        );
    }
    for s in 0..seconds {
        let itow = ITOW0_MS + 1000 * s;
        let t = f64::from(itow) * 1e-3;
        st.push(t + 0.040, nav_pvt(itow));
        let h = 30.0 + 2.0 * f64::from(s);
        let rel = if s == 1 {
            let r = h.to_radians();
            relposned_v0(
                itow,
                [1.2 * r.cos(), 1.2 * r.sin(), 0.01],
                [0.004, 0.004],
                GNSS_FIX_OK | REL_POS_VALID | CARR_FIXED,
            )
        } else {
            relposned_v1(itow, h, 0.3, RELPOS_OK)
        };
        st.push(t + 0.041, rel);
    }
    st.finish()
}
