//! A small synthetic ULog (for tests and the fuzz seed): every message type the
//! reader knows, a nested type, arrays, `_padding` (inside and trailing), two
//! instances of one topic, and the topics navfuse reads, with a static vehicle at
//! 47.4 N 8.5 E on a known GPS time (`time_utc_usec`).

/// Boot time of the first record \[µs\].
pub const T0_US: u64 = 20_000_000;
/// UTC of boot time 0 [µs since 1970]: 2024-03-18 00:00:00 UTC.
pub const UTC_AT_BOOT_US: u64 = 1_710_720_000_000_000;

fn msg(out: &mut Vec<u8>, ty: u8, payload: &[u8]) {
    out.extend_from_slice(&(payload.len() as u16).to_le_bytes());
    out.push(ty);
    out.extend_from_slice(payload);
}

fn key_value(key: &str, value: &[u8]) -> Vec<u8> {
    let mut p = vec![key.len() as u8];
    p.extend_from_slice(key.as_bytes());
    p.extend_from_slice(value);
    p
}

fn add(out: &mut Vec<u8>, multi_id: u8, msg_id: u16, name: &str) {
    let mut p = vec![multi_id];
    p.extend_from_slice(&msg_id.to_le_bytes());
    p.extend_from_slice(name.as_bytes());
    msg(out, b'A', &p);
}

fn data(out: &mut Vec<u8>, msg_id: u16, fields: &[u8]) {
    let mut p = msg_id.to_le_bytes().to_vec();
    p.extend_from_slice(fields);
    msg(out, b'D', &p);
}

/// Little-endian field bytes.
#[derive(Default)]
struct Rec(Vec<u8>);

/// `fn u64(self, v: u64) -> Self` etc.: append `v` little-endian.
macro_rules! put {
    ($($name:ident: $t:ty),*) => {
        $(fn $name(mut self, v: $t) -> Self {
            self.0.extend_from_slice(&v.to_le_bytes());
            self
        })*
    };
}

impl Rec {
    put!(u64: u64, f32: f32, f64: f64, i32: i32, u32: u32);
    fn u8(mut self, v: u8) -> Self {
        self.0.push(v);
        self
    }
    fn bytes(mut self, n: usize) -> Self {
        self.0.extend(std::iter::repeat_n(0u8, n));
        self
    }
}

/// The log: `seconds` of 100 Hz IMU (`sensor_combined`), 5 Hz GPS, 10 Hz baro,
/// 50 Hz attitude and 10 Hz global position.
pub fn synthetic_ulog(seconds: u32) -> Vec<u8> {
    build(seconds, false)
}

/// [`synthetic_ulog`] with the IMU as PX4 v1.11+ `sensor_gyro` (100 Hz) and
/// `sensor_accel` (100 Hz, sampled 4 ms after the gyro) instead of
/// `sensor_combined`, the same rates.
pub fn synthetic_ulog_separate_imu(seconds: u32) -> Vec<u8> {
    build(seconds, true)
}

