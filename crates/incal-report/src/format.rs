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

/// `text` as the content of a double-quoted CSS string inside a `<style>`
/// element: every character but letters, digits, space and `-_.,:/+#()`
/// written as a CSS escape (`\3c ` for `<`), so nothing can end the
/// string, the rule or the style element (CSS Syntax Level 3 §4.3.7).
/// Control characters become a space.
pub fn css_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            c if c.is_control() => out.push(' '),
            c if c.is_alphanumeric() || " -_.,:/+#()".contains(c) => out.push(c),
            c => out.push_str(&format!("\\{:x} ", c as u32)),
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

/// The decimal exponent of the last digit shown for a standard
/// uncertainty `u` with two significant digits (GUM 7.2.6): `u = 0.0141`
/// → −3. `None` when `u` is not a positive finite number.
fn last_place(u: f64) -> Option<i32> {
    if !(u.is_finite() && u > 0.0) {
        return None;
    }
    // Rounding may carry into a new digit (0.0996 → 0.10): recompute.
    let e = u.log10().floor() as i32;
    let rounded = round_at(u, e - 1);
    Some(rounded.log10().floor() as i32 - 1)
}

/// `x` rounded to a multiple of `10^place`.
fn round_at(x: f64, place: i32) -> f64 {
    if place >= 0 {
        let f = 10f64.powi(place);
        (x / f).round() * f
    } else {
        let f = 10f64.powi(-place);
        (x * f).round() / f
    }
}

/// `x` written with its last digit at `10^place`: plain while that fits
/// in a readable width, else scientific with the exponent of `x` (or of
/// the last digit's leading place when `x` is smaller).
fn at_place(x: f64, place: i32) -> String {
    if !x.is_finite() {
        return "-".into();
    }
    let r = round_at(x, place);
    let e = if r == 0.0 {
        place
    } else {
        r.abs().log10().floor() as i32
    };
    if (-4..7).contains(&e) && place >= -12 {
        let dec = (-place).max(0) as usize;
        return format!("{r:.dec$}");
    }
    let e = e.max(place);
    let dec = (e - place).max(0) as usize;
    format!("{:.dec$}e{e}", r / 10f64.powi(e))
}

/// A measured value for people (GUM 7.2.6): the standard uncertainty `u`
/// with two significant digits, the value to the same decimal place, the
/// expanded uncertainty `u95` with two significant digits: `(value, u,
/// U95)`. The value shown then differs from `value` by at most half a
/// unit of u's second digit, under 5 % of u (so under a tenth of U95 for
/// any k95 ≥ 1). Without a positive finite `u` (a term fixed by
/// construction), the value has seven significant digits.
pub fn measured(value: f64, u: f64, u95: f64) -> (String, String, String) {
    let two = |x: f64| match last_place(x) {
        Some(p) => at_place(x, p),
        None if x == 0.0 => "0".into(),
        None => sig(x, 2),
    };
    let v = match last_place(u) {
        Some(p) => at_place(value, p),
        None => sig(value, 7),
    };
    (v, two(u), two(u95))
}

/// A coefficient's name as shown beside the unit `shown`: a trailing unit
/// suffix (`tilt_rad`, `R_plus_m`) is dropped when the unit shown is not
/// that unit, so a name never contradicts its column.
pub fn shown_name(name: &str, shown: &str) -> String {
    const SUFFIXES: [(&str, &str); 9] = [
        ("_rad", "rad"),
        ("_deg", "deg"),
        ("_m", "m"),
        ("_s", "s"),
        ("_hz", "Hz"),
        ("_g", "g"),
        ("_m_s2", "m/s^2"),
        ("_deg_s", "deg/s"),
        ("_rad_s", "rad/s"),
    ];
    // Longest suffix first: `_rad_s` before `_s`.
    let mut hit: Option<(&str, &str)> = None;
    for (suf, unit) in SUFFIXES {
        if name.len() > suf.len()
            && name.ends_with(suf)
            && hit.is_none_or(|(h, _)| suf.len() > h.len())
        {
            hit = Some((suf, unit));
        }
    }
    match hit {
        Some((suf, unit)) if unit != shown => name[..name.len() - suf.len()].to_string(),
        _ => name.to_string(),
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
    fn a_css_string_cannot_end_itself_its_rule_or_the_style_element() {
        assert_eq!(css_string("ITL-2026/"), "ITL-2026/");
        let e = css_string("</style>\"; }\\\n");
        for bad in ['<', '>', '"', ';', '}', '\n'] {
            assert!(!e.contains(bad), "{bad:?} in {e}");
        }
        assert_eq!(css_string("<"), "\\3c ");
        assert_eq!(css_string("\\"), "\\5c ");
    }

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

    #[test]
    fn digits_follow_the_uncertainty() {
        // GUM 7.2.6: u with two significant digits, the value to its place.
        assert_eq!(
            measured(10.000_000_12, 3.63e-7, 7.2e-7),
            ("10.00000012".into(), "3.6e-7".into(), "7.2e-7".into())
        );
        assert_eq!(
            measured(7999.98612, 0.0141, 0.0279),
            ("7999.986".into(), "0.014".into(), "0.028".into())
        );
        // Rounding that carries into a new digit keeps two digits.
        assert_eq!(measured(1.23456, 0.0996, 0.197).1, "0.10");
        assert_eq!(measured(1.23456, 0.0996, 0.197).0, "1.23");
        // A value smaller than its uncertainty.
        assert_eq!(measured(0.000_12, 0.0031, 0.0062).0, "0.0001");
        // Large and tiny magnitudes go scientific, with the value's exponent.
        assert_eq!(measured(1.2344e-9, 3.1e-11, 6.2e-11).0, "1.234e-9");
        assert_eq!(measured(123_456_789.0, 1234.0, 2468.0).0, "1.234568e8");
        // No uncertainty (fixed by construction): seven digits.
        assert_eq!(
            measured(1.5, 0.0, 0.0),
            ("1.500000".into(), "0".into(), "0".into())
        );
    }

    #[test]
    fn names_drop_a_unit_suffix_that_contradicts_the_unit_shown() {
        assert_eq!(shown_name("tilt_rad", "arcsec"), "tilt");
        assert_eq!(shown_name("R_plus_m", "mm"), "R_plus");
        assert_eq!(shown_name("R_plus_m", "m"), "R_plus_m");
        assert_eq!(shown_name("bias_rad_s", "deg/s"), "bias");
        assert_eq!(shown_name("K1", "output/g"), "K1");
        assert_eq!(shown_name("_m", "mm"), "_m");
    }
}
