//! `incal gyro rate|positions`, `incal plan gyro-rate|gyro-positions`,
//! `incal simulate gyro-rate|gyro-positions` (IEEE Std 952 / 1431 / 517).

use std::path::{Path, PathBuf};

use clap::{Subcommand, ValueEnum};
use incal::document::Procedure;
use incal::procedures::gyro::positions::{
    self as gp, Axial, DriftTerm, PositionObservation, PositionsOptions, ScaleFactor,
};
use incal::procedures::gyro::rate::{
    self as gr, InputAxis, RateObservation, RateOptions, RateTerm,
};
use incal::sim::gyro::{
    simulate_positions, simulate_rate, DriftTruth, GyroPositionsSim, GyroRateSim,
};
use incal::warning::{Warning, WarningCode};
use serde_json::{json, Map, Value};

use crate::documents::read_document;
use crate::error::{core, in_file, usage, CliError, CliResult};
use crate::input::Table;
use crate::options::noise_option;
use crate::output::{input_file, json_text, num, sig, table, write_text, ResultArgs};

/// `incal gyro …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Rate-transfer test on a rate table: scale factor K1, bias B, K2/K3, asymmetry, nonlinearity, repeatability.
    Rate(RateArgs),
    /// Multi-position test on a dividing head: bias and g-sensitive drift terms, Earth rate as the known input.
    Positions(PositionsArgs),
}

/// Input axis on the rate table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IaArg {
    /// IA up, along the table's counter-clockwise rotation axis.
    Up,
    /// IA down.
    Down,
}

impl From<IaArg> for InputAxis {
    fn from(a: IaArg) -> InputAxis {
        match a {
            IaArg::Up => InputAxis::Up,
            IaArg::Down => InputAxis::Down,
        }
    }
}

/// Gyro axis along the head axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AxialArg {
    /// Spin axis along the head axis (the in-plane axis is OA).
    Sa,
    /// Output axis along the head axis (the in-plane axis is SA).
    Oa,
}

impl From<AxialArg> for Axial {
    fn from(a: AxialArg) -> Axial {
        match a {
            AxialArg::Sa => Axial::Sa,
            AxialArg::Oa => Axial::Oa,
        }
    }
}

fn finite(name: &str, x: f64) -> CliResult<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(usage(format!("{name} must be a finite number, got {x}")))
    }
}

fn rate_terms(list: &Option<Vec<String>>) -> CliResult<Vec<RateTerm>> {
    match list {
        None => Ok(vec![RateTerm::B, RateTerm::K1]),
        Some(v) => v
            .iter()
            .map(|s| RateTerm::parse(s).map_err(|e| usage(format!("--terms: {e}"))))
            .collect(),
    }
}

fn drift_terms(list: &Option<Vec<String>>, axial: Axial) -> CliResult<Vec<DriftTerm>> {
    match list {
        None => Ok(gp::default_terms(axial)),
        Some(v) => v
            .iter()
            .map(|s| DriftTerm::parse(s).map_err(|e| usage(format!("--terms: {e}"))))
            .collect(),
    }
}

/// Options of `incal gyro rate`.
#[derive(clap::Args, Debug)]
pub struct RateArgs {
    /// Input CSV: rate_deg_s,output (optional run); rows with the same rate (and run) are samples; - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Latitude of the rate table (deg, -90..90): the Earth rate's vertical component is an input.
    #[arg(long, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Input axis along the table axis, up or down.
    #[arg(long, value_enum, default_value = "up")]
    pub ia: IaArg,
    /// Terms, comma separated, from K1, B, K2, K3 (K1 always).
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Relative standard uncertainty of the table rate (ppm), a type-B component of K1, B, K2, K3.
    #[arg(long, default_value_t = 0.0)]
    pub rate_uncertainty_ppm: f64,
    #[command(flatten)]
    pub result: ResultArgs,
}