fn build(seconds: u32, separate_imu: bool) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&super::MAGIC);
    out.push(1);
    out.extend_from_slice(&T0_US.to_le_bytes());
    // Flag bits: no flags, no appended data.
    msg(&mut out, b'B', &[0u8; 40]);
    msg(&mut out, b'I', &key_value("char[9] sys_name", b"synthetic"));
    msg(
        &mut out,
        b'I',
        &key_value("uint32_t ver_sw_release", &1u32.to_le_bytes()),
    );
    msg(
        &mut out,
        b'M',
        &[[0u8].as_slice(), &key_value("char[3] perf", b"abc")].concat(),
    );
    msg(
        &mut out,
        b'P',
        &key_value("float EKF2_GPS_DELAY", &110f32.to_le_bytes()),
    );
    msg(
        &mut out,
        b'Q',
        &[
            [1u8].as_slice(),
            &key_value("int32_t SYS_AUTOSTART", &0i32.to_le_bytes()),
        ]
        .concat(),
    );
    let formats = [
        "vec3:float x;float y;float z;",
        "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;\
         int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;\
         uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;uint8_t[3] _padding0;",
        "vehicle_gps_position:uint64_t timestamp;uint64_t time_utc_usec;int32_t lat;int32_t lon;\
         int32_t alt;int32_t alt_ellipsoid;float s_variance_m_s;float eph;float epv;\
         float vel_n_m_s;float vel_e_m_s;float vel_d_m_s;uint8_t fix_type;bool vel_ned_valid;\
         uint8_t[6] _padding0;",
        "sensor_baro:uint64_t timestamp;uint32_t device_id;float pressure;float temperature;\
         uint8_t[4] _padding0;",
        "vehicle_attitude:uint64_t timestamp;float[4] q;vec3 delta;uint8_t[4] _padding0;",
        "vehicle_global_position:uint64_t timestamp;double lat;double lon;float alt;\
         float alt_ellipsoid;",
        "vehicle_local_position:uint64_t timestamp;float vx;float vy;float vz;",
        "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;\
         float y;float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;\
         uint8_t samples;uint8_t[4] _padding0;",
        "sensor_accel:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;\
         float y;float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;\
         uint8_t samples;uint8_t[4] _padding0;",
    ];
    for f in formats {
        msg(&mut out, b'F', f.as_bytes());
    }
    let names = [
        if separate_imu {
            "sensor_gyro"
        } else {
            "sensor_combined"
        },
        "vehicle_gps_position",
        "sensor_baro",
        "vehicle_attitude",
        "vehicle_global_position",
        "vehicle_local_position",
    ];
    for (i, n) in names.iter().enumerate() {
        add(&mut out, 0, i as u16, n);
    }
    add(&mut out, 1, 6, "sensor_baro");
    if separate_imu {
        add(&mut out, 0, 7, "sensor_accel");
    }
    let (lat, lon, h) = (47.4_f64, 8.5_f64, 500.0_f64);
    let steps = seconds * 100;
    for k in 0..=steps {
        let ts = T0_US + k as u64 * 10_000;
        let imu = Rec::default()
            .u64(ts)
            .f32(1e-3)
            .f32(-2e-3)
            .f32(5e-4)
            .u32(10_000)
            .i32(0)
            .f32(0.05)
            .f32(-0.03)
            .f32(-9.81)
            .u32(10_000)
            .u8(0);
        if separate_imu {
            let sensor = |t_sample: u64, v: [f32; 3]| {
                Rec::default()
                    .u64(t_sample + 1_000)
                    .u64(t_sample)
                    .u32(0x24_0001)
                    .f32(v[0])
                    .f32(v[1])
                    .f32(v[2])
                    .f32(35.0)
                    .u32(0)
                    .bytes(3)
                    .u8(1)
                    .0
            };
            data(&mut out, 0, &sensor(ts, [1e-3, -2e-3, 5e-4]));
            data(&mut out, 7, &sensor(ts + 4_000, [0.05, -0.03, -9.81]));
        } else {
            data(&mut out, 0, &imu.0); // trailing padding not logged
        }
        if k % 20 == 0 {
            let gps = Rec::default()
                .u64(ts)
                .u64(UTC_AT_BOOT_US + ts)
                .i32((lat * 1e7) as i32)
                .i32((lon * 1e7) as i32)
                .i32(((h - 48.0) * 1e3) as i32)
                .i32((h * 1e3) as i32)
                .f32(0.2)
                .f32(1.5)
                .f32(2.5)
                .f32(0.0)
                .f32(0.0)
                .f32(0.0)
                .u8(3)
                .u8(1);
            data(&mut out, 1, &gps.0);
        }
        if k % 10 == 0 {
            let baro = Rec::default().u64(ts).u32(7).f32(95_400.0).f32(20.0);
            data(&mut out, 2, &baro.0);
            data(&mut out, 6, &baro.0);
            let gp = Rec::default()
                .u64(ts)
                .f64(lat)
                .f64(lon)
                .f32(452.0)
                .f32(h as f32);
            data(&mut out, 4, &gp.0);
            let lp = Rec::default().u64(ts).f32(0.0).f32(0.0).f32(0.0);
            data(&mut out, 5, &lp.0);
        }
        if k % 2 == 0 {
            // Yaw 90 deg: q = (cos 45, 0, 0, sin 45).
            let c = std::f32::consts::FRAC_1_SQRT_2;
            let att = Rec::default()
                .u64(ts)
                .f32(c)
                .f32(0.0)
                .f32(0.0)
                .f32(c)
                .bytes(12);
            data(&mut out, 3, &att.0);
        }
        if k == steps / 2 {
            let mut l = vec![6u8];
            l.extend_from_slice(&ts.to_le_bytes());
            l.extend_from_slice(b"halfway");
            msg(&mut out, b'L', &l);
            msg(
                &mut out,
                b'S',
                &[0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12],
            );
            msg(&mut out, b'O', &25u16.to_le_bytes());
        }
    }
    out
}
