//! Limits and pass/fail decisions with the measurement uncertainty taken
//! into account (ILAC-G8:2019; JCGM 106:2012).
//!
//! A limits file (TOML) gives, per procedure and coefficient, a lower
//! and/or upper tolerance limit, in the coefficient's JSON unit or with an
//! explicit unit, and one decision rule for the file:
//!
//! ```toml
//! rule = "guard-band"            # or "simple" (default)
//! [tumble]
//! K0 = { min = -1e-3, max = 1e-3 }          # g, the JSON unit of K0
//! K2 = { max = 20, unit = "ug/g^2" }        # explicit unit
//! delta_o = { min = -900, max = 900, unit = "arcsec" }
//! [gfimu-calibrate]
//! "a.K0" = { min = -0.01, max = 0.01 }
//! ```
//!
//! # Decision rules
//! With the coefficient's value `x`, its expanded uncertainty `U = U95`
//! and the tolerance interval `[min, max]` (a missing side is unbounded):
//! * `simple` (ILAC-G8 §4.2.1, simple acceptance, shared risk): `pass`
//!   when `min ≤ x ≤ max`, else `fail`.
//! * `guard-band` (ILAC-G8 §4.2.2–4.2.3, guard band `w = U`): `pass` when
//!   `min ≤ x − U` and `x + U ≤ max` (the whole interval inside), `fail`
//!   when `x + U < min` or `x − U > max` (wholly outside), otherwise
//!   `conditional-pass` when `x` itself is inside and `conditional-fail`
//!   when it is outside.
//!
//! A limit on a term this result does not report (a noise term not
//! identified on a channel: the channel's slope readings name every term
//! the fit could give) is `not-determined`: conformity cannot be stated
//! for it, and the run is not refused. Any other name that is not a
//! coefficient is refused (a misspelling must not pass unnoticed).
//!
//! # Wildcards
//! A `*` in a name matches any run of characters without a `.`:
//! `"*.ARW" = { max = 0.2, unit = "deg/sqrt(h)" }` limits the ARW of every
//! channel, so one limits file serves every channel of a noise result (or
//! every accelerometer of a gyro-free unit). It is matched against the
//! result's coefficients and the terms it could report (a channel without
//! the term gets `not-determined`); a name given in full takes precedence
//! over a wildcard that also matches it; a wildcard that matches nothing
//! is refused.
//!
//! The overall verdict is the worst one: `fail` before `conditional-fail`
//! before `not-determined` before `conditional-pass` before `pass`.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{Procedure, ResultDocument};
use crate::units::Unit;

/// How a value and its uncertainty are judged against a limit.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum DecisionRule {
    /// Value against the limit (ILAC-G8 simple acceptance).
    #[default]
    Simple,
    /// Value ± U95 against the limit (ILAC-G8 guard band w = U).
    GuardBand,
}

/// The verdict on one coefficient or on the whole result.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Inside the limits (with U95 under the guard-band rule).
    Pass,
    /// The value is inside, but value ± U95 crosses a limit.
    ConditionalPass,
    /// The result does not report this term (not identified): no
    /// conformity can be stated.
    NotDetermined,
    /// The value is outside, but value ± U95 reaches inside.
    ConditionalFail,
    /// Outside the limits (wholly, with U95, under the guard-band rule).
    Fail,
}

impl Verdict {
    /// `pass`, `conditional-pass`, `not-determined`, `conditional-fail`,
    /// `fail`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::ConditionalPass => "conditional-pass",
            Verdict::NotDetermined => "not-determined",
            Verdict::ConditionalFail => "conditional-fail",
            Verdict::Fail => "fail",
        }
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One coefficient judged against its limits (all numbers in the
/// coefficient's JSON unit).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CoefficientVerdict {
    /// Lower limit (`null`: none).
    pub min: Option<f64>,
    /// Upper limit (`null`: none).
    pub max: Option<f64>,
    /// The verdict.
    pub verdict: Verdict,
}

/// One limit as written in the file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Limit {
    /// Lower limit.
    pub min: Option<f64>,
    /// Upper limit.
    pub max: Option<f64>,
    /// Unit of `min`/`max` (default: the coefficient's JSON unit).
    pub unit: Option<String>,
}

/// A limits file: the decision rule and, per procedure id, the limits of
/// its coefficients.
#[derive(Debug, Clone, PartialEq)]
pub struct Limits {
    /// The decision rule (default `simple`).
    pub rule: DecisionRule,
    /// `procedure id → coefficient name → limit`.
    pub procedures: BTreeMap<String, BTreeMap<String, Limit>>,
}