fn read_rate(path: &Path) -> CliResult<(Table, Vec<RateObservation>)> {
    let t = Table::read(path)?;
    let cr = t.column("rate_deg_s")?;
    let co = t.column("output")?;
    let crun = t.opt_column("run");
    let mut obs = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        let rate = t.f64(row, cr)?;
        if rate.abs() > 1e5 {
            return Err(t.error_at(
                row,
                format!(
                    "rate_deg_s {} is beyond any rate table (|rate| <= 1e5 deg/s)",
                    num(rate)
                ),
            ));
        }
        let run = match crun {
            Some(c) => {
                let s = t.text(row, c).trim();
                if s.is_empty() {
                    return Err(t.error_at(row, "empty run label".into()));
                }
                Some(s.to_string())
            }
            None => None,
        };
        obs.push(RateObservation {
            rate_deg_s: rate,
            output: t.f64(row, co)?,
            run,
        });
    }
    Ok((t, obs))
}

/// `incal gyro rate`.
pub fn run_rate(a: &RateArgs) -> CliResult<()> {
    // In range: --latitude-deg goes through options::latitude_deg.
    let lat = a.latitude_deg.to_radians();
    let noise = noise_option(a.noise)?;
    let terms = rate_terms(&a.terms)?;
    if !(a.rate_uncertainty_ppm.is_finite() && (0.0..=1e5).contains(&a.rate_uncertainty_ppm)) {
        return Err(usage(format!(
            "--rate-uncertainty-ppm must be within 0..1e5, got {}",
            num(a.rate_uncertainty_ppm)
        )));
    }
    let (t, obs) = read_rate(&a.input)?;
    let r = gr::calibrate(
        &obs,
        &RateOptions {
            latitude_rad: lat,
            ia: a.ia.into(),
            terms,
            noise,
            rate_uncertainty_ppm: a.rate_uncertainty_ppm,
        },
    )
    .map_err(|e| in_file(&t.path, e))?;
    let mut doc = r
        .document(a.noise.is_some(), a.rate_uncertainty_ppm)
        .map_err(|e| in_file(&t.path, e))?;
    doc.inputs.push(t.input_file("input"));
    doc.options
        .insert("latitude_deg".into(), json!(a.latitude_deg));
    doc.options
        .insert("ia".into(), json!(InputAxis::from(a.ia).name()));
    doc.options.insert("noise".into(), json!(a.noise));
    a.result.emit(doc)
}

/// Options of `incal gyro positions`.
#[derive(clap::Args, Debug)]
pub struct PositionsArgs {
    /// Input CSV: angle_deg,output (optional azimuth_deg, overriding --azimuth-deg); - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Latitude (deg, -90..90).
    #[arg(long, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Azimuth of the head axis (deg from north towards east); needed unless the CSV has azimuth_deg.
    #[arg(long)]
    pub azimuth_deg: Option<f64>,
    /// Gyro axis along the head axis: sa (spin axis; the in-plane axis is OA) or oa.
    #[arg(long, value_enum)]
    pub axial: AxialArg,
    /// Scale factor K1 (output/(deg/s)) from a rate test.
    #[arg(long, group = "k1_source")]
    pub k1: Option<f64>,
    /// Standard uncertainty of --k1 (output/(deg/s)).
    #[arg(long)]
    pub u_k1: Option<f64>,
    /// A gyro rate result (JSON) whose K1 (with u and dof) is used.
    #[arg(long, group = "k1_source")]
    pub from: Option<PathBuf>,
    /// Fit K1 from the Earth-rate projection (needs several azimuths).
    #[arg(long, group = "k1_source")]
    pub fit_k1: bool,
    /// Drift terms, comma separated, from B, D_I, D_O, D_S, D_II, D_IO, D_IS, D_OO, D_SS (default: B, D_I and D_O for sa or D_S for oa).
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    #[command(flatten)]
    pub result: ResultArgs,
}

