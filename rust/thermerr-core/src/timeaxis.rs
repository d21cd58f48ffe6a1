//! The time axis of a run, shared by every part that needs it: the names of a run's time columns,
//! the reading of ISO-8601 date-times (the run reader and the edge's stream read them with the
//! same code), and the sampling step the thermal simulation's thinning, a failing-sensor guard's
//! clock and a model's temperature history use.

/// A run's time in seconds since its start (formats.md).
pub const TIME_S: &str = "time_s";
/// The ISO-8601 date-time column a run may carry instead of [`TIME_S`] (formats.md): a logger's
/// timestamps, read as seconds since the first row.
pub const TIME_ISO: &str = "time";

/// Which of a header's columns is the time, and how it is written: `time_s` if there is one,
/// else `time` (then its ISO-8601 cells are read by an [`IsoClock`]). `None` without either.
pub fn time_column<S: AsRef<str>>(names: &[S]) -> Option<(usize, TimeKind)> {
    let find = |n: &str| names.iter().position(|s| s.as_ref() == n);
    find(TIME_S)
        .map(|k| (k, TimeKind::Seconds))
        .or_else(|| find(TIME_ISO).map(|k| (k, TimeKind::Iso)))
}

/// How a run's time column is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeKind {
    /// `time_s`: numbers of seconds
    Seconds,
    /// `time`: ISO-8601 date-times
    Iso,
}

impl TimeKind {
    /// The column's name.
    pub fn name(self) -> &'static str {
        match self {
            TimeKind::Seconds => TIME_S,
            TimeKind::Iso => TIME_ISO,
        }
    }
}

/// Reads the ISO-8601 date-times of one column, in order, as seconds since 1970-01-01T00:00:00Z.
///
/// A cell is `YYYY-MM-DD`, then `T` or a space and `hh:mm[:ss[.fraction]]`, with or without a UTC
/// offset (`Z`, `+01:00`); or the date day first with dots, `DD.MM.YYYY hh:mm[:ss[.fraction]]`,
/// as a logger or a spreadsheet in a German locale writes it (dots are day first in every
/// locale that writes them; a date with slashes, day or month first by locale, is refused). With an offset the instant is exact, so a run that crosses a change
/// of daylight saving time keeps counting real seconds. Without one the clock is read as it is
/// written (no time zone is assumed), so such a change makes time jump or step back, which the
/// run reader refuses naming the row. A column must stay with one style: a cell with an offset
/// after cells without one (or the other way round) is refused, as the two cannot be ordered.
#[derive(Clone, Debug, Default)]
pub struct IsoClock {
    /// whether the column's first date-time carried a UTC offset
    zoned: Option<bool>,
}

impl IsoClock {
    pub fn new() -> Self {
        Self::default()
    }

    /// The cell's seconds since the epoch; an empty cell or `NaN` is `NaN` (a missing time, which
    /// the caller refuses where it must); the reason when the cell is not an ISO-8601 date-time.
    pub fn seconds(&mut self, cell: &str) -> Result<f64, String> {
        let c = cell.trim();
        if c.is_empty() || c.eq_ignore_ascii_case("nan") {
            return Ok(f64::NAN);
        }
        let dotted = day_first(c);
        let iso = dotted.as_deref().unwrap_or(c);
        let (ts, zoned) = match iso.parse::<jiff::Timestamp>() {
            Ok(ts) => (ts, true),
            Err(_) => match iso.parse::<jiff::civil::DateTime>() {
                Ok(dt) => match jiff::tz::TimeZone::UTC.to_timestamp(dt) {
                    Ok(ts) => (ts, false),
                    Err(e) => return Err(format!("{c:?}: {e}")),
                },
                Err(_) => {
                    let hint = if c.parse::<f64>().is_ok() {
                        " (a number of seconds belongs in a `time_s` column)"
                    } else if c.contains('/') {
                        " (a date with slashes is day or month first by locale: write it as \
                         ISO-8601)"
                    } else {
                        ""
                    };
                    return Err(format!(
                        "{c:?} is not an ISO-8601 date-time such as 2025-03-04T08:00:15 or \
                         2025-03-04 08:00:15+01:00, nor a day-first one such as 04.03.2025 \
                         08:00:15{hint}"
                    ));
                }
            },
        };
        match self.zoned {
            None => self.zoned = Some(zoned),
            Some(z) if z != zoned => {
                return Err(format!(
                    "{c:?} has {} UTC offset but the column's first date-time {}: write every \
                     time of a run the same way",
                    if zoned { "a" } else { "no" },
                    if z { "has one" } else { "does not" }
                ))
            }
            Some(_) => {}
        }
        Ok(ts.as_second() as f64 + f64::from(ts.subsec_nanosecond()) * 1e-9)
    }
}

