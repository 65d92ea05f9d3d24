//! The result document of a noise and stability analysis
//! (`"procedure": "noise"`).
//!
//! Top-level `channels`: per channel `taus_s`, each deviation as
//! `{taus_s, value, lo, hi, edf, n}`, `alpha` and `id_method` (`lag1`,
//! `b1` or `rn` at each τ), the IEEE term fit's model curve and the
//! slope-line readings, and `allan_minimum` (`tau_s`, the floor's span
//! `tau_low_s`–`tau_high_s`, `adev`, `u_adev`, `dof`, `unit`) when the
//! curve has a minimum inside its τ range. Coefficients `NAME.TERM` in
//! engineering units (module [`NoiseUnits`]), only the identified terms
//! (each with U95 below its value), and `NAME.adev_min` (the bias
//! stability unit), the Allan deviation's floor, which the record
//! determines even where it cannot tell bias instability from a rate
//! random walk.

use serde_json::{json, Value};

use crate::document::{Cell, Coefficient, DocumentBuilder, Procedure, ResultDocument, Table};
use crate::error::Result;
use crate::noise::minimum::allan_minimum;
use crate::noise::terms::{Term, TermFit};
use crate::noise::{DevSeries, Deviation, Series, Stability, Statistic};
use crate::units::{Unit, STANDARD_GRAVITY_M_S2};
use crate::warning::{Warning, WarningCode};

/// What the channels measure, and so the units of their terms.
#[derive(Debug, Clone, PartialEq)]
pub enum Quantity {
    /// Gyro: rate in deg/s internally (after the unit factor); terms in
    /// deg/√h, deg/h, deg/h/√h, deg/h², arcsec.
    Gyro,
    /// Accelerometer: rate in g internally; terms in µg/√Hz, µg, µg/√s,
    /// µg/s, m/s.
    Accel,
    /// Anything else: terms in the input unit `u` (u·√s, u, u/√s, u/s, u·s).
    Generic(String),
}

/// Names, units and factors of the five terms and bias stability of one
/// quantity. `factor` multiplies the amplitude in the base unit (rate unit
/// after [`Quantity`]'s conversion, seconds).
#[derive(Debug, Clone)]
pub struct NoiseUnits {
    /// (name, unit, factor) for Q, N, B, K, R.
    pub terms: [(String, Unit, f64); 5],
    /// Unit and factor of bias stability.
    pub stability: (Unit, f64),
}

impl Quantity {
    /// The units of the terms (IEEE Std 952 Annex C for gyros, IEEE Std
    /// 1293 for accelerometers).
    pub fn units(&self) -> NoiseUnits {
        let o = |s: &str| Unit::Other(s.to_string());
        match self {
            Quantity::Gyro => NoiseUnits {
                terms: [
                    ("quantization".into(), o("arcsec"), 3600.0),
                    ("ARW".into(), o("deg/sqrt(h)"), 60.0),
                    ("bias_instability".into(), o("deg/h"), 3600.0),
                    ("RRW".into(), o("deg/h/sqrt(h)"), 3600.0 * 60.0),
                    ("rate_ramp".into(), o("deg/h^2"), 3600.0 * 3600.0),
                ],
                stability: (o("deg/h"), 3600.0),
            },
            Quantity::Accel => NoiseUnits {
                terms: [
                    ("quantization".into(), o("m/s"), STANDARD_GRAVITY_M_S2),
                    ("VRW".into(), o("ug/sqrt(Hz)"), 1e6),
                    ("bias_instability".into(), o("ug"), 1e6),
                    ("acceleration_random_walk".into(), o("ug/sqrt(s)"), 1e6),
                    ("acceleration_ramp".into(), o("ug/s"), 1e6),
                ],
                stability: (o("ug"), 1e6),
            },
            Quantity::Generic(u) => NoiseUnits {
                terms: [
                    ("Q".into(), o(&format!("{u}*s")), 1.0),
                    ("N".into(), o(&format!("{u}*sqrt(s)")), 1.0),
                    ("B".into(), o(u), 1.0),
                    ("K".into(), o(&format!("{u}/sqrt(s)")), 1.0),
                    ("R".into(), o(&format!("{u}/s")), 1.0),
                ],
                stability: (o(u), 1.0),
            },
        }
    }
}