fn read_positions(
    path: &Path,
    azimuth_deg: Option<f64>,
) -> CliResult<(Table, Vec<PositionObservation>)> {
    let t = Table::read(path)?;
    let ca = t.column("angle_deg")?;
    let co = t.column("output")?;
    let cz = t.opt_column("azimuth_deg");
    if cz.is_none() && azimuth_deg.is_none() {
        return Err(usage(format!(
            "{}: give --azimuth-deg or an azimuth_deg column",
            t.path
        )));
    }
    let mut obs = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        let angle = t.f64(row, ca)?;
        if angle.abs() > 1e4 {
            return Err(t.error_at(
                row,
                format!(
                    "angle_deg {} is out of range (|angle| <= 1e4 deg)",
                    num(angle)
                ),
            ));
        }
        let az = match cz {
            Some(c) => t.f64(row, c)?,
            None => azimuth_deg.unwrap_or(0.0),
        };
        if az.abs() > 1e4 {
            return Err(t.error_at(
                row,
                format!(
                    "azimuth_deg {} is out of range (|azimuth| <= 1e4 deg)",
                    num(az)
                ),
            ));
        }
        obs.push(PositionObservation {
            angle_rad: angle.to_radians(),
            azimuth_rad: az.to_radians(),
            output: t.f64(row, co)?,
        });
    }
    Ok((t, obs))
}

/// The scale factor, its warnings, and the `--from` file's name and SHA-256.
type ScaleChoice = (ScaleFactor, Vec<Warning>, Option<(String, String)>);

/// K1 with u and dof from `--k1/--u-k1` or `--from`; warnings.
fn scale_factor(a: &PositionsArgs) -> CliResult<ScaleChoice> {
    if a.fit_k1 {
        if a.u_k1.is_some() {
            return Err(usage("--u-k1 goes with --k1"));
        }
        return Ok((ScaleFactor::Fit, vec![], None));
    }
    if let Some(k1) = a.k1 {
        let k1 = finite("--k1", k1)?;
        if k1 == 0.0 {
            return Err(usage("--k1 must not be 0"));
        }
        let mut w = Vec::new();
        let u = match a.u_k1 {
            Some(u) if u.is_finite() && u >= 0.0 && u < k1.abs() => u,
            Some(u) => {
                return Err(usage(format!(
                    "--u-k1 must be >= 0 and smaller than |--k1|, got {}",
                    num(u)
                )))
            }
            None => {
                w.push(Warning::new(
                    WarningCode::MissingUncertainty,
                    "--k1 given without --u-k1: K1 is taken as exact, and every u derived from it is too small by its share",
                ));
                0.0
            }
        };
        return Ok((
            ScaleFactor::Known {
                k1,
                u,
                dof: f64::INFINITY,
            },
            w,
            None,
        ));
    }
    if let Some(p) = &a.from {
        if a.u_k1.is_some() {
            return Err(usage(
                "--u-k1 goes with --k1 (the u of --from comes from the result)",
            ));
        }
        let (name, sha, doc) = read_document(p)?;
        if doc.procedure != Procedure::GyroRate {
            return Err(CliError::Input(format!(
                "{name}: --from needs a gyro-rate result, this is a {} result",
                doc.procedure
            )));
        }
        let c = doc
            .coefficients
            .get("K1")
            .ok_or_else(|| CliError::Input(format!("{name}: $.coefficients.K1: missing")))?;
        if !(c.value.is_finite() && c.value != 0.0 && c.u.is_finite() && c.u >= 0.0) {
            return Err(CliError::Input(format!(
                "{name}: $.coefficients.K1: value {} with u {} is not a usable scale factor",
                c.value, c.u
            )));
        }
        return Ok((
            ScaleFactor::Known {
                k1: c.value,
                u: c.u,
                dof: c.dof.unwrap_or(f64::INFINITY),
            },
            vec![],
            Some((name, sha)),
        ));
    }
    Err(usage(
        "give --k1 (with --u-k1), --from RATE.json or --fit-k1",
    ))
}

