//! GPS time helpers of the file formats (no leap seconds anywhere: everything here is
//! GPST): the RTKLIB calendar form (`YYYY/MM/DD HH:MM:SS.sss`) -> (GPS week, seconds
//! of week), and back. The GPS time type, the week length and the "GPST as Unix
//! seconds" conversions (RTKLIB tag files) are `navfuse_core::time`, re-exported here.

use std::fmt;

// The week length, the GPS epoch, the GPST-as-Unix conversions and the proleptic
// Gregorian day arithmetic live in the core (the workspace's one GPS time module).
pub use navfuse_core::time::{
    civil_from_days, days_from_civil, days_in_month, gpst_unix_parts_to_week_sow,
    gpst_unix_to_week_sow, week_sow_to_gpst_unix, GPS_EPOCH_UNIX, SECONDS_PER_WEEK,
    SECONDS_PER_WEEK_I64,
};

/// A GPST calendar date and time of day.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calendar {
    pub year: i64,
    pub month: u32,
    pub day: u32,
    pub hour: u32,
    pub minute: u32,
    /// Seconds, 0 <= second < 60 (values up to 61 are accepted on input and carried).
    pub second: f64,
}

impl fmt::Display for Calendar {
    /// `YYYY/MM/DD HH:MM:SS.sss` (the RTKLIB form; seconds rounded to the
    /// millisecond, but never up to 60).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ms_total = (self.second * 1000.0).round().clamp(0.0, 59_999.0);
        let s = (ms_total / 1000.0).floor();
        let ms = ms_total - s * 1000.0;
        write!(
            f,
            "{:04}/{:02}/{:02} {:02}:{:02}:{:02}.{:03}",
            self.year, self.month, self.day, self.hour, self.minute, s as u32, ms as u32
        )
    }
}

/// GPST calendar -> (GPS week, seconds of week). None if the date or time of day is
/// invalid, the seconds are not finite, or the time is before the GPS epoch.
pub fn calendar_to_week_sow(c: &Calendar) -> Option<(u32, f64)> {
    if !(1..=12).contains(&c.month)
        || c.day == 0
        || c.day > days_in_month(c.year, c.month)
        || c.hour > 23
        || c.minute > 59
        || !c.second.is_finite()
        || !(0.0..61.0).contains(&c.second)
    {
        return None;
    }
    if !(1900..=9999).contains(&c.year) {
        return None;
    }
    let days = days_from_civil(c.year, c.month, c.day) - days_from_civil(1980, 1, 6);
    if days < 0 {
        return None;
    }
    let week = days / 7;
    let sod = i64::from(c.hour) * 3600 + i64::from(c.minute) * 60;
    let sow = ((days % 7) * 86_400 + sod) as f64 + c.second;
    u32::try_from(week).ok().map(|w| (w, sow))
}