/// One analysed channel.
#[derive(Debug, Clone)]
pub struct ChannelResult {
    /// Column name.
    pub name: String,
    /// Samples.
    pub samples: usize,
    /// The deviations at every τ.
    pub stability: Stability,
    /// The IEEE 952 term fit (in the internal rate unit).
    pub fit: TermFit,
    /// Slope-line readings Q, N, B, K, R (internal rate unit).
    pub slope: [Option<f64>; 5],
    /// Bias stability at each requested τ (s): value in the internal unit.
    pub bias_stability: Vec<(f64, Option<Term>)>,
    /// The statistics beyond the default five, each on its own τ grid.
    pub more: Vec<(Statistic, Series)>,
    /// Factor from the internal rate unit back to the input unit (for the
    /// deviations, which are reported in the input unit).
    pub to_input: f64,
    /// The power spectral density, when asked for.
    pub spectrum: Option<super::spectrum::ChannelSpectrum>,
    /// The Gauss–Markov bias and its filter rate (Hz), when asked for.
    pub gauss_markov: Option<(super::gauss_markov::Fitted, f64)>,
    /// The dynamic Allan variance, when asked for.
    pub davar: Option<super::davar::Davar>,
    /// The terms in temperature bins, when asked for.
    pub temperature: Option<super::temperature::ChannelTemperature>,
}

/// The identified terms of a gyro or accelerometer in SI continuous-time
/// form, the robotics tools' names (Kalibr, IEEE Std 952-2020 Annex C):
/// `quantization` (rad; m/s), `noise_density` (rad/s/√Hz; m/s²/√Hz),
/// `bias_instability` (rad/s; m/s²), `random_walk` (rad/s²/√Hz; m/s³/√Hz),
/// `ramp` (rad/s²; m/s³), each `{value, u, unit}`; from the internal units
/// (deg/s, g) by π/180 or g₀ = 9.80665 m/s². A discrete sample at rate f
/// has σ_d = noise_density·√f and a bias step random_walk/√f. `None` for
/// a generic quantity.
fn si_terms(quantity: &Quantity, fit: &TermFit) -> Option<Value> {
    let (k, units) = match quantity {
        Quantity::Gyro => (
            std::f64::consts::PI / 180.0,
            [
                "rad",
                "rad/s/sqrt(Hz)",
                "rad/s",
                "rad/s^2/sqrt(Hz)",
                "rad/s^2",
            ],
        ),
        Quantity::Accel => (
            STANDARD_GRAVITY_M_S2,
            ["m/s", "m/s^2/sqrt(Hz)", "m/s^2", "m/s^3/sqrt(Hz)", "m/s^3"],
        ),
        Quantity::Generic(_) => return None,
    };
    let names = [
        "quantization",
        "noise_density",
        "bias_instability",
        "random_walk",
        "ramp",
    ];
    let mut m = serde_json::Map::new();
    for (j, t) in fit.terms.iter().enumerate() {
        if let Some(t) = t {
            m.insert(
                names[j].into(),
                json!({"value": t.value * k, "u": t.u * k, "unit": units[j]}),
            );
        }
    }
    Some(Value::Object(m))
}

fn arr(v: &[Option<f64>], f: f64) -> Value {
    Value::Array(
        v.iter()
            .map(|x| x.map_or(Value::Null, |x| json!(x * f)))
            .collect(),
    )
}

fn tau_label(t: f64) -> String {
    if t.fract() == 0.0 {
        format!("{}s", t as u64)
    } else {
        format!("{t}s").replace('.', "p")
    }
}