/// `incal gyro positions`.
pub fn run_positions(a: &PositionsArgs) -> CliResult<()> {
    // In range: --latitude-deg goes through options::latitude_deg.
    let lat = a.latitude_deg.to_radians();
    let noise = noise_option(a.noise)?;
    let axial: Axial = a.axial.into();
    let terms = drift_terms(&a.terms, axial)?;
    if let Some(z) = a.azimuth_deg {
        finite("--azimuth-deg", z)?;
    }
    let (sf, warnings, from) = scale_factor(a)?;
    let (t, obs) = read_positions(&a.input, a.azimuth_deg)?;
    let r = gp::calibrate(
        &obs,
        &PositionsOptions {
            latitude_rad: lat,
            axial,
            terms,
            noise,
            scale_factor: sf,
        },
    )
    .map_err(|e| in_file(&t.path, e))?;
    let mut doc = r
        .document(a.noise.is_some(), sf, axial.name())
        .map_err(|e| in_file(&t.path, e))?;
    doc.warnings.extend(warnings);
    doc.inputs.push(t.input_file("input"));
    if let (Some((name, sha)), Some(p)) = (from, &a.from) {
        let _ = name;
        doc.inputs
            .push(input_file("from", &p.display().to_string(), sha, None));
    }
    doc.options
        .insert("latitude_deg".into(), json!(a.latitude_deg));
    doc.options
        .insert("azimuth_deg".into(), json!(a.azimuth_deg));
    doc.options.insert("noise".into(), json!(a.noise));
    a.result.emit(doc)
}

/// Options of `incal plan gyro-rate`.
#[derive(clap::Args, Debug)]
pub struct PlanRateArgs {
    /// Table rates (deg/s), comma separated.
    #[arg(long, value_delimiter = ',', required = true)]
    pub rates_deg_s: Vec<f64>,
    /// Samples per rate.
    #[arg(long, default_value_t = 1)]
    pub samples: usize,
    /// Standard deviation of one output sample (output units).
    #[arg(long)]
    pub noise: f64,
    /// Nominal scale factor K1 (output/(deg/s)).
    #[arg(long)]
    pub k1: f64,
    /// Latitude (deg).
    #[arg(long, default_value_t = 0.0, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Input axis up or down.
    #[arg(long, value_enum, default_value = "up")]
    pub ia: IaArg,
    /// Terms, comma separated, from K1, B, K2, K3.
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Relative standard uncertainty of the table rate (ppm).
    #[arg(long, default_value_t = 0.0)]
    pub rate_uncertainty_ppm: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

fn check_plan_noise(noise: f64, samples: usize) -> CliResult<()> {
    if !(noise.is_finite() && noise > 0.0) {
        return Err(usage(format!(
            "--noise must be a positive number, got {}",
            num(noise)
        )));
    }
    if samples == 0 {
        return Err(usage("--samples must be at least 1"));
    }
    if samples > 100_000_000 {
        return Err(usage("--samples must be at most 100000000"));
    }
    Ok(())
}

fn emit_plan(
    json_out: bool,
    output: Option<&Path>,
    header: Value,
    title: String,
    rows: Vec<(String, f64, String)>,
    warnings: &[Warning],
) -> CliResult<()> {
    if json_out {
        let mut doc = header;
        doc["warnings"] = json!(warnings);
        let mut u = Map::new();
        let mut units = Map::new();
        for (n, v, unit) in &rows {
            u.insert(n.clone(), json!(v));
            units.insert(n.clone(), json!(unit));
        }
        doc["predicted_u"] = Value::Object(u);
        doc["units"] = Value::Object(units);
        return write_text(output, &json_text(&doc));
    }
    let mut s = title;
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|(n, v, unit)| vec![n.clone(), sig(*v, 3), unit.clone()])
        .collect();
    s.push_str(&table(&["term", "predicted u", "unit"], &body));
    for w in warnings {
        s.push_str(&format!("warning [{}]: {}\n", w.code, w.message));
    }
    write_text(output, &s)
}

