//! GPS time (GPST) for the whole workspace: the week length, the [`GpsTime`] type
//! (week + seconds of week), GPST calendar dates, GPST-as-Unix seconds (RTKLIB tag
//! files) and the week alignment helpers the readers and the run pipeline share.
//!
//! GPST has no leap seconds; RINEX GPS epochs (RINEX 3.04 §6.5/§8.2 "time system
//! GPS") are GPST calendar dates, so the conversions here involve none. A single f64
//! of seconds since 1980 would keep only ~0.1 us at today's 1.4e9 s; week + sow keeps
//! ~1e-10 s.
//!
//! Times in the navigator are GPS seconds of one reference week, continuing past
//! [`SECONDS_PER_WEEK`] when the data cross a week (see `types.rs`);
//! [`GpsTime::seconds_of_week`] and [`split_week`] convert between the two forms.

/// Seconds in a GPS week (the one definition in the workspace).
pub const SECONDS_PER_WEEK: f64 = 604_800.0;
/// Seconds in a GPS week, as an integer (for whole-second arithmetic).
pub const SECONDS_PER_WEEK_I64: i64 = SECONDS_PER_WEEK as i64;
/// Half a week: the wrap limit of IS-GPS-200 20.3.3.4.3 (tk) and 20.3.3.3.3.1.
pub const HALF_WEEK_S: f64 = SECONDS_PER_WEEK / 2.0;
/// The GPS epoch (1980-01-06 00:00:00 GPST) in GPST-as-Unix seconds: seconds since
/// 1970-01-01 00:00:00 counted in GPS time (no leap seconds), as RTKLIB tag files
/// and "gpst_unix" CSV times count.
pub const GPS_EPOCH_UNIX: i64 = 315_964_800;
/// Days from 1970-01-01 to the GPS epoch 1980-01-06.
const GPS_EPOCH_DAYS_FROM_1970: i64 = 3_657;

/// A GPST instant: `week` (continuous, not modulo 1024) and `sow` in [0, 604800).
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub struct GpsTime {
    /// GPS week since 1980-01-06.
    pub week: i32,
    /// Seconds of week \[s\], in [0, 604800) once normalised.
    pub sow: f64,
}

/// The leap seconds GPS - UTC \[s\] from each UTC instant on (Unix seconds of the
/// first second with the new value; IERS Bulletin C, 1981-07-01 .. 2017-01-01).
const LEAP_STEPS_UNIX: [(i64, f64); 18] = [
    (362_793_600, 1.0),    // 1981-07-01
    (394_329_600, 2.0),    // 1982-07-01
    (425_865_600, 3.0),    // 1983-07-01
    (489_024_000, 4.0),    // 1985-07-01
    (567_993_600, 5.0),    // 1988-01-01
    (631_152_000, 6.0),    // 1990-01-01
    (662_688_000, 7.0),    // 1991-01-01
    (709_948_800, 8.0),    // 1992-07-01
    (741_484_800, 9.0),    // 1993-07-01
    (773_020_800, 10.0),   // 1994-07-01
    (820_454_400, 11.0),   // 1996-01-01
    (867_715_200, 12.0),   // 1997-07-01
    (915_148_800, 13.0),   // 1999-01-01
    (1_136_073_600, 14.0), // 2006-01-01
    (1_230_768_000, 15.0), // 2009-01-01
    (1_341_100_800, 16.0), // 2012-07-01
    (1_435_708_800, 17.0), // 2015-07-01
    (1_483_228_800, 18.0), // 2017-01-01
];

/// GPS - UTC \[s\] at a UTC instant counted in seconds since the GPS epoch
/// (1980-01-06 00:00 UTC): exact at the leap seconds' dates.
pub fn leap_seconds_at_utc(utc_since_gps_epoch_s: f64) -> f64 {
    let unix = utc_since_gps_epoch_s + GPS_EPOCH_UNIX as f64;
    LEAP_STEPS_UNIX
        .iter()
        .rev()
        .find(|(from, _)| unix >= *from as f64)
        .map_or(0.0, |s| s.1)
}

/// GPS - UTC \[s\] at the start of GPS week `week` (18 s when unknown). A week with a
/// leap second in it changes value within the week: readers with UTC times use
/// [`leap_seconds_at_utc`].
pub fn leap_seconds(week: Option<u32>) -> f64 {
    let Some(w) = week else { return 18.0 };
    let gps_s = f64::from(w) * SECONDS_PER_WEEK;
    // UTC = GPS - leap: the value before the start is at most 18 s off, so look up
    // at GPS time - the value found there.
    let first = leap_seconds_at_utc(gps_s);
    leap_seconds_at_utc(gps_s - first)
}