/// Build the document. `unit` is the input unit string (deviations are in
/// it; TDEV in `unit·s`); `tables` adds a readable τ table per channel.
pub fn document(
    shown: &[Deviation],
    channels: &[ChannelResult],
    quantity: &Quantity,
    unit: &str,
    confidence: f64,
    tables: bool,
) -> Result<ResultDocument> {
    let units = quantity.units();
    let mut b = DocumentBuilder::new(
        Procedure::Noise,
        format!(
            "Noise and stability: {} channel{}",
            channels.len(),
            if channels.len() == 1 { "" } else { "s" }
        ),
    );
    let mut chans = serde_json::Map::new();
    let mut warnings = Vec::new();
    for c in channels {
        let mut o = channel_json(c, shown, quantity, &units, unit, &mut warnings);
        if let Some(t) = &c.temperature {
            o.insert("temperature".into(), t.render(&c.name, &units, &mut b)?);
        }
        chans.insert(c.name.clone(), Value::Object(o));
        channel_coefficients(&mut b, c, (&units, unit), &mut warnings)?;
        for w in &c.fit.warnings {
            warnings.push(Warning::new(w.code, format!("{}: {}", c.name, w.message)));
        }
        if tables {
            b.table(stability_table(c, unit)?);
        }
        if let Some(s) = c.spectrum.as_ref().filter(|s| !s.tones.is_empty()) {
            b.table(tones_table(c, s, unit)?);
        }
        if let Some(d) = &c.davar {
            b.table(d.table(&c.name, c.to_input, unit)?);
            warnings.extend(d.warning(&c.name, c.to_input, unit));
        }
    }
    b.warnings(warnings);
    b.option("confidence", json!(confidence));
    b.extra("channels", Value::Object(chans))?;
    Ok(b.finish())
}

/// One channel's entry of `channels` (module docs): its deviations, the
/// statistics beyond the default five (a `statistic-truncated` warning
/// for each one cut short), the noise identification, the term fit and
/// the slope-line readings.
fn channel_json(
    c: &ChannelResult,
    shown: &[Deviation],
    quantity: &Quantity,
    units: &NoiseUnits,
    unit: &str,
    warnings: &mut Vec<Warning>,
) -> serde_json::Map<String, Value> {
    let st = &c.stability;
    let f = c.to_input;
    let mut o = serde_json::Map::new();
    o.insert("samples".into(), json!(c.samples));
    o.insert("unit".into(), json!(unit));
    o.insert("tdev_unit".into(), json!(format!("{unit}*s")));
    o.insert("taus_s".into(), json!(st.taus_s));
    for &d in shown {
        o.insert(d.as_str().into(), series_json(&st.taus_s, st.series(d), f));
    }
    for (s, r) in &c.more {
        if r.left_out > 0 {
            warnings.push(Warning::new(
                WarningCode::StatisticTruncated,
                format!(
                    "{}: {} computed up to tau = {} s only; its cost grows as N*m and the {} longer averaging times would take too long (average the record down for them)",
                    c.name,
                    s.as_str(),
                    r.taus_s.last().map_or("-".into(), |t| crate::error::short_f64(*t)),
                    r.left_out
                ),
            ));
        }
        o.insert(s.as_str().into(), series_json(&r.taus_s, &r.dev, f));
    }
    o.insert("alpha".into(), json!(st.alpha));
    o.insert("id_method".into(), json!(st.id_method));
    insert_fit(&mut o, c);
    let mut slope = serde_json::Map::new();
    for (j, v) in c.slope.iter().enumerate() {
        let (name, u, k) = &units.terms[j];
        slope.insert(
            name.clone(),
            json!({"value": v.map(|v| v * k), "unit": u.as_str()}),
        );
    }
    o.insert("slope_readings".into(), Value::Object(slope));
    if let Some(m) = allan_minimum(&st.taus_s, &st.oadev) {
        let (u, k) = &units.stability;
        o.insert(
            "allan_minimum".into(),
            json!({
                "tau_s": m.tau_s,
                "tau_low_s": m.tau_low_s,
                "tau_high_s": m.tau_high_s,
                "adev": m.adev * k,
                "u_adev": m.u_adev * k,
                "dof": m.dof,
                "unit": u.as_str(),
            }),
        );
    }
    if let Some(si) = si_terms(quantity, &c.fit) {
        o.insert("si_terms".into(), si);
    }
    if let Some(s) = &c.spectrum {
        let (_, n_unit, n_k) = &units.terms[1];
        o.insert("psd".into(), s.json(f, (*n_k, n_unit.as_str()), &c.fit));
    }
    if let Some((g, rate)) = &c.gauss_markov {
        o.insert(
            "gauss_markov".into(),
            super::gauss_markov::json(g, f, *rate),
        );
    }
    if let Some(d) = &c.davar {
        o.insert("davar".into(), d.json(f, unit));
    }
    o
}