/// Longest parser message kept from a limits file (characters).
const MAX_ECHO: usize = 200;

/// One top-level entry of a limits file: `rule = "…"` or a `[procedure]`
/// table. Read by hand (not with serde's `flatten`, which buffers the
/// values and loses their position), so every error has its line.
enum Entry {
    Rule(DecisionRule),
    Section(BTreeMap<String, toml::Spanned<Limit>>),
}

impl<'de> Deserialize<'de> for Entry {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Entry;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a decision rule or a table of limits")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<Entry, E> {
                use serde::de::IntoDeserializer;
                let d: serde::de::value::StrDeserializer<'_, E> = v.into_deserializer();
                DecisionRule::deserialize(d).map(Entry::Rule)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> std::result::Result<Entry, A::Error> {
                let mut out = BTreeMap::new();
                while let Some(k) = map.next_key::<String>()? {
                    let limit = map.next_value::<toml::Spanned<Limit>>()?;
                    out.insert(k, limit);
                }
                Ok(Entry::Section(out))
            }
        }
        d.deserialize_any(V)
    }
}

impl Limits {
    /// Parse a limits file (TOML). Errors say where (line, key) and what.
    pub fn parse(text: &str) -> std::result::Result<Limits, String> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // Where every line starts, once: a line number is a binary search
        // (counting newlines from the start for every entry was quadratic).
        let newlines: Vec<usize> = text.match_indices('\n').map(|(i, _)| i).collect();
        let line_of = |start: usize| 1 + newlines.partition_point(|&i| i < start);
        let toml_error = |e: toml::de::Error| {
            // The parser echoes the offending value whole (a float literal
            // of 300 digits): kept to one readable line.
            let mut msg = e.message().replace('\n', " ");
            if msg.chars().count() > MAX_ECHO {
                msg = msg.chars().take(MAX_ECHO).collect::<String>() + "…";
            }
            match e.span() {
                Some(s) => format!("line {}: {msg}", line_of(s.start)),
                None => msg,
            }
        };
        let entries: BTreeMap<String, toml::Spanned<Entry>> =
            toml::from_str(text).map_err(toml_error)?;
        let mut limits = Limits {
            rule: DecisionRule::default(),
            procedures: BTreeMap::new(),
        };
        for (key, entry) in entries {
            let line = line_of(entry.span().start);
            match (key.as_str(), entry.into_inner()) {
                ("rule", Entry::Rule(r)) => limits.rule = r,
                ("rule", Entry::Section(_)) => {
                    return Err(format!(
                        "line {line}: rule: expected \"simple\" or \"guard-band\", not a table"
                    ))
                }
                (p, Entry::Section(coefs)) => {
                    if Procedure::from_id(p).is_none() {
                        let all: Vec<&str> = Procedure::all().iter().map(|p| p.as_str()).collect();
                        return Err(format!(
                            "line {line}: [{}]: not a procedure ({})",
                            incal_io::clip(p),
                            all.join(", ")
                        ));
                    }
                    let coefs = checked_section(p, coefs, line_of)?;
                    limits.procedures.insert(p.to_string(), coefs);
                }
                (k, Entry::Rule(_)) => {
                    return Err(format!(
                        "line {line}: {}: not a key of a limits file (rule, or a [procedure] table of limits)",
                        incal_io::clip(k)
                    ))
                }
            }
        }
        Ok(limits)
    }
}

/// A `[procedure]` table's limits, each with the line it is on, checked:
/// min and/or max given, finite, min not above max.
fn checked_section(
    p: &str,
    coefs: BTreeMap<String, toml::Spanned<Limit>>,
    line_of: impl Fn(usize) -> usize,
) -> std::result::Result<BTreeMap<String, Limit>, String> {
    let mut out = BTreeMap::new();
    for (name, l) in coefs {
        let at = format!(
            "line {}: [{p}] {}",
            line_of(l.span().start),
            incal_io::clip(&name)
        );
        let l = l.into_inner();
        match (l.min, l.max) {
            (None, None) => return Err(format!("{at}: give min and/or max")),
            (Some(a), Some(b)) if a > b => return Err(format!("{at}: min {a} is above max {b}")),
            _ => {}
        }
        if l.min.is_some_and(|x| !x.is_finite()) || l.max.is_some_and(|x| !x.is_finite()) {
            return Err(format!("{at}: limits must be finite numbers"));
        }
        out.insert(name, l);
    }
    Ok(out)
}