/// `incal plan gyro-rate`.
pub fn plan_rate(a: &PlanRateArgs) -> CliResult<()> {
    check_plan_noise(a.noise, a.samples)?;
    // In range: --latitude-deg goes through options::latitude_deg.
    let lat = a.latitude_deg.to_radians();
    for r in &a.rates_deg_s {
        if !(r.is_finite() && r.abs() <= 1e5) {
            return Err(usage(format!(
                "--rates-deg-s: {} is not a table rate (|rate| <= 1e5 deg/s)",
                num(*r)
            )));
        }
    }
    let k1 = finite("--k1", a.k1)?;
    let opts = RateOptions {
        latitude_rad: lat,
        ia: a.ia.into(),
        terms: rate_terms(&a.terms)?,
        noise: incal::estimation::Noise::Auto,
        rate_uncertainty_ppm: a.rate_uncertainty_ppm,
    };
    let p = gr::plan(&a.rates_deg_s, a.samples, a.noise, k1, &opts).map_err(core)?;
    let rows: Vec<(String, f64, String)> = p
        .coefficients
        .names()
        .iter()
        .enumerate()
        .filter(|(_, n)| !n.starts_with("K1_"))
        .map(|(k, n)| {
            (
                n.clone(),
                p.coefficients.u_at(k),
                gr::coefficient_unit(n).to_string(),
            )
        })
        .collect();
    let header = json!({
        "plan": "gyro-rate",
        "rates_deg_s": a.rates_deg_s,
        "samples": a.samples,
        "noise": a.noise,
        "k1": a.k1,
        "latitude_deg": a.latitude_deg,
        "ia": opts.ia.name(),
        "rate_uncertainty_ppm": a.rate_uncertainty_ppm,
    });
    let title = format!(
        "Gyro rate-transfer plan: {} rates, {} samples each, noise {:e} per sample, K1 = {}\n",
        a.rates_deg_s.len(),
        a.samples,
        a.noise,
        a.k1
    );
    emit_plan(
        a.json,
        a.output.as_deref(),
        header,
        title,
        rows,
        &p.warnings,
    )
}

fn default_angles() -> Vec<f64> {
    (0..12).map(|k| 30.0 * k as f64).collect()
}