/// One deviation as `{taus_s, value, lo, hi, edf, n}`, the values and
/// bounds times `f` (into the input unit).
fn series_json(taus_s: &[f64], s: &DevSeries, f: f64) -> Value {
    json!({
        "taus_s": taus_s,
        "value": arr(&s.value, f),
        "lo": arr(&s.lo, f),
        "hi": arr(&s.hi, f),
        "edf": arr(&s.edf, 1.0),
        "n": s.n,
    })
}

/// The IEEE term fit into a channel's entry: the model's OADEV curve
/// (`fit_oadev`), each identified term's line (`fit_terms_oadev`) and the
/// chosen model (`term_model`).
fn insert_fit(o: &mut serde_json::Map<String, Value>, c: &ChannelResult) {
    let (st, f) = (&c.stability, c.to_input);
    let model: Vec<Option<f64>> = st
        .taus_s
        .iter()
        .map(|&t| Some(c.fit.model(t)).filter(|v| *v > 0.0 && v.is_finite()))
        .collect();
    o.insert("fit_oadev".into(), arr(&model, f));
    let mut lines = serde_json::Map::new();
    for (j, t) in c.fit.terms.iter().enumerate() {
        if let Some(t) = t {
            let curve: Vec<Option<f64>> = st
                .taus_s
                .iter()
                .map(|&tau| Some(t.value * crate::noise::terms::regressor(j, tau).sqrt()))
                .collect();
            lines.insert(crate::noise::terms::TERMS[j].into(), arr(&curve, f));
        }
    }
    o.insert("fit_terms_oadev".into(), Value::Object(lines));
    // The chosen model: its terms, the fit's χ² and the correlation of
    // the fitted squares (B² and K² are strongly correlated on short
    // records).
    if let (Some(sq), Some((chi2, dof))) = (&c.fit.squares, c.fit.chi2) {
        let names: Vec<&str> = sq.names().iter().map(|n| n.trim_end_matches('2')).collect();
        let r = sq.correlation();
        let rows: Vec<Vec<Option<f64>>> = (0..r.nrows())
            .map(|i| {
                (0..r.ncols())
                    .map(|j| Some(r[(i, j)]).filter(|v| v.is_finite()))
                    .collect()
            })
            .collect();
        o.insert(
            "term_model".into(),
            json!({
                "terms": names,
                "chi2": Some(chi2).filter(|v| v.is_finite()),
                "dof": dof,
                "penalty": crate::noise::terms::PENALTY,
                "correlation": rows,
            }),
        );
    }
}