/// How many JSON units one `unit` is, for a coefficient in `json`:
/// the JSON unit itself, its engineering unit, or a common SI prefix of it.
fn unit_factor(json: &Unit, unit: &str) -> Option<f64> {
    if unit == json.as_str() {
        return Some(1.0);
    }
    let (scale, label) = json.engineering();
    if unit == label {
        return Some(1.0 / scale);
    }
    // An SI prefix on a declared output unit (mV/g for V/g, mA for A).
    let js = json.as_str();
    for (p, f) in [
        ("n", 1e-9),
        ("u", 1e-6),
        ("µ", 1e-6),
        ("m", 1e-3),
        ("k", 1e3),
    ] {
        if let Some(rest) = unit.strip_prefix(p) {
            if rest == js && !js.is_empty() && js.starts_with(|c: char| c.is_ascii_uppercase()) {
                return Some(f);
            }
        }
    }
    let rad = std::f64::consts::PI / 180.0;
    match (json, unit) {
        (Unit::Rad, "deg") => Some(rad),
        (Unit::Rad, "arcmin") => Some(rad / 60.0),
        (Unit::Rad, "mrad") => Some(1e-3),
        (Unit::Rad, "urad") => Some(1e-6),
        (Unit::G, "mg") => Some(1e-3),
        (Unit::M, "um") => Some(1e-6),
        (Unit::M, "cm") => Some(1e-2),
        (Unit::GPerG2, "mg/g^2") => Some(1e-3),
        (Unit::GPerG3, "mg/g^3") => Some(1e-3),
        _ => None,
    }
}

/// Judge `value ± u95` against `[min, max]` with `rule` (module docs).
pub fn judge(
    value: f64,
    u95: f64,
    min: Option<f64>,
    max: Option<f64>,
    rule: DecisionRule,
) -> Verdict {
    let lo = min.unwrap_or(f64::NEG_INFINITY);
    let hi = max.unwrap_or(f64::INFINITY);
    let inside = lo <= value && value <= hi;
    match rule {
        DecisionRule::Simple => {
            if inside {
                Verdict::Pass
            } else {
                Verdict::Fail
            }
        }
        DecisionRule::GuardBand => {
            if lo <= value - u95 && value + u95 <= hi {
                Verdict::Pass
            } else if value + u95 < lo || value - u95 > hi {
                Verdict::Fail
            } else if inside {
                Verdict::ConditionalPass
            } else {
                Verdict::ConditionalFail
            }
        }
    }
}

/// True when `name` matches `pattern`, where `*` stands for any run of
/// characters without a `.`.
fn glob(pattern: &str, name: &str) -> bool {
    fn go(p: &[u8], n: &[u8]) -> bool {
        match p.split_first() {
            None => n.is_empty(),
            Some((b'*', rest)) => {
                // Try every length of the run, up to the next '.'.
                let mut k = 0;
                loop {
                    if go(rest, &n[k..]) {
                        return true;
                    }
                    if k == n.len() || n[k] == b'.' {
                        return false;
                    }
                    k += 1;
                }
            }
            Some((c, rest)) => n.first() == Some(c) && go(rest, &n[1..]),
        }
    }
    go(pattern.as_bytes(), name.as_bytes())
}

/// The terms `doc` could report but may not have: for a noise result,
/// every term its slope readings name on each channel (identified or
/// not), as `(channel.term, unit)`.
fn possible_terms(doc: &ResultDocument) -> Vec<(String, Unit)> {
    let mut out: Vec<(String, Unit)> = Vec::new();
    if let Some(serde_json::Value::Object(chans)) = doc.extra.get("channels") {
        for (ch, v) in chans {
            if let Some(serde_json::Value::Object(terms)) = v.get("slope_readings") {
                for (t, r) in terms {
                    if let Some(u) = r.get("unit").and_then(|u| u.as_str()) {
                        out.push((format!("{ch}.{t}"), Unit::parse(u)));
                    }
                }
            }
        }
    }
    out
}