/// A GPST calendar date and time of day (no leap seconds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpstCalendar {
    /// Year (proleptic Gregorian).
    pub year: i32,
    /// 1-12.
    pub month: u32,
    /// 1-31.
    pub day: u32,
    /// 0-23.
    pub hour: u32,
    /// 0-59.
    pub minute: u32,
    /// Seconds in [0, 60) \[s\].
    pub second: f64,
}

impl GpsTime {
    /// `week`, `sow` normalised so that sow is in [0, 604800).
    pub fn new(week: i32, sow: f64) -> Self {
        GpsTime { week, sow }.normalized()
    }

    /// The same instant with sow moved into [0, 604800) (week adjusted).
    pub fn normalized(self) -> Self {
        if !self.sow.is_finite() {
            return self;
        }
        let weeks = (self.sow / SECONDS_PER_WEEK).floor();
        let mut sow = self.sow - weeks * SECONDS_PER_WEEK;
        let mut week = self.week.saturating_add(weeks as i32);
        if sow >= SECONDS_PER_WEEK {
            sow -= SECONDS_PER_WEEK;
            week = week.saturating_add(1);
        }
        if sow < 0.0 {
            sow = 0.0;
        }
        GpsTime { week, sow }
    }

    /// `self - other` \[s\].
    pub fn diff_s(&self, other: &GpsTime) -> f64 {
        f64::from(self.week - other.week) * SECONDS_PER_WEEK + (self.sow - other.sow)
    }

    /// `self + dt_s`, normalised.
    pub fn add_s(&self, dt_s: f64) -> GpsTime {
        GpsTime::new(self.week, self.sow + dt_s)
    }

    /// Seconds of the reference week `week`: `sow` continued past a week (or negative)
    /// when `self` lies in a later (or earlier) week, as the navigator's times count.
    pub fn seconds_of_week(&self, week: i32) -> f64 {
        f64::from(self.week - week) * SECONDS_PER_WEEK + self.sow
    }

    /// From a GPST calendar date; None for an invalid date or time of day.
    pub fn from_calendar(c: &GpstCalendar) -> Option<GpsTime> {
        let dim = days_in_month(i64::from(c.year), c.month);
        if dim == 0
            || c.day == 0
            || c.day > dim
            || c.hour > 23
            || c.minute > 59
            || !(0.0..61.0).contains(&c.second)
        {
            return None;
        }
        let days = days_from_civil(i64::from(c.year), c.month, c.day) - GPS_EPOCH_DAYS_FROM_1970;
        let week = days.div_euclid(7);
        let dow = days.rem_euclid(7);
        let week = i32::try_from(week).ok()?;
        let sow =
            (dow * 86_400 + i64::from(c.hour) * 3_600 + i64::from(c.minute) * 60) as f64 + c.second;
        Some(GpsTime::new(week, sow))
    }

    /// To a GPST calendar date (seconds keep their fraction).
    pub fn to_calendar(&self) -> GpstCalendar {
        let t = self.normalized();
        let whole = t.sow.floor();
        let frac = t.sow - whole;
        let whole = whole as i64;
        let days = i64::from(t.week) * 7 + whole.div_euclid(86_400) + GPS_EPOCH_DAYS_FROM_1970;
        let sod = whole.rem_euclid(86_400);
        let (year, month, day) = civil_from_days(days);
        GpstCalendar {
            year: year as i32,
            month,
            day,
            hour: (sod / 3_600) as u32,
            minute: ((sod % 3_600) / 60) as u32,
            second: (sod % 60) as f64 + frac,
        }
    }
}

/// Days from 1970-01-01 to a proleptic Gregorian date (days-from-civil algorithm).
pub fn days_from_civil(year: i64, month: u32, day: u32) -> i64 {
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let m = i64::from(month);
    let mp = if m > 2 { m - 3 } else { m + 9 };
    let doy = (153 * mp + 2) / 5 + i64::from(day) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// Inverse of [`days_from_civil`].
pub fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(month <= 2), month, day)
}

/// Days in a month (1-12) of a year; 0 for an invalid month.
pub fn days_in_month(year: i64, month: u32) -> u32 {
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    match month {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if leap => 29,
        2 => 28,
        _ => 0,
    }
}

/// `dt` wrapped into \[-302400, 302400\] s (IS-GPS-200 20.3.3.4.3, tk; 20.3.3.3.3.1).
pub fn wrap_half_week(dt_s: f64) -> f64 {
    if dt_s > HALF_WEEK_S {
        dt_s - SECONDS_PER_WEEK
    } else if dt_s < -HALF_WEEK_S {
        dt_s + SECONDS_PER_WEEK
    } else {
        dt_s
    }
}