/// Options of `incal plan gyro-positions`.
#[derive(clap::Args, Debug)]
pub struct PlanPositionsArgs {
    /// Head angles (deg), comma separated (default: 0, 30, ..., 330).
    #[arg(long, value_delimiter = ',')]
    pub angles_deg: Option<Vec<f64>>,
    /// Azimuths of the head axis (deg), comma separated; every angle at each.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub azimuths_deg: Vec<f64>,
    /// Latitude (deg).
    #[arg(long, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Gyro axis along the head axis.
    #[arg(long, value_enum, default_value = "sa")]
    pub axial: AxialArg,
    /// Drift terms, comma separated.
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Nominal scale factor K1 (output/(deg/s)).
    #[arg(long)]
    pub k1: f64,
    /// Standard uncertainty of K1 (output/(deg/s)).
    #[arg(long, default_value_t = 0.0)]
    pub u_k1: f64,
    /// Predict with K1 fitted from the Earth-rate projection.
    #[arg(long)]
    pub fit_k1: bool,
    /// Standard deviation of one output sample (output units).
    #[arg(long)]
    pub noise: f64,
    /// Samples per position.
    #[arg(long, default_value_t = 1)]
    pub samples: usize,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

fn check_angles(flag: &str, v: &[f64]) -> CliResult<()> {
    if v.is_empty() {
        return Err(usage(format!("{flag}: give at least one angle")));
    }
    for x in v {
        crate::options::angle_deg(flag, *x)?;
    }
    Ok(())
}

/// `incal plan gyro-positions`.
pub fn plan_positions(a: &PlanPositionsArgs) -> CliResult<()> {
    check_plan_noise(a.noise, a.samples)?;
    // In range: --latitude-deg goes through options::latitude_deg.
    let lat = a.latitude_deg.to_radians();
    let angles = a.angles_deg.clone().unwrap_or_else(default_angles);
    check_angles("--angles-deg", &angles)?;
    check_angles("--azimuths-deg", &a.azimuths_deg)?;
    let k1 = finite("--k1", a.k1)?;
    if !(a.u_k1.is_finite() && a.u_k1 >= 0.0) {
        return Err(usage("--u-k1 must be a non-negative number"));
    }
    let axial: Axial = a.axial.into();
    let opts = PositionsOptions {
        latitude_rad: lat,
        axial,
        terms: drift_terms(&a.terms, axial)?,
        noise: incal::estimation::Noise::Auto,
        scale_factor: if a.fit_k1 {
            ScaleFactor::Fit
        } else {
            ScaleFactor::Known {
                k1,
                u: a.u_k1,
                dof: f64::INFINITY,
            }
        },
    };
    let rad = |v: &[f64]| v.iter().map(|x| x.to_radians()).collect::<Vec<f64>>();
    let p = gp::plan(
        &rad(&angles),
        &rad(&a.azimuths_deg),
        a.samples,
        a.noise,
        k1,
        &opts,
    )
    .map_err(core)?;
    let rows: Vec<(String, f64, String)> = p
        .coefficients
        .names()
        .iter()
        .enumerate()
        .map(|(k, n)| {
            let unit = if n == "K1" {
                "output/(deg/s)".to_string()
            } else {
                DriftTerm::parse(n).map_or(String::new(), |t| t.unit().to_string())
            };
            (n.clone(), p.coefficients.u_at(k), unit)
        })
        .collect();
    let header = json!({
        "plan": "gyro-positions",
        "angles_deg": angles,
        "azimuths_deg": a.azimuths_deg,
        "samples": a.samples,
        "noise": a.noise,
        "k1": a.k1,
        "u_k1": a.u_k1,
        "fit_k1": a.fit_k1,
        "latitude_deg": a.latitude_deg,
        "axial": axial.name(),
    });
    let title = format!(
        "Gyro multi-position plan: {} angles x {} azimuths, {} samples each, noise {:e} per sample, K1 = {}\n",
        angles.len(),
        a.azimuths_deg.len(),
        a.samples,
        a.noise,
        a.k1
    );
    emit_plan(
        a.json,
        a.output.as_deref(),
        header,
        title,
        rows,
        &p.warnings,
    )
}

/// Options of `incal simulate gyro-rate`.
#[derive(clap::Args, Debug)]
pub struct SimRateArgs {
    /// Scale factor K1 (output/(deg/s)), the mean of K1+ and K1-.
    #[arg(long, default_value_t = 0.02)]
    pub k1: f64,
    /// Scale-factor asymmetry (K1+ - K1-)/K1 (ppm).
    #[arg(long, default_value_t = 0.0)]
    pub asymmetry_ppm: f64,
    /// Bias B (deg/h).
    #[arg(long, default_value_t = 5.0)]
    pub b_deg_h: f64,
    /// K2 (1/(deg/s)).
    #[arg(long, default_value_t = 0.0)]
    pub k2: f64,
    /// K3 (1/(deg/s)^2).
    #[arg(long, default_value_t = 0.0)]
    pub k3: f64,
    /// Latitude (deg).
    #[arg(long, default_value_t = 45.0, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Input axis up or down.
    #[arg(long, value_enum, default_value = "up")]
    pub ia: IaArg,
    /// Table rates (deg/s), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "-200,-100,-50,-10,-1,1,10,50,100,200"
    )]
    pub rates_deg_s: Vec<f64>,
    /// Samples per rate.
    #[arg(long, default_value_t = 20)]
    pub samples: usize,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 2e-5)]
    pub noise: f64,
    /// Runs (2 or more add a run column).
    #[arg(long, default_value_t = 1)]
    pub runs: usize,
    /// Run-to-run scatter of K1 (ppm, standard deviation).
    #[arg(long, default_value_t = 0.0)]
    pub run_scatter_ppm: f64,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate gyro-rate`.
pub fn simulate_rate_cmd(a: &SimRateArgs) -> CliResult<()> {
    for (n, v) in [
        ("--k1", a.k1),
        ("--asymmetry-ppm", a.asymmetry_ppm),
        ("--b-deg-h", a.b_deg_h),
        ("--k2", a.k2),
        ("--k3", a.k3),
    ] {
        finite(n, v)?;
    }
    if a.k1 == 0.0 || a.k1.abs() > 1e9 {
        return Err(usage("--k1 must be non-zero and at most 1e9 in magnitude"));
    }
    if a.asymmetry_ppm.abs() >= 1e6 {
        return Err(usage("--asymmetry-ppm must be below 1e6 in magnitude"));
    }
    if a.b_deg_h.abs() > 1e7 || a.k2.abs() > 1.0 || a.k3.abs() > 1.0 {
        return Err(usage(
            "--b-deg-h (<= 1e7), --k2 and --k3 (<= 1) out of range",
        ));
    }
    // In range: --latitude-deg goes through options::latitude_deg.
    let lat = a.latitude_deg.to_radians();
    if a.samples == 0 || a.runs == 0 {
        return Err(usage("--samples and --runs must be at least 1"));
    }
    crate::options::sim_size(&[
        ("--rates-deg-s", a.rates_deg_s.len() as f64),
        ("--samples", a.samples as f64),
        ("--runs", a.runs as f64),
    ])?;
    if let Some(r) = a
        .rates_deg_s
        .iter()
        .find(|r| !(r.is_finite() && r.abs() <= 1e5))
    {
        return Err(usage(format!(
            "--rates-deg-s: {} is not a table rate (|rate| <= 1e5 deg/s)",
            num(*r)
        )));
    }
    if !(a.noise.is_finite() && (0.0..=1e9).contains(&a.noise)) {
        return Err(usage("--noise must be a non-negative number (at most 1e9)"));
    }
    if !(a.run_scatter_ppm.is_finite() && (0.0..1e5).contains(&a.run_scatter_ppm)) {
        return Err(usage("--run-scatter-ppm must be within 0..1e5"));
    }
    let half = 0.5 * a.asymmetry_ppm * 1e-6;
    let obs = simulate_rate(&GyroRateSim {
        k1_pos: a.k1 * (1.0 + half),
        k1_neg: a.k1 * (1.0 - half),
        b_deg_h: a.b_deg_h,
        k2: a.k2,
        k3: a.k3,
        latitude_rad: lat,
        ia: a.ia.into(),
        rates_deg_s: a.rates_deg_s.clone(),
        samples: a.samples,
        noise: a.noise,
        runs: a.runs,
        run_scatter_ppm: a.run_scatter_ppm,
        seed: a.seed,
    });
    let mut text = String::from(if a.runs > 1 {
        "rate_deg_s,output,run\n"
    } else {
        "rate_deg_s,output\n"
    });
    for o in &obs {
        if !o.output.is_finite() {
            return Err(usage(
                "the truth gives a non-finite output; choose smaller coefficients",
            ));
        }
        match &o.run {
            Some(r) => text.push_str(&format!("{},{},{r}\n", o.rate_deg_s, o.output)),
            None => text.push_str(&format!("{},{}\n", o.rate_deg_s, o.output)),
        }
    }
    write_text(a.output.as_deref(), &text)
}

/// Options of `incal simulate gyro-positions`.
#[derive(clap::Args, Debug)]
pub struct SimPositionsArgs {
    /// Scale factor K1 (output/(deg/s)).
    #[arg(long, default_value_t = 0.02)]
    pub k1: f64,
    /// Bias B (deg/h).
    #[arg(long, default_value_t = 3.0)]
    pub b_deg_h: f64,
    /// D_I (deg/h/g).
    #[arg(long, default_value_t = 0.8)]
    pub d_i_deg_h_g: f64,
    /// D_O (deg/h/g).
    #[arg(long, default_value_t = -0.5)]
    pub d_o_deg_h_g: f64,
    /// D_S (deg/h/g).
    #[arg(long, default_value_t = 0.4)]
    pub d_s_deg_h_g: f64,
    /// D_II (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_ii_deg_h_g2: f64,
    /// D_IO (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_io_deg_h_g2: f64,
    /// D_IS (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_is_deg_h_g2: f64,
    /// D_OO (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_oo_deg_h_g2: f64,
    /// D_SS (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_ss_deg_h_g2: f64,
    /// Latitude (deg).
    #[arg(long, default_value_t = 45.0, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Azimuths of the head axis (deg), comma separated; two or more add an azimuth_deg column.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub azimuths_deg: Vec<f64>,
    /// Gyro axis along the head axis.
    #[arg(long, value_enum, default_value = "sa")]
    pub axial: AxialArg,
    /// Head angles (deg), comma separated (default: 0, 30, ..., 330).
    #[arg(long, value_delimiter = ',')]
    pub angles_deg: Option<Vec<f64>>,
    /// Samples per position.
    #[arg(long, default_value_t = 10)]
    pub samples: usize,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 2e-5)]
    pub noise: f64,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate gyro-positions`.