/// Judge every limited coefficient of `doc` and set its `verdicts`,
/// `verdict` and `decision_rule` (module docs: wildcards and
/// `not-determined`). Fails (naming the key) when the file has no limits
/// for this procedure, names a coefficient the result cannot have, has a
/// wildcard that matches nothing, or gives a unit that does not fit the
/// coefficient.
pub fn apply(doc: &mut ResultDocument, limits: &Limits) -> std::result::Result<(), String> {
    let p: Procedure = doc.procedure;
    let coefs = limits
        .procedures
        .get(p.as_str())
        .ok_or_else(|| format!("no [{p}] section: no limits for this procedure"))?;
    if coefs.is_empty() {
        // An empty table would give a result with no verdict at all.
        return Err(format!(
            "[{p}] is empty: no limits for this procedure (give at least one coefficient's min or max)"
        ));
    }
    let names = doc.coefficients.names();
    let terms = possible_terms(doc);
    let term_unit = |name: &str| -> Option<Unit> {
        terms
            .iter()
            .find(|(x, _)| x == name)
            .map(|(_, u)| u.clone())
    };
    let could_be = |name: &str| term_unit(name).is_some();
    // Every name to judge and the key of the file it comes from: names
    // given in full first, then what the wildcards add.
    let mut targets: BTreeMap<String, (&String, &Limit)> = BTreeMap::new();
    for (key, l) in coefs.iter().filter(|(k, _)| !k.contains('*')) {
        if !names.contains(key) && !could_be(key) {
            return Err(format!(
                "[{p}] {key}: not a coefficient of this result (it has {})",
                names.join(", ")
            ));
        }
        targets.insert(key.clone(), (key, l));
    }
    for (key, l) in coefs.iter().filter(|(k, _)| k.contains('*')) {
        let mut candidates: Vec<String> = names.iter().filter(|n| glob(key, n)).cloned().collect();
        for (n, _) in &terms {
            if glob(key, n) && !candidates.contains(n) {
                candidates.push(n.clone());
            }
        }
        if candidates.is_empty() {
            return Err(format!(
                "[{p}] \"{key}\": the wildcard matches no coefficient of this result (it has {})",
                names.join(", ")
            ));
        }
        for n in candidates {
            targets.entry(n).or_insert((key, l));
        }
    }
    let mut verdicts = BTreeMap::new();
    for (name, (key, l)) in targets {
        let coef = doc.coefficients.get(&name);
        // The unit a limit converts to: the coefficient's, else (a term not
        // reported) the term's unit in this result.
        let unit = coef.map(|c| c.unit.clone()).or_else(|| term_unit(&name));
        let f = match (&l.unit, &unit) {
            (None, _) => Some(1.0),
            (Some(u), Some(cu)) => Some(unit_factor(cu, u).ok_or_else(|| {
                format!("[{p}] {key}: unit '{u}' does not fit the coefficient's unit '{cu}'")
            })?),
            // No coefficient to say the JSON unit: the limits are kept out.
            (Some(_), None) => None,
        };
        let (min, max) = match f {
            Some(f) => (l.min.map(|x| x * f), l.max.map(|x| x * f)),
            None => (None, None),
        };
        let verdict = match coef {
            Some(c) => judge(c.value, c.u95, min, max, limits.rule),
            None => Verdict::NotDetermined,
        };
        verdicts.insert(name, CoefficientVerdict { min, max, verdict });
    }
    doc.verdict = verdicts.values().map(|v| v.verdict).max();
    doc.verdicts = Some(verdicts);
    doc.decision_rule = Some(limits.rule);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-made cases for each verdict, limits [−1, 1], U = 0.2.
    /// Class 10 of the third hardening round: line numbers come from one
    /// index of the line starts (a file of 100,000 limits was quadratic);
    /// the last entry's line is still named right.
    #[test]
    fn a_large_limits_file_names_the_line_of_its_last_entry() {
        let mut text = String::from("[tumble]\n");
        for i in 0..100_000 {
            text.push_str(&format!("K{i} = {{ min = 0, max = 1 }}\n"));
        }
        text.push_str("Kbad = { min = 2, max = 1 }\n");
        let e = Limits::parse(&text).unwrap_err();
        assert!(
            e.starts_with("line 100002: [tumble] Kbad: min 2 is above max 1"),
            "{e}"
        );
    }

    #[test]
    fn a_huge_value_is_not_echoed_whole() {
        // Found by the fuzz campaign: a 12-byte file gave a 404-character line.
        let e = Limits::parse("rule = 1e308").unwrap_err();
        assert!(e.starts_with("line 1: "), "{e}");
        assert!(e.chars().count() < 230, "{} chars: {e}", e.chars().count());
    }

    #[test]
    fn guard_band_gives_each_of_the_four_verdicts() {
        let g = DecisionRule::GuardBand;
        let (lo, hi) = (Some(-1.0), Some(1.0));
        assert_eq!(judge(0.5, 0.2, lo, hi, g), Verdict::Pass);
        assert_eq!(judge(0.9, 0.2, lo, hi, g), Verdict::ConditionalPass);
        assert_eq!(judge(1.1, 0.2, lo, hi, g), Verdict::ConditionalFail);
        assert_eq!(judge(1.3, 0.2, lo, hi, g), Verdict::Fail);
        assert_eq!(judge(-0.9, 0.2, lo, hi, g), Verdict::ConditionalPass);
        assert_eq!(judge(-1.1, 0.2, lo, hi, g), Verdict::ConditionalFail);
        assert_eq!(judge(-1.3, 0.2, lo, hi, g), Verdict::Fail);
        // Boundaries: touching the limit with value ± U is still inside.
        assert_eq!(judge(0.8, 0.2, lo, hi, g), Verdict::Pass);
        assert_eq!(judge(1.2, 0.2, lo, hi, g), Verdict::ConditionalFail);
        // One-sided limits.
        assert_eq!(judge(5.0, 0.2, None, Some(1.0), g), Verdict::Fail);
        assert_eq!(judge(-5.0, 0.2, None, Some(1.0), g), Verdict::Pass);
    }

    #[test]
    fn simple_rule_ignores_the_uncertainty() {
        let s = DecisionRule::Simple;
        assert_eq!(judge(0.9, 0.5, Some(-1.0), Some(1.0), s), Verdict::Pass);
        assert_eq!(judge(1.1, 0.5, Some(-1.0), Some(1.0), s), Verdict::Fail);
    }

    #[test]
    fn limits_files_are_checked() {
        let ok = Limits::parse("rule = \"guard-band\"\n[tumble]\nK0 = { max = 1e-3 }\n").unwrap();
        assert_eq!(ok.rule, DecisionRule::GuardBand);
        assert!(Limits::parse("[tumble]\nK0 = {}\n")
            .unwrap_err()
            .contains("min and/or max"));
        assert!(Limits::parse("[tumble]\nK0 = { min = 2, max = 1 }\n")
            .unwrap_err()
            .contains("above max"));
        assert!(Limits::parse("rule = \"lenient\"\n")
            .unwrap_err()
            .contains("line 1"));
        assert!(Limits::parse("[tumble]\nK0 = { mx = 1 }\n").is_err());
        assert!(Limits::parse("[tumbel]\nK0 = { max = 1 }\n")
            .unwrap_err()
            .contains("not a procedure"));
    }

    #[test]
    fn wildcards_match_within_one_name_segment() {
        assert!(glob("*.ARW", "ch1.ARW"));
        assert!(glob("*.ARW", "gyro_x.ARW"));
        assert!(!glob("*.ARW", "a.b.ARW"));
        assert!(!glob("*.ARW", "ch1.ARW2"));
        assert!(glob("ch*.K", "ch12.K"));
        assert!(glob("K_a.*", "K_a.xx"));
        assert!(!glob("K_a.*", "K_g.xx"));
        assert!(glob("*", "K0") && !glob("*", "a.K0"));
    }

    #[test]
    fn the_worst_verdict_orders_not_determined_between_the_conditionals() {
        let mut v = [
            Verdict::Fail,
            Verdict::Pass,
            Verdict::NotDetermined,
            Verdict::ConditionalFail,
            Verdict::ConditionalPass,
        ];
        v.sort();
        assert_eq!(
            v.map(Verdict::as_str),
            [
                "pass",
                "conditional-pass",
                "not-determined",
                "conditional-fail",
                "fail"
            ]
        );
    }

    #[test]
    fn units_convert_to_the_json_unit() {
        assert_eq!(unit_factor(&Unit::G, "ug"), Some(1e-6));
        assert_eq!(unit_factor(&Unit::G, "g"), Some(1.0));
        assert!((unit_factor(&Unit::Rad, "arcsec").unwrap() - 4.84813681e-6).abs() < 1e-14);
        assert_eq!(unit_factor(&Unit::M, "mm"), Some(1e-3));
        assert_eq!(unit_factor(&Unit::G, "arcsec"), None);
    }
}