/// `DD.MM.YYYY hh:mm[:ss[.fraction]]` (day and month of one or two digits, a space or `T`, an
/// hour of one or two) as ISO-8601 (`YYYY-MM-DDThh:mm...`); `None` for any other cell.
fn day_first(c: &str) -> Option<String> {
    let (date, time) = c.split_once([' ', 'T'])?;
    let mut d = date.split('.');
    let (day, month, year) = (d.next()?, d.next()?, d.next()?);
    let digits = |s: &str, lo: usize, hi: usize| {
        (lo..=hi).contains(&s.len()) && s.bytes().all(|b| b.is_ascii_digit())
    };
    if d.next().is_some() || !digits(day, 1, 2) || !digits(month, 1, 2) || !digits(year, 4, 4) {
        return None;
    }
    let time = time.trim_start();
    let (hour, rest) = time.split_once(':')?;
    if !digits(hour, 1, 2) {
        return None;
    }
    Some(format!("{year}-{month:0>2}-{day:0>2}T{hour:0>2}:{rest}"))
}

/// The median step of a time axis (s), the upper middle of the steps for an even count; `None`
/// with fewer than two samples or no positive median step. Non-finite steps are ignored.
pub fn median_step(t: &[f64]) -> Option<f64> {
    let mut d: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|v| v.is_finite())
        .collect();
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    let (_, m, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    (*m > 0.0).then_some(*m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_upper_middle_step() {
        assert_eq!(median_step(&[0.0, 15.0, 30.0, 60.0, 75.0]), Some(15.0));
        assert_eq!(median_step(&[0.0, 10.0, 30.0]), Some(20.0));
        assert_eq!(median_step(&[0.0]), None);
        assert_eq!(median_step(&[3.0, 3.0, 3.0]), None);
    }

    #[test]
    fn iso_date_times_in_seconds() {
        let mut c = IsoClock::new();
        // 2025-03-04T08:00:00Z = 1741075200 s (date -u -d 2025-03-04T08:00:00 +%s)
        assert_eq!(c.seconds("2025-03-04T08:00:00").unwrap(), 1_741_075_200.0);
        assert_eq!(c.seconds("2025-03-04 08:00:15").unwrap(), 1_741_075_215.0);
        assert_eq!(
            c.seconds(" 2025-03-04T08:00:15.5 ").unwrap(),
            1_741_075_215.5
        );
        assert!(c.seconds("").unwrap().is_nan());
        let e = c.seconds("2025-03-04T08:00:30+01:00").unwrap_err();
        assert!(e.contains("has a UTC offset"), "{e}");
        // day first with dots, as a German logger writes: the same instants
        assert_eq!(c.seconds("04.03.2025 08:00").unwrap(), 1_741_075_200.0);
        assert_eq!(c.seconds("4.3.2025 8:00:15").unwrap(), 1_741_075_215.0);
        assert_eq!(c.seconds("04.03.2025T08:00:15.5").unwrap(), 1_741_075_215.5);
        for bad in [
            "04/03/2025 08:00",
            "32.03.2025 08:00",
            "04.03.25 08:00",
            "04.03.2025",
        ] {
            let e = c.seconds(bad).unwrap_err();
            assert!(e.contains("not an ISO-8601"), "{e}");
        }
        assert!(c
            .seconds("04/03/2025 08:00")
            .unwrap_err()
            .contains("slashes"));
        let e = c.seconds("32.03.2025 08:00").unwrap_err();
        assert!(e.starts_with("\"32.03.2025 08:00\""), "{e}");
        let e = c.seconds("1741075200").unwrap_err();
        assert!(e.contains("time_s"), "{e}");
    }

    #[test]
    fn offsets_give_the_instant() {
        // across the end of summer time in Berlin: 02:59:45+02:00, then 02:00:00+01:00 is 15 s on
        let mut c = IsoClock::new();
        let a = c.seconds("2025-10-26T02:59:45+02:00").unwrap();
        let b = c.seconds("2025-10-26T02:00:00+01:00").unwrap();
        assert_eq!(b - a, 15.0);
        assert_eq!(c.seconds("2025-10-26T01:00:15Z").unwrap() - a, 30.0);
        assert!(c
            .seconds("2025-10-26T02:00:30")
            .unwrap_err()
            .contains("has no UTC offset"));
    }

    #[test]
    fn the_time_column_of_a_header() {
        assert_eq!(
            time_column(&["T_a", "time_s"]),
            Some((1, TimeKind::Seconds))
        );
        assert_eq!(
            time_column(&["time", "T_a", "time_s"]),
            Some((2, TimeKind::Seconds))
        );
        assert_eq!(time_column(&["time", "T_a"]), Some((0, TimeKind::Iso)));
        assert_eq!(time_column(&["T_a"]), None);
    }
}