/// A channel's coefficients: its identified terms (`NAME.TERM`) and its
/// bias stability at each requested τ (`NAME.bias_stability_τ`, a
/// `short-record` warning where the record is too short for it).
fn channel_coefficients(
    b: &mut DocumentBuilder,
    c: &ChannelResult,
    (units, unit): (&NoiseUnits, &str),
    warnings: &mut Vec<Warning>,
) -> Result<()> {
    for (j, t) in c.fit.terms.iter().enumerate() {
        if let Some(t) = t {
            let (name, u, k) = &units.terms[j];
            let full = format!("{}.{name}", c.name);
            b.coefficient(
                &full,
                Coefficient::new(&full, t.value * k, t.u * k, u.clone(), t.dof)?,
            )?;
        }
    }
    if let Some(m) = allan_minimum(&c.stability.taus_s, &c.stability.oadev) {
        let full = format!("{}.adev_min", c.name);
        let (u, k) = &units.stability;
        b.coefficient(
            &full,
            Coefficient::new(&full, m.adev * k, m.u_adev * k, u.clone(), m.dof)?,
        )?;
    }
    if let Some(s) = &c.spectrum {
        spectrum_coefficient(b, c, s, (units, unit), warnings)?;
    }
    if let Some((g, _)) = &c.gauss_markov {
        markov_coefficients(b, c, g, unit, warnings)?;
    }
    for (tau, t) in &c.bias_stability {
        let full = format!("{}.bias_stability_{}", c.name, tau_label(*tau));
        match t {
            Some(t) => {
                let (u, k) = &units.stability;
                b.coefficient(&full, Coefficient::new(&full, t.value * k, t.u * k, u.clone(), t.dof)?)?;
            }
            None => warnings.push(Warning::new(
                WarningCode::ShortRecord,
                format!("{}: the record holds fewer than two windows of {tau} s: no bias stability at {tau} s", c.name),
            )),
        }
    }
    Ok(())
}

/// The PSD's white level as `NAME.white_asd` (input unit/√Hz), and a
/// `noise-inconsistent` warning when its N and the Allan fit's differ
/// beyond the U95 of their difference (or a `short-record` warning when
/// the band holds too few bins for a level).
fn spectrum_coefficient(
    b: &mut DocumentBuilder,
    c: &ChannelResult,
    s: &super::spectrum::ChannelSpectrum,
    (units, unit): (&NoiseUnits, &str),
    warnings: &mut Vec<Warning>,
) -> Result<()> {
    let lines = s.tones.len() + s.unfitted.len() + s.search.more;
    if lines > 0 {
        let hz: Vec<String> = s
            .tones
            .iter()
            .take(4)
            .map(|t| format!("{:.6} Hz", t.frequency_hz))
            .collect();
        warnings.push(Warning::new(
            WarningCode::Tones,
            format!(
                "{}: {lines} line(s) stand above the PSD's noise floor ({}{}); each raises the Allan deviation near tau = 0.37/f (table tones.{}; {} not estimated)",
                c.name,
                hz.join(", "),
                if lines > hz.len() { ", ..." } else { "" },
                c.name,
                s.unfitted.len() + s.search.more,
            ),
        ));
    }
    let Some(w) = s.white else {
        warnings.push(Warning::new(
            WarningCode::ShortRecord,
            format!("{}: the PSD's white band holds fewer than 3 independent bins: no white level (lengthen psd_segment_samples or widen psd_white_band_hz)", c.name),
        ));
        return Ok(());
    };
    let (asd, u_asd) = w.asd(c.to_input);
    let full = format!("{}.white_asd", c.name);
    let asd_unit = Unit::Other(format!("{unit}/sqrt(Hz)"));
    b.coefficient(&full, Coefficient::new(&full, asd, u_asd, asd_unit, w.dof)?)?;
    if let Some(t) = c.fit.terms[1].as_ref() {
        let (n, un) = w.n_equivalent();
        let (name, u_name, k) = &units.terms[1];
        let d = n - t.value;
        let u = (un * un + t.u * t.u).sqrt();
        if d.abs() > 1.96 * u {
            warnings.push(Warning::new(
                WarningCode::NoiseInconsistent,
                format!(
                    "{}: the PSD's white level gives {name} = {:.4} {}, the Allan fit {:.4} {}: they differ by {:.1} u of their difference (a filtered or coloured band, a tone, or a term the fit lacks)",
                    c.name,
                    n * k,
                    u_name.as_str(),
                    t.value * k,
                    u_name.as_str(),
                    d.abs() / u
                ),
            ));
        }
    }
    Ok(())
}

