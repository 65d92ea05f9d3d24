//! Text for people: HTML escaping, numbers with a fixed count of
//! significant digits (as the text report prints them), degrees of
//! freedom, and the UTC date of the report.

/// `text` with `&`, `<`, `>`, `"` and `'` escaped: safe both as element
/// content and inside a double- or single-quoted attribute value.
pub fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            other => out.push(other),
        }
    }
    out
}

/// A number with `digits` significant digits, plain or scientific as fits
/// (the text report's rule); `-` when not finite.
pub fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() {
        return "-".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let e = x.abs().log10().floor() as i32;
    if (-3..6).contains(&e) {
        let dec = (digits as i32 - 1 - e).max(0) as usize;
        format!("{x:.dec$}")
    } else {
        format!("{x:.prec$e}", prec = digits.saturating_sub(1))
    }
}

/// [`sig`] with trailing zeros dropped (`30.0000` → `30`, `1.50e-4` →
/// `1.5e-4`): table cells and axis ticks.
pub fn trimmed(x: f64, digits: usize) -> String {
    let s = sig(x, digits);
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        None if s.contains('.') => s.trim_end_matches('0').trim_end_matches('.').to_string(),
        _ => s,
    }
}

/// Degrees of freedom for people: whole numbers from 10 up, one decimal
/// below unless whole, `inf` for a known variance (`None`).
pub fn dof_text(dof: Option<f64>) -> String {
    match dof {
        None => "inf".into(),
        Some(d) if d.fract() == 0.0 || d >= 10.0 => format!("{d:.0}"),
        Some(d) => format!("{d:.1}"),
    }
}

/// The civil date of a count of days since 1970-01-01 (proleptic
/// Gregorian; H. Hinnant's `civil_from_days`).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// `YYYY-MM-DD HH:MM UTC` of a time in seconds since the Unix epoch.
pub fn utc_text(unix_seconds: i64) -> String {
    let (days, secs) = (
        unix_seconds.div_euclid(86_400),
        unix_seconds.rem_euclid(86_400),
    );
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        secs / 3600,
        (secs / 60) % 60
    )
}

/// The current time as [`utc_text`] (the epoch if the clock is before it).
pub fn now_utc_text() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64);
    utc_text(secs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_quotes() {
        assert_eq!(
            esc(r#"<script>alert("x")</script> & 'y'"#),
            "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt; &amp; &#39;y&#39;"
        );
    }

    #[test]
    fn numbers_read_as_in_the_text_report() {
        assert_eq!(sig(7999.98612, 7), "7999.986");
        assert_eq!(sig(3.63e-7, 3), "3.63e-7");
        assert_eq!(trimmed(30.0, 6), "30");
        assert_eq!(trimmed(1.5e-4, 3), "1.5e-4");
        assert_eq!(sig(f64::NAN, 3), "-");
        assert_eq!(dof_text(Some(95.1)), "95");
        assert_eq!(dof_text(Some(6.0)), "6");
        assert_eq!(dof_text(Some(4.46)), "4.5");
        assert_eq!(dof_text(None), "inf");
    }

    #[test]
    fn utc_dates() {
        assert_eq!(utc_text(0), "1970-01-01 00:00 UTC");
        assert_eq!(utc_text(951_782_400), "2000-02-29 00:00 UTC");
        assert_eq!(utc_text(1_767_225_600 + 3_723), "2026-01-01 01:02 UTC");
        assert_eq!(utc_text(-86_400), "1969-12-31 00:00 UTC");
    }
}
