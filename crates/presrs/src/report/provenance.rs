//! When, by what and how a report was made (the line every report page ends with).

use std::fmt::Write as _;

/// When, by what and how a report was made: presrs's version, the time (UTC) and the command line.
pub fn provenance(command_line: Option<&str>) -> String {
    let mut text = format!(
        "Made by presrs {} on {}",
        env!("CARGO_PKG_VERSION"),
        utc_now()
    );
    if let Some(command) = command_line {
        let _ = write!(text, " with `{command}`");
    }
    text.push('.');
    text
}

/// The current time, `YYYY-MM-DD HH:MM UTC`.
fn utc_now() -> String {
    utc_minute(jiff::Timestamp::now())
}

/// `time` to the minute, `YYYY-MM-DD HH:MM UTC` (the proleptic Gregorian calendar).
fn utc_minute(time: jiff::Timestamp) -> String {
    time.strftime("%Y-%m-%d %H:%M UTC").to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_gregorian_utc_minutes() {
        let at = |seconds: i64| utc_minute(jiff::Timestamp::from_second(seconds).unwrap());
        const DAY: i64 = 86_400;
        assert_eq!(at(0), "1970-01-01 00:00 UTC");
        assert_eq!(at(59 * DAY), "1970-03-01 00:00 UTC");
        // A leap day, the last second of its last minute.
        assert_eq!(at(11_016 * DAY + DAY - 1), "2000-02-29 23:59 UTC");
        assert_eq!(at(11_017 * DAY), "2000-03-01 00:00 UTC");
        // 2100 is no leap year.
        assert_eq!(at(47_540 * DAY), "2100-02-28 00:00 UTC");
        assert_eq!(at(47_541 * DAY), "2100-03-01 00:00 UTC");
        assert_eq!(
            at(20_417 * DAY + 13 * 3600 + 7 * 60 + 30),
            "2025-11-25 13:07 UTC"
        );
        assert_eq!(at(-60), "1969-12-31 23:59 UTC");
    }
}