/// (GPS week, seconds of week) -> GPST calendar. `sow` may be negative or exceed a
/// week (it is normalised); it is clamped to +-1e12 s, and a non-finite `sow` gives
/// the week start.
pub fn week_sow_to_calendar(week: u32, sow: f64) -> Calendar {
    let sow = if sow.is_finite() {
        sow.clamp(-1e12, 1e12)
    } else {
        0.0
    };
    let whole = sow.floor();
    let frac = sow - whole;
    let total = i64::from(week) * SECONDS_PER_WEEK_I64 + whole as i64; // since GPS epoch
    let days = total.div_euclid(86_400);
    let sod = total.rem_euclid(86_400);
    let (year, month, day) = civil_from_days(days_from_civil(1980, 1, 6) + days);
    Calendar {
        year,
        month,
        day,
        hour: (sod / 3600) as u32,
        minute: ((sod % 3600) / 60) as u32,
        second: (sod % 60) as f64 + frac,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cal(y: i64, mo: u32, d: u32, h: u32, mi: u32, s: f64) -> Calendar {
        Calendar {
            year: y,
            month: mo,
            day: d,
            hour: h,
            minute: mi,
            second: s,
        }
    }

    #[test]
    fn gps_epoch() {
        assert_eq!(days_from_civil(1970, 1, 1), 0);
        assert_eq!(days_from_civil(1980, 1, 6) * 86_400, GPS_EPOCH_UNIX);
        assert_eq!(
            calendar_to_week_sow(&cal(1980, 1, 6, 0, 0, 0.0)),
            Some((0, 0.0))
        );
        assert_eq!(calendar_to_week_sow(&cal(1980, 1, 5, 23, 59, 59.0)), None);
        assert_eq!(gpst_unix_to_week_sow(315_964_800.0), Some((0, 0.0)));
        assert_eq!(gpst_unix_to_week_sow(315_964_799.5), None);
    }

    #[test]
    fn known_dates() {
        // 2025-07-08 is a Tuesday of GPS week 2374 (week 2374 starts Sun 2025-07-06).
        let (w, sow) = calendar_to_week_sow(&cal(2025, 7, 8, 19, 34, 18.499)).unwrap();
        assert_eq!(w, 2374);
        assert!((sow - (2.0 * 86400.0 + 19.0 * 3600.0 + 34.0 * 60.0 + 18.499)).abs() < 1e-9);
        // Week 1024 rollover day, 1999-08-22.
        assert_eq!(
            calendar_to_week_sow(&cal(1999, 8, 22, 0, 0, 0.0)),
            Some((1024, 0.0))
        );
        // Week 2048 rollover, 2019-04-07.
        assert_eq!(
            calendar_to_week_sow(&cal(2019, 4, 7, 0, 0, 0.0)),
            Some((2048, 0.0))
        );
        // Leap day.
        let (w, sow) = calendar_to_week_sow(&cal(2024, 2, 29, 12, 0, 0.0)).unwrap();
        let back = week_sow_to_calendar(w, sow);
        assert_eq!(
            (back.year, back.month, back.day, back.hour),
            (2024, 2, 29, 12)
        );
    }

    #[test]
    fn invalid_calendar() {
        assert_eq!(calendar_to_week_sow(&cal(2023, 2, 29, 0, 0, 0.0)), None);
        assert_eq!(calendar_to_week_sow(&cal(2023, 13, 1, 0, 0, 0.0)), None);
        assert_eq!(calendar_to_week_sow(&cal(2023, 1, 1, 24, 0, 0.0)), None);
        assert_eq!(calendar_to_week_sow(&cal(2023, 1, 1, 0, 60, 0.0)), None);
        assert_eq!(calendar_to_week_sow(&cal(2023, 1, 1, 0, 0, f64::NAN)), None);
        assert_eq!(calendar_to_week_sow(&cal(2023, 1, 1, 0, 0, -1.0)), None);
    }

    #[test]
    fn calendar_round_trip_many_days() {
        let start = days_from_civil(1980, 1, 6);
        for d in (0..20_000).step_by(7 * 13 + 3) {
            let (y, m, dd) = civil_from_days(start + d);
            assert_eq!(days_from_civil(y, m, dd), start + d);
            let c = cal(y, m, dd, 13, 7, 42.125);
            let (w, sow) = calendar_to_week_sow(&c).unwrap();
            assert_eq!(week_sow_to_calendar(w, sow), c);
        }
    }

    #[test]
    fn extreme_inputs_do_not_panic() {
        let _ = week_sow_to_calendar(u32::MAX, 1e300);
        let _ = week_sow_to_calendar(0, -1e300);
        let _ = week_sow_to_calendar(0, f64::NAN).to_string();
        assert_eq!(gpst_unix_to_week_sow(f64::INFINITY), None);
        assert_eq!(gpst_unix_to_week_sow(-1e300), None);
        assert_eq!(gpst_unix_parts_to_week_sow(i64::MIN, 0.5), None);
        let _ = gpst_unix_parts_to_week_sow(i64::MAX, 0.5);
    }

    #[test]
    fn calendar_display() {
        let c = week_sow_to_calendar(2374, 2.0 * 86400.0 + 70461.854);
        assert_eq!(c.to_string(), "2025/07/08 19:34:21.854");
    }
}
