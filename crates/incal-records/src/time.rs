//! RFC 3339 UTC times, to the second, without a date-time dependency.
//!
//! Stored form: `YYYY-MM-DDTHH:MM:SSZ` (fixed width, so text order is
//! time order). Accepted input: that form, any RFC 3339 offset
//! (`2025-03-14T10:26:53+01:00` is stored as `2025-03-14T09:26:53Z`), a
//! fraction of a second that is zero, or a bare date `YYYY-MM-DD`
//! (midnight UTC). Years 0001 to 9999. Civil-date arithmetic: H. Hinnant,
//! "chrono-Compatible Low-Level Date Algorithms" (proleptic Gregorian).

use std::time::{SystemTime, UNIX_EPOCH};

/// Days since 1970-01-01 of the civil date `y-m-d`.
fn days_from_civil(y: i64, m: u32, d: u32) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = if y >= 0 { y } else { y - 399 } / 400;
    let yoe = y - era * 400; // [0, 399]
    let mp = i64::from((m + 9) % 12); // March = 0
    let doy = (153 * mp + 2) / 5 + i64::from(d) - 1; // [0, 365]
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy; // [0, 146096]
    era * 146_097 + doe - 719_468
}

/// The civil date `(y, m, d)` of `z` days since 1970-01-01.
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = if z >= 0 { z } else { z - 146_096 } / 146_097;
    let doe = z - era * 146_097; // [0, 146096]
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365; // [0, 399]
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100); // [0, 365]
    let mp = (5 * doy + 2) / 153; // [0, 11]
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400;
    (if m <= 2 { y + 1 } else { y }, m, d)
}

fn days_in_month(y: i64, m: u32) -> u32 {
    match m {
        4 | 6 | 9 | 11 => 30,
        2 if (y % 4 == 0 && y % 100 != 0) || y % 400 == 0 => 29,
        2 => 28,
        _ => 31,
    }
}

/// `secs` since the Unix epoch as `YYYY-MM-DDTHH:MM:SSZ`.
pub fn format_utc(secs: i64) -> String {
    let days = secs.div_euclid(86_400);
    let sod = secs.rem_euclid(86_400);
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        sod / 3600,
        (sod / 60) % 60,
        sod % 60
    )
}

/// The current time, to the second, in the stored form.
pub fn now_utc() -> String {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64);
    format_utc(secs)
}

/// Seconds since the Unix epoch of an RFC 3339 time (module docs for
/// what is accepted); the error says what is wrong with `text`.
pub fn parse_utc(text: &str) -> Result<i64, String> {
    let bad = |why: &str| format!("'{text}' is not an RFC 3339 time ({why})");
    let b = text.as_bytes();
    let num = |range: std::ops::Range<usize>| -> Result<i64, String> {
        let s = text.get(range).ok_or_else(|| bad("too short"))?;
        if s.bytes().all(|c| c.is_ascii_digit()) && !s.is_empty() {
            s.parse::<i64>().map_err(|_| bad("not a number"))
        } else {
            Err(bad("expected YYYY-MM-DDTHH:MM:SSZ"))
        }
    };
    if b.len() < 10 || b[4] != b'-' || b[7] != b'-' {
        return Err(bad("expected YYYY-MM-DDTHH:MM:SSZ or YYYY-MM-DD"));
    }
    let (y, mo, d) = (num(0..4)?, num(5..7)?, num(8..10)?);
    if !(1..=9999).contains(&y) || !(1..=12).contains(&mo) {
        return Err(bad("no such date"));
    }
    let (mo, d) = (mo as u32, d as u32);
    if d == 0 || i64::from(d) > i64::from(days_in_month(y, mo)) {
        return Err(bad("no such date"));
    }
    let days = days_from_civil(y, mo, d);
    if b.len() == 10 {
        return Ok(days * 86_400);
    }
    if !matches!(b[10], b'T' | b't' | b' ') || b.len() < 19 || b[13] != b':' || b[16] != b':' {
        return Err(bad("expected YYYY-MM-DDTHH:MM:SSZ"));
    }
    let (h, mi, s) = (num(11..13)?, num(14..16)?, num(17..19)?);
    if h > 23 || mi > 59 || s > 59 {
        return Err(bad("no such time of day"));
    }
    let mut rest = &text[19..];
    if let Some(frac) = rest.strip_prefix('.') {
        let digits = frac.bytes().take_while(u8::is_ascii_digit).count();
        if digits == 0 {
            return Err(bad("empty fraction of a second"));
        }
        if frac[..digits].bytes().any(|c| c != b'0') {
            return Err(bad("records keep whole seconds"));
        }
        rest = &frac[digits..];
    }
    let offset = match rest {
        "Z" | "z" => 0,
        _ if rest.len() == 6
            && matches!(rest.as_bytes()[0], b'+' | b'-')
            && rest.as_bytes()[3] == b':' =>
        {
            let oh = num(text.len() - 5..text.len() - 3)?;
            let om = num(text.len() - 2..text.len())?;
            if oh > 23 || om > 59 {
                return Err(bad("no such offset"));
            }
            let o = (oh * 60 + om) * 60;
            if rest.starts_with('-') {
                -o
            } else {
                o
            }
        }
        "" => return Err(bad("no offset: give Z for UTC or +HH:MM")),
        _ => return Err(bad("expected Z or +HH:MM after the seconds")),
    };
    Ok(days * 86_400 + h * 3600 + mi * 60 + s - offset)
}

/// `text` (module docs) in the stored form `YYYY-MM-DDTHH:MM:SSZ`.
pub fn normalize_utc(text: &str) -> Result<String, String> {
    parse_utc(text).map(format_utc)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_known_dates() {
        assert_eq!(format_utc(0), "1970-01-01T00:00:00Z");
        assert_eq!(format_utc(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(format_utc(-1), "1969-12-31T23:59:59Z");
        for s in [
            "0001-01-01T00:00:00Z",
            "1999-12-31T23:59:59Z",
            "2024-02-29T12:34:56Z",
            "9999-12-31T23:59:59Z",
        ] {
            assert_eq!(normalize_utc(s).unwrap(), s);
        }
        assert_eq!(parse_utc("2025-03-14").unwrap() % 86_400, 0);
        assert_eq!(
            normalize_utc("2025-03-14T10:26:53+01:00").unwrap(),
            "2025-03-14T09:26:53Z"
        );
        assert_eq!(
            normalize_utc("2025-03-14t23:30:00.000-01:00").unwrap(),
            "2025-03-15T00:30:00Z"
        );
        // Every day of a 400-year cycle survives the round trip.
        for day in (-719_162..2_932_896).step_by(97) {
            let s = format_utc(day * 86_400 + 3_723);
            assert_eq!(parse_utc(&s).unwrap(), day * 86_400 + 3_723, "{s}");
        }
    }

    #[test]
    fn refuses_what_is_not_a_time() {
        for s in [
            "",
            "yesterday",
            "2025-02-29",
            "2025-13-01",
            "2025-01-01T24:00:00Z",
            "2025-01-01T12:00:00",
            "2025-01-01T12:00:00.5Z",
            "2025-01-01T12:00:00+1:00",
            "2025-01-01T12:00Z",
            "2025-01-01T12:00:00Zjunk",
            "+2025-01-01",
            "2025-1-01",
        ] {
            assert!(parse_utc(s).is_err(), "{s}");
        }
    }
}