/// Normalise (week, t) so that t is in [0, 604800): the week moves by whole weeks
/// (never below week 0). t already in range is returned unchanged.
pub fn split_week(week: u32, t: f64) -> (u32, f64) {
    if (0.0..SECONDS_PER_WEEK).contains(&t) {
        return (week, t);
    }
    let k = (t / SECONDS_PER_WEEK).floor();
    (
        (week as i64 + k as i64).max(0) as u32,
        t - k * SECONDS_PER_WEEK,
    )
}

/// GPST-as-Unix seconds -> (GPS week, seconds of week). None before the GPS epoch or
/// for non-finite input.
pub fn gpst_unix_to_week_sow(unix_s: f64) -> Option<(u32, f64)> {
    if !unix_s.is_finite() {
        return None;
    }
    let whole = unix_s.floor();
    if whole.abs() > 1e15 {
        return None;
    }
    gpst_unix_parts_to_week_sow(whole as i64, unix_s - whole)
}

/// GPST-as-Unix time given as whole seconds plus a fraction (keeps full precision,
/// as in RTKLIB tag files) -> (GPS week, seconds of week).
pub fn gpst_unix_parts_to_week_sow(whole_s: i64, frac_s: f64) -> Option<(u32, f64)> {
    if !frac_s.is_finite() {
        return None;
    }
    let since = whole_s.checked_sub(GPS_EPOCH_UNIX)?;
    let mut week = since.div_euclid(SECONDS_PER_WEEK_I64);
    let mut sow = since.rem_euclid(SECONDS_PER_WEEK_I64) as f64 + frac_s;
    // Carry a fraction outside [0, 1) into the week if needed.
    if sow >= SECONDS_PER_WEEK {
        sow -= SECONDS_PER_WEEK;
        week += 1;
    } else if sow < 0.0 {
        sow += SECONDS_PER_WEEK;
        week -= 1;
    }
    u32::try_from(week).ok().map(|w| (w, sow))
}

/// (GPS week, seconds of week) -> GPST-as-Unix seconds. `sow` may exceed a week.
pub fn week_sow_to_gpst_unix(week: u32, sow: f64) -> f64 {
    (GPS_EPOCH_UNIX + i64::from(week) * SECONDS_PER_WEEK_I64) as f64 + sow
}

#[cfg(test)]
mod tests {
    use super::*;

    /// GPS - UTC at the leap seconds' own dates, not at week boundaries: 2009-01-01
    /// (mid-week 1512), 2015-07-01 (mid-week 1851), 1999-01-01 (mid-week 990).
    #[test]
    fn leap_seconds_change_on_their_dates() {
        let utc = |y: i64, m: u32, d: u32, h: f64| {
            (days_from_civil(y, m, d) - GPS_EPOCH_DAYS_FROM_1970) as f64 * 86_400.0 + h * 3600.0
        };
        assert_eq!(leap_seconds_at_utc(utc(2008, 12, 31, 23.99)), 14.0);
        assert_eq!(leap_seconds_at_utc(utc(2009, 1, 2, 0.0)), 15.0);
        assert_eq!(leap_seconds_at_utc(utc(2015, 6, 29, 12.0)), 16.0);
        assert_eq!(leap_seconds_at_utc(utc(2015, 7, 1, 0.0)), 17.0);
        assert_eq!(leap_seconds_at_utc(utc(1998, 12, 28, 0.0)), 12.0);
        assert_eq!(leap_seconds_at_utc(utc(1980, 1, 6, 0.0)), 0.0);
        assert_eq!(leap_seconds_at_utc(utc(2024, 3, 18, 0.0)), 18.0);
        // By week: the value at the week's start.
        assert_eq!(leap_seconds(Some(1512)), 14.0);
        assert_eq!(leap_seconds(Some(1513)), 15.0);
        assert_eq!(leap_seconds(Some(2374)), 18.0);
        assert_eq!(leap_seconds(None), 18.0);
    }

    fn cal(year: i32, month: u32, day: u32, hour: u32, minute: u32, second: f64) -> GpstCalendar {
        GpstCalendar {
            year,
            month,
            day,
            hour,
            minute,
            second,
        }
    }

    #[test]
    fn gps_epoch_is_week_zero() {
        let t = GpsTime::from_calendar(&cal(1980, 1, 6, 0, 0, 0.0)).unwrap();
        assert_eq!((t.week, t.sow), (0, 0.0));
    }

    #[test]
    fn known_date() {
        // 2025-08-28 is a Thursday of GPS week 2381 (the walk_0827 nav file's week).
        let t = GpsTime::from_calendar(&cal(2025, 8, 28, 18, 0, 0.0)).unwrap();
        assert_eq!(t.week, 2381);
        assert_eq!(t.sow, 4.0 * 86_400.0 + 18.0 * 3_600.0);
        let c = t.to_calendar();
        assert_eq!(c, cal(2025, 8, 28, 18, 0, 0.0));
    }