/// The readable τ table of a channel (`stability.NAME`): α, OADEV with
/// its bounds, MDEV, OHDEV and TOTDEV in the input unit, and OADEV's number of terms.
fn stability_table(c: &ChannelResult, unit: &str) -> Result<Table> {
    let (st, f) = (&c.stability, c.to_input);
    let u = Some(Unit::Other(unit.to_string()));
    let mut t = Table::new(
        &format!("stability.{}", c.name),
        &format!("{}: Allan family at each averaging time", c.name),
        &[
            ("tau", Some(Unit::Other("s".into()))),
            ("alpha", None),
            ("oadev", u.clone()),
            ("oadev_lo", u.clone()),
            ("oadev_hi", u.clone()),
            ("mdev", u.clone()),
            ("ohdev", u.clone()),
            ("totdev", u.clone()),
            ("n", None),
        ],
    );
    for (k, tau) in st.taus_s.iter().enumerate() {
        let g = |v: Option<f64>| Cell::opt(v.map(|v| v * f));
        t.push(vec![
            Cell::num(*tau),
            Cell::opt(st.alpha[k].map(f64::from)),
            g(st.oadev.value[k]),
            g(st.oadev.lo[k]),
            g(st.oadev.hi[k]),
            g(st.mdev.value[k]),
            g(st.ohdev.value[k]),
            g(st.totdev.value[k]),
            Cell::num(st.oadev.n[k] as f64),
        ])?;
    }
    Ok(t)
}

/// The lines of a channel's spectrum (`tones.NAME`): frequency and rms
/// amplitude (input unit) with their u, the coverage factor of both and
/// the peak's ratio to its floor.
fn tones_table(
    c: &ChannelResult,
    s: &super::spectrum::ChannelSpectrum,
    unit: &str,
) -> Result<Table> {
    let u = Some(Unit::Other(unit.to_string()));
    let hz = Some(Unit::Other("Hz".into()));
    let mut t = Table::new(
        &format!("tones.{}", c.name),
        &format!("{}: lines above the PSD's noise floor", c.name),
        &[
            ("frequency_hz", hz.clone()),
            ("u_frequency_hz", hz),
            ("amplitude_rms", u.clone()),
            ("u_amplitude_rms", u),
            ("k95", None),
            ("peak_to_floor", None),
        ],
    );
    for l in &s.tones {
        t.push(vec![
            Cell::num(l.frequency_hz),
            Cell::num(l.u_frequency_hz),
            Cell::num(l.amplitude_rms * c.to_input),
            Cell::num(l.u_amplitude_rms * c.to_input),
            Cell::num(crate::estimation::coverage_factor(l.dof, 0.95)),
            Cell::num(l.peak.ratio),
        ])?;
    }
    Ok(t)
}

/// The Gauss–Markov bias as `NAME.gm_sigma` (input unit) and
/// `NAME.gm_tau_c_s` (s) when the record supports one, else a
/// `not-significant` warning with the reason.
fn markov_coefficients(
    b: &mut DocumentBuilder,
    c: &ChannelResult,
    g: &super::gauss_markov::Fitted,
    unit: &str,
    warnings: &mut Vec<Warning>,
) -> Result<()> {
    let (g, why) = match g {
        Ok(g) => (Some(g), g.unsupported.as_ref()),
        Err(why) => (None, Some(why)),
    };
    let (Some(g), None) = (g, why) else {
        warnings.push(Warning::new(
            WarningCode::NotSignificant,
            format!(
                "{}: no Gauss-Markov bias reported: {}",
                c.name,
                why.map_or("", String::as_str)
            ),
        ));
        return Ok(());
    };
    let full = format!("{}.gm_sigma", c.name);
    let f = c.to_input;
    b.coefficient(
        &full,
        Coefficient::new(
            &full,
            g.sigma * f,
            g.u_sigma * f,
            Unit::Other(unit.to_string()),
            g.dof,
        )?,
    )?;
    let full = format!("{}.gm_tau_c_s", c.name);
    b.coefficient(
        &full,
        Coefficient::new(
            &full,
            g.tau_c_s,
            g.u_tau_c_s,
            Unit::Other("s".into()),
            g.dof,
        )?,
    )?;
    Ok(())
}