pub fn simulate_positions_cmd(a: &SimPositionsArgs) -> CliResult<()> {
    let drift = DriftTruth {
        b: a.b_deg_h,
        d_i: a.d_i_deg_h_g,
        d_o: a.d_o_deg_h_g,
        d_s: a.d_s_deg_h_g,
        d_ii: a.d_ii_deg_h_g2,
        d_io: a.d_io_deg_h_g2,
        d_is: a.d_is_deg_h_g2,
        d_oo: a.d_oo_deg_h_g2,
        d_ss: a.d_ss_deg_h_g2,
    };
    for t in gp::ALL_TERMS {
        let v = drift.get(t.name());
        if !(v.is_finite() && v.abs() <= 1e7) {
            return Err(usage(format!(
                "{} truth must be finite and at most 1e7, got {}",
                t.name(),
                num(v)
            )));
        }
    }
    finite("--k1", a.k1)?;
    if a.k1 == 0.0 || a.k1.abs() > 1e9 {
        return Err(usage("--k1 must be non-zero and at most 1e9 in magnitude"));
    }
    // In range: --latitude-deg goes through options::latitude_deg.
    let lat = a.latitude_deg.to_radians();
    let angles = a.angles_deg.clone().unwrap_or_else(default_angles);
    check_angles("--angles-deg", &angles)?;
    check_angles("--azimuths-deg", &a.azimuths_deg)?;
    if a.samples == 0 {
        return Err(usage("--samples must be at least 1"));
    }
    crate::options::sim_size(&[
        ("--angles-deg", angles.len() as f64),
        ("--azimuths-deg", a.azimuths_deg.len() as f64),
        ("--samples", a.samples as f64),
    ])?;
    if !(a.noise.is_finite() && (0.0..=1e9).contains(&a.noise)) {
        return Err(usage("--noise must be a non-negative number (at most 1e9)"));
    }
    let obs = simulate_positions(&GyroPositionsSim {
        k1: a.k1,
        drift,
        latitude_rad: lat,
        azimuths_rad: a.azimuths_deg.iter().map(|z| z.to_radians()).collect(),
        axial: a.axial.into(),
        angles_deg: angles,
        samples: a.samples,
        noise: a.noise,
        seed: a.seed,
    });
    let several = a.azimuths_deg.len() > 1;
    let mut text = String::from(if several {
        "angle_deg,azimuth_deg,output\n"
    } else {
        "angle_deg,output\n"
    });
    for o in &obs {
        // Round-trip exact angles: printed to 1e-9 deg.
        let ang = (o.angle_rad.to_degrees() * 1e9).round() / 1e9;
        if several {
            let az = (o.azimuth_rad.to_degrees() * 1e9).round() / 1e9;
            text.push_str(&format!("{ang},{az},{}\n", o.output));
        } else {
            text.push_str(&format!("{ang},{}\n", o.output));
        }
    }
    write_text(a.output.as_deref(), &text)
}