    #[test]
    fn calendar_round_trip_keeps_fraction() {
        let t = GpsTime::new(2381, 410_400.123_456_789);
        let back = GpsTime::from_calendar(&t.to_calendar()).unwrap();
        assert_eq!(back.week, t.week);
        assert!((back.sow - t.sow).abs() < 1e-9);
        // Across a leap day and a year end.
        for (y, m, d) in [(2024, 2, 29), (2023, 12, 31), (2000, 3, 1)] {
            let t = GpsTime::from_calendar(&cal(y, m, d, 23, 59, 59.5)).unwrap();
            assert_eq!(t.to_calendar(), cal(y, m, d, 23, 59, 59.5));
        }
    }

    #[test]
    fn invalid_dates_rejected() {
        assert!(GpsTime::from_calendar(&cal(2023, 2, 29, 0, 0, 0.0)).is_none());
        assert!(GpsTime::from_calendar(&cal(2023, 13, 1, 0, 0, 0.0)).is_none());
        assert!(GpsTime::from_calendar(&cal(2023, 1, 1, 24, 0, 0.0)).is_none());
        assert!(GpsTime::from_calendar(&cal(2023, 1, 1, 0, 0, -1.0)).is_none());
    }

    #[test]
    fn add_diff_and_normalise() {
        let t = GpsTime::new(2000, 604_799.5);
        let u = t.add_s(1.0);
        assert_eq!((u.week, u.sow), (2001, 0.5));
        assert_eq!(u.diff_s(&t), 1.0);
        let v = GpsTime::new(2000, -0.25);
        assert_eq!((v.week, v.sow), (1999, 604_799.75));
        let w = t.add_s(-3.0 * SECONDS_PER_WEEK);
        assert_eq!((w.week, w.sow), (1997, 604_799.5));
        // Sub-nanosecond differences survive at today's week numbers.
        let a = GpsTime::new(2381, 100.0);
        let b = a.add_s(1e-10);
        assert!((b.diff_s(&a) - 1e-10).abs() < 1e-13);
    }

    #[test]
    fn seconds_of_week_and_split() {
        let t = GpsTime::new(2375, 12.5);
        assert_eq!(t.seconds_of_week(2374), 604_812.5);
        assert_eq!(t.seconds_of_week(2375), 12.5);
        assert_eq!(split_week(2374, 604_812.5), (2375, 12.5));
        assert_eq!(split_week(2374, 100.0), (2374, 100.0));
        assert_eq!(split_week(2374, -0.5), (2373, 604_799.5));
        assert_eq!(split_week(0, -10.0), (0, 604_790.0));
    }

    #[test]
    fn unix_round_trip() {
        assert_eq!(gpst_unix_to_week_sow(315_964_800.0), Some((0, 0.0)));
        assert_eq!(gpst_unix_to_week_sow(315_964_799.5), None);
        for &(w, sow) in &[
            (0u32, 0.0),
            (2374, 243_258.499),
            (2379, 604_799.75),
            (1, 3.0),
        ] {
            let u = week_sow_to_gpst_unix(w, sow);
            let (w2, sow2) = gpst_unix_to_week_sow(u).unwrap();
            assert_eq!(w2, w);
            assert!((sow2 - sow).abs() < 1e-6, "{sow} {sow2}");
        }
        // Parts keep precision and carry.
        assert_eq!(
            gpst_unix_parts_to_week_sow(GPS_EPOCH_UNIX + SECONDS_PER_WEEK_I64 - 1, 1.0),
            Some((1, 0.0))
        );
        assert_eq!(
            gpst_unix_parts_to_week_sow(GPS_EPOCH_UNIX + SECONDS_PER_WEEK_I64, -0.25),
            Some((0, 604_799.75))
        );
        assert_eq!(gpst_unix_to_week_sow(f64::INFINITY), None);
        assert_eq!(gpst_unix_to_week_sow(-1e300), None);
        assert_eq!(gpst_unix_parts_to_week_sow(i64::MIN, 0.5), None);
        let _ = gpst_unix_parts_to_week_sow(i64::MAX, 0.5);
    }

    #[test]
    fn wrap() {
        assert_eq!(wrap_half_week(302_401.0), 302_401.0 - SECONDS_PER_WEEK);
        assert_eq!(wrap_half_week(-302_401.0), -302_401.0 + SECONDS_PER_WEEK);
        assert_eq!(wrap_half_week(100.0), 100.0);
    }
}
