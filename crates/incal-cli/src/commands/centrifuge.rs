//! `incal centrifuge` and `incal simulate centrifuge` (seed 001,
//! methods.md §2).

use std::path::PathBuf;

use incal::document::{Decision, DecisionCode, Procedure, ResultDocument, Warning, WarningCode};
use incal::models::{AccelerometerModel, Term};
use incal::procedures::centrifuge::radius::ValueU;
use incal::procedures::centrifuge::{calibrate, CentrifugeOptions, Observation};
use incal::rigs::centrifuge::{Centrifuge, Plane, Position};
use incal::sim::centrifuge::{rates_for_levels, simulate as sim_centrifuge, CentrifugeSim};
use incal::units::{arcsec_to_rad, rad_to_deg, STANDARD_GRAVITY_M_S2};
use serde_json::json;

use crate::documents::read_document;
use crate::error::{in_file, usage, CliError, CliResult};
use crate::input::Table;
use crate::options::noise_option;
use crate::output::{input_file, write_text, ResultArgs};

/// Options of `incal centrifuge`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input CSV with columns plane, phi_deg, polarity, omega_rad_s, output (one row per sample); - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// A tumble result (incal tumble --json) giving K0 and K1 with their u and covariance.
    #[arg(long, value_name = "TUMBLE.json")]
    pub from: Option<PathBuf>,
    /// Bias K0 from the 1 g calibration (g); overrides --from.
    #[arg(long = "k0", visible_alias = "k0-g")]
    pub k0: Option<f64>,
    /// Scale factor K1 from the 1 g calibration (output/g); overrides --from.
    #[arg(long)]
    pub k1: Option<f64>,
    /// Standard uncertainty of K0 (g); with --k0 (missing: taken as 0, with a warning).
    #[arg(long = "u-k0", visible_alias = "u-k0-g")]
    pub u_k0: Option<f64>,
    /// Standard uncertainty of K1 (output/g); with --k1 (missing: taken as 0, with a warning).
    #[arg(long)]
    pub u_k1: Option<f64>,
    /// Nominal test radius R0 (m): start of the regression iteration.
    #[arg(long)]
    pub radius_m: f64,
    /// Latitude of the centrifuge (deg, north positive).
    #[arg(long, allow_hyphen_values = true, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Local gravity g_L (m/s^2): the g unit of every coefficient.
    #[arg(long = "gravity-m-s2", visible_alias = "g-local", default_value_t = STANDARD_GRAVITY_M_S2)]
    pub gravity_m_s2: f64,
    /// The table spins opposite to Earth's sense (default: in Earth's sense).
    #[arg(long)]
    pub opposite_sense: bool,
    /// Model order of the radius regression and the station fits (2 or 3).
    #[arg(long, default_value_t = 3)]
    pub order: usize,
    /// Bound of the fixture angle error (deg), for the type-B alignment component.
    #[arg(long, default_value_t = 0.0)]
    pub alignment_tolerance_deg: f64,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Coefficients required, comma separated (default: every one the data supports).
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Relative standard uncertainty of the table rate (ppm): a type-B input of the static (eq. 6) radius, u(R)/R = 2 u(omega)/omega.
    #[arg(long, default_value_t = 0.0)]
    pub u_omega_ppm: f64,
    #[command(flatten)]
    pub result: ResultArgs,
}

fn read_observations(path: &std::path::Path) -> CliResult<(Table, Vec<Observation>)> {
    let t = Table::read(path)?;
    let cp = t.column("plane")?;
    let cf = t.column("phi_deg")?;
    let cs = t.column("polarity")?;
    let cw = t.column("omega_rad_s")?;
    let co = t.column("output")?;
    let mut obs = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        let plane = Plane::parse(t.text(row, cp))
            .map_err(|e| t.error_at(row, format!("column 'plane': {e}")))?;
        let phi = t.f64(row, cf)?;
        let pol = t.f64(row, cs)?;
        let polarity: i8 = if pol == 1.0 {
            1
        } else if pol == -1.0 {
            -1
        } else {
            return Err(t.error_at(
                row,
                format!("column 'polarity': '{}' must be +1 or -1", t.text(row, cs)),
            ));
        };
        let omega = t.f64(row, cw)?;
        let output = t.f64(row, co)?;
        obs.push(Observation {
            position: Position {
                plane,
                phi_rad: phi.to_radians(),
                polarity,
            },
            omega_rad_s: omega,
            output,
        });
    }
    Ok((t, obs))
}

/// K0 and K1 with u and their covariance, and where they came from.
struct ScaleInputs {
    k0: ValueU,
    k1: ValueU,
    cov_k0_k1: f64,
    warnings: Vec<Warning>,
    from: Option<(String, String, ResultDocument)>,
}

/// K0, K1 from `--from` and/or `--k0/--k1` (explicit values win; an
/// explicit value without its u is a warning, never a silent 0).
fn scale_inputs(a: &Args) -> CliResult<ScaleInputs> {
    let from = match &a.from {
        Some(p) => {
            let (name, sha, doc) = read_document(p)?;
            if doc.procedure != Procedure::Tumble {
                return Err(CliError::Input(format!(
                    "{name}: --from needs a tumble result, this is a {} result",
                    doc.procedure
                )));
            }
            Some((name, sha, doc))
        }
        None => None,
    };
    let mut warnings = Vec::new();
    let mut pick = |flag: &str,
                    uflag: &str,
                    name: &str,
                    v: Option<f64>,
                    u: Option<f64>|
     -> CliResult<ValueU> {
        match (v, &from) {
            (Some(value), _) => {
                if let Some(u) = u {
                    // An input's u as large as the value (K1) or a whole g
                    // (K0) leaves nothing to calibrate.
                    let limit = if name == "K1" { value.abs() } else { 1.0 };
                    if !(u.is_finite() && u >= 0.0 && u < limit) {
                        return Err(usage(format!(
                            "{uflag} must be >= 0 and below {}, got {}",
                            if name == "K1" { "|--k1|" } else { "1 g" },
                            crate::output::num(u)
                        )));
                    }
                }
                if u.is_none() {
                    warnings.push(Warning::new(
                        WarningCode::MissingUncertainty,
                        format!("{flag} given without {uflag}: {name} is taken as exact, and every u derived from it is too small by its share"),
                    ));
                }
                Ok(ValueU {
                    value,
                    u: u.unwrap_or(0.0),
                })
            }
            (None, Some((file, _, doc))) => {
                if u.is_some() {
                    return Err(usage(format!(
                        "{uflag} goes with {flag} (the u of --from comes from the result)"
                    )));
                }
                let c = doc.coefficients.get(name).ok_or_else(|| {
                    CliError::Input(format!("{file}: $.coefficients.{name}: missing"))
                })?;
                Ok(ValueU {
                    value: c.value,
                    u: c.u,
                })
            }
            (None, None) => Err(usage(format!(
                "give {flag} (with {uflag}) or --from TUMBLE.json"
            ))),
        }
    };
    let k0 = pick("--k0", "--u-k0", "K0", a.k0, a.u_k0)?;
    let k1 = pick("--k1", "--u-k1", "K1", a.k1, a.u_k1)?;
    // The covariance holds only when both come from the same result.
    let cov_k0_k1 = match (&from, a.k0, a.k1) {
        (Some((file, _, doc)), None, None) => doc.covariance("K0", "K1").ok_or_else(|| {
            CliError::Input(format!("{file}: $.correlation: no entry for K0 and K1"))
        })?,
        _ => 0.0,
    };
    Ok(ScaleInputs {
        k0,
        k1,
        cov_k0_k1,
        warnings,
        from,
    })
}

/// `incal centrifuge`.
pub fn run(a: &Args) -> CliResult<()> {
    let noise = noise_option(a.noise)?;
    if !(a.u_omega_ppm.is_finite() && (0.0..=1e5).contains(&a.u_omega_ppm)) {
        return Err(usage(format!(
            "--u-omega-ppm must be within 0..1e5, got {}",
            crate::output::num(a.u_omega_ppm)
        )));
    }
    let terms = match &a.terms {
        None => None,
        Some(v) => Some(
            v.iter()
                .map(|s| Term::parse(s).map_err(|e| usage(format!("--terms: {e}"))))
                .collect::<CliResult<Vec<Term>>>()?,
        ),
    };
    let si = scale_inputs(a)?;
    let opts = CentrifugeOptions {
        k0_g: si.k0,
        k1: si.k1,
        cov_k0_k1: si.cov_k0_k1,
        radius0_m: a.radius_m,
        latitude_rad: a.latitude_deg.to_radians(),
        g_local_m_s2: a.gravity_m_s2,
        opposite_sense: a.opposite_sense,
        order: a.order,
        alignment_tolerance_rad: a.alignment_tolerance_deg.to_radians(),
        noise,
        terms,
        u_omega_ppm: a.u_omega_ppm,
    };
    let (table, obs) = read_observations(&a.input)?;
    let r = calibrate(&obs, &opts).map_err(|e| in_file(&table.path, e))?;
    let mut doc = r.document(&opts).map_err(|e| in_file(&table.path, e))?;
    doc.inputs.push(table.input_file("input"));
    if let Some((name, sha, from)) = &si.from {
        // The path as given: `-` for standard input.
        let path = if name == "<stdin>" {
            "-"
        } else {
            name.as_str()
        };
        doc.inputs.push(input_file("from", path, sha.clone(), None));
        doc.decisions.push(Decision {
            code: DecisionCode::ChainedInput,
            message: format!(
                "K0 and K1 from the tumble result {name}{} (covariance of K0 and K1 included)",
                from.instrument
                    .serial
                    .as_ref()
                    .map_or(String::new(), |s| format!(" of serial {s}"))
            ),
        });
    }
    doc.warnings.splice(0..0, si.warnings);
    doc.options.insert("noise".into(), json!(a.noise));
    doc.options
        .insert("u_omega_ppm".into(), json!(a.u_omega_ppm));
    a.result.emit(doc)
}

/// Truth instrument for the centrifuge simulator (g units).
#[derive(clap::Args, Debug, Clone)]
pub struct TruthArgs {
    /// Bias K0 (g).
    #[arg(
        long = "k0",
        visible_alias = "k0-g",
        default_value_t = 1.2e-4,
        allow_hyphen_values = true
    )]
    pub k0_g: f64,
    /// Scale factor K1 (output/g).
    #[arg(long, default_value_t = 1.3, allow_hyphen_values = true)]
    pub k1: f64,
    /// K2 (g/g^2).
    #[arg(long, default_value_t = 3.9e-6, allow_hyphen_values = true)]
    pub k2: f64,
    /// K3 (g/g^3).
    #[arg(long, default_value_t = 5e-9, allow_hyphen_values = true)]
    pub k3: f64,
    /// Misalignment delta_o (arcsec).
    #[arg(long, default_value_t = 40.0, allow_hyphen_values = true)]
    pub delta_o_arcsec: f64,
    /// Misalignment delta_p (arcsec).
    #[arg(long, default_value_t = -20.0, allow_hyphen_values = true)]
    pub delta_p_arcsec: f64,
    /// Cross-coupling K_ip (g/g^2).
    #[arg(long, default_value_t = 7e-6, allow_hyphen_values = true)]
    pub k_ip: f64,
    /// Cross-coupling K_io (g/g^2).
    #[arg(long, default_value_t = 2e-6, allow_hyphen_values = true)]
    pub k_io: f64,
    /// Cross-coupling K_po (g/g^2).
    #[arg(long, default_value_t = -1e-6, allow_hyphen_values = true)]
    pub k_po: f64,
    /// Cross-axis nonlinearity K_pp (g/g^2).
    #[arg(long, default_value_t = 4.6e-7, allow_hyphen_values = true)]
    pub k_pp: f64,
    /// Cross-axis nonlinearity K_oo (g/g^2).
    #[arg(long, default_value_t = -3e-7, allow_hyphen_values = true)]
    pub k_oo: f64,
    /// Odd quadratic K_oq (g/g^2).
    #[arg(long, default_value_t = 5e-7, allow_hyphen_values = true)]
    pub k_oq: f64,
}

impl TruthArgs {
    /// The truth model (fails on a non-finite value or K1 = 0).
    pub fn model(&self) -> CliResult<AccelerometerModel> {
        let m = AccelerometerModel {
            k0_g: self.k0_g,
            k1_out_per_g: self.k1,
            k2: self.k2,
            k3: self.k3,
            delta_o_rad: arcsec_to_rad(self.delta_o_arcsec),
            delta_p_rad: arcsec_to_rad(self.delta_p_arcsec),
            k_ip: self.k_ip,
            k_io: self.k_io,
            k_po: self.k_po,
            k_pp: self.k_pp,
            k_oo: self.k_oo,
            k_oq: self.k_oq,
        };
        m.validate()
            .map_err(|e| usage(format!("truth model: {e}")))?;
        Ok(m)
    }
}

/// Options of `incal simulate centrifuge`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub truth: TruthArgs,
    #[command(flatten)]
    pub rig: RigArgs,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// The rig and the test plan (shared by `simulate centrifuge` and `plan centrifuge`).
#[derive(clap::Args, Debug)]
pub struct RigArgs {
    /// True ECM radius with IA radial, polarity + (m).
    #[arg(long, default_value_t = 0.714775)]
    pub r_plus_m: f64,
    /// True ECM radius with IA radial, polarity - (m).
    #[arg(long, default_value_t = 0.705794)]
    pub r_minus_m: f64,
    /// Nominal radius used to turn --levels-g into rates (m).
    #[arg(long, default_value_t = 0.71)]
    pub radius_m: f64,
    /// IA tilt above the horizontal plane (arcsec).
    #[arg(long, default_value_t = 60.0, allow_hyphen_values = true)]
    pub tilt_arcsec: f64,
    /// Latitude (deg, north positive).
    #[arg(long, default_value_t = 39.9, allow_hyphen_values = true, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Local gravity (m/s^2).
    #[arg(long = "gravity-m-s2", visible_alias = "g-local", default_value_t = STANDARD_GRAVITY_M_S2)]
    pub g_local: f64,
    /// The table spins opposite to Earth's sense.
    #[arg(long)]
    pub opposite_sense: bool,
    /// Positions as plane:phi_deg, comma separated (both polarities of each unless --single-polarity).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "ip:0,ip:90,io:90,ip:45,io:45,po:45"
    )]
    pub positions: Vec<String>,
    /// Only polarity +1.
    #[arg(long)]
    pub single_polarity: bool,
    /// Nominal centripetal inputs (g) at --radius-m, comma separated; 0 = at rest.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,1,2,4,7,10,14,18,22,25"
    )]
    pub levels_g: Vec<f64>,
    /// Samples per point.
    #[arg(long, default_value_t = 5)]
    pub samples: usize,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 2e-6)]
    pub noise: f64,
}

fn parse_positions(list: &[String], single: bool) -> CliResult<Vec<Position>> {
    let mut out = Vec::new();
    for item in list {
        let (p, d) = item
            .split_once(':')
            .ok_or_else(|| usage(format!("--positions: '{item}' is not plane:phi_deg")))?;
        let plane = Plane::parse(p).map_err(|e| usage(format!("--positions: {e}")))?;
        let deg: f64 = d
            .trim()
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite())
            .ok_or_else(|| usage(format!("--positions: '{d}' is not an angle")))?;
        let pols: &[i8] = if single { &[1] } else { &[1, -1] };
        for &polarity in pols {
            out.push(Position {
                plane,
                phi_rad: deg.to_radians(),
                polarity,
            });
        }
    }
    Ok(out)
}

/// The simulated test of `truth` on the rig and plan `a` (checked).
fn sim_config(truth: &TruthArgs, a: &RigArgs, seed: u64) -> CliResult<CentrifugeSim> {
    if a.samples == 0 {
        return Err(usage("--samples must be at least 1"));
    }
    if !(a.noise.is_finite() && a.noise >= 0.0) {
        return Err(usage("--noise must be a non-negative number"));
    }
    for (name, v, max) in [
        ("--r-plus-m", a.r_plus_m, 100.0),
        ("--r-minus-m", a.r_minus_m, 100.0),
        ("--radius-m", a.radius_m, 100.0),
        ("--gravity-m-s2", a.g_local, 100.0),
    ] {
        if !(v.is_finite() && v > 0.0 && v <= max) {
            return Err(usage(format!(
                "{name} must be a positive number at most {max}, got {}",
                crate::output::num(v)
            )));
        }
    }
    if a.tilt_arcsec.abs() > 36000.0 {
        return Err(usage(
            "--tilt-arcsec must be at most 36000 (10 deg) in magnitude",
        ));
    }
    if let Some(l) = a.levels_g.iter().find(|l| **l > 1000.0) {
        return Err(usage(format!(
            "--levels-g: {} is beyond any centrifuge (at most 1000 g)",
            crate::output::num(*l)
        )));
    }
    if !(a.tilt_arcsec.is_finite() && a.latitude_deg.is_finite()) {
        return Err(usage("--tilt-arcsec and --latitude-deg must be finite"));
    }
    if let Some(l) = a.levels_g.iter().find(|l| !(l.is_finite() && **l >= 0.0)) {
        return Err(usage(format!(
            "--levels-g: {l} is not a non-negative level"
        )));
    }
    let cfg = CentrifugeSim {
        truth: truth.model()?,
        rig: Centrifuge {
            r_plus_m: a.r_plus_m,
            r_minus_m: a.r_minus_m,
            latitude_rad: a.latitude_deg.to_radians(),
            g_local_m_s2: a.g_local,
            opposite_sense: a.opposite_sense,
            tilt_rad: arcsec_to_rad(a.tilt_arcsec),
        },
        positions: parse_positions(&a.positions, a.single_polarity)?,
        rates_rad_s: rates_for_levels(&a.levels_g, a.radius_m, a.g_local),
        samples: a.samples,
        noise: a.noise,
        seed,
    };
    crate::options::sim_size(&[
        ("positions", cfg.positions.len() as f64),
        ("--levels-g", cfg.rates_rad_s.len() as f64),
        ("--samples", a.samples as f64),
    ])?;
    Ok(cfg)
}

/// `incal simulate centrifuge`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let cfg = sim_config(&a.truth, &a.rig, a.seed)?;
    let mut text = String::from("plane,phi_deg,polarity,omega_rad_s,output\n");
    for o in sim_centrifuge(&cfg) {
        crate::options::finite_output(o.output)?;
        let phi = (rad_to_deg(o.position.phi_rad) * 1e9).round() / 1e9;
        text.push_str(&format!(
            "{},{phi},{},{},{}\n",
            o.position.plane.name(),
            o.position.polarity,
            o.omega_rad_s,
            o.output
        ));
    }
    write_text(a.output.as_deref(), &text)
}

/// Options of `incal plan centrifuge`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    /// The instrument expected (its K0 and K1 matter most; the other terms barely change the prediction).
    #[command(flatten)]
    pub truth: TruthArgs,
    #[command(flatten)]
    pub rig: RigArgs,
    /// Standard uncertainty of K0 from the 1 g calibration (g).
    #[arg(long = "u-k0", visible_alias = "u-k0-g", default_value_t = 0.0)]
    pub u_k0: f64,
    /// Standard uncertainty of K1 from the 1 g calibration (output/g).
    #[arg(long, default_value_t = 0.0)]
    pub u_k1: f64,
    /// Model order of the radius regression and station fits, 2 or 3.
    #[arg(long, default_value_t = 3)]
    pub order: usize,
    /// Bound of the fixture angle error (deg), for the type-B delta-c2.
    #[arg(long, default_value_t = 0.0)]
    pub alignment_tolerance_deg: f64,
    /// Relative standard uncertainty of the table rate (ppm).
    #[arg(long, default_value_t = 0.0)]
    pub u_omega_ppm: f64,
    /// Print the plan as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal plan centrifuge`: the predicted u of every coefficient and radius
/// quantity for a station/speed plan (the reduction run on noise-free
/// outputs with an exact scatter of `--noise`, `incal::sim::centrifuge::plan`).
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    use crate::output::{json_text, sig, table};
    if a.rig.samples < 2 {
        return Err(usage(
            "--samples must be at least 2 (the plan needs a scatter)",
        ));
    }
    if !(a.rig.noise.is_finite() && a.rig.noise > 0.0) {
        return Err(usage(format!(
            "--noise must be a positive number, got {}",
            crate::output::num(a.rig.noise)
        )));
    }
    for (n, v) in [
        ("--u-k0", a.u_k0),
        ("--u-k1", a.u_k1),
        ("--alignment-tolerance-deg", a.alignment_tolerance_deg),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(usage(format!(
                "{n} must be a non-negative number, got {}",
                crate::output::num(v)
            )));
        }
    }
    if !(a.u_omega_ppm.is_finite() && (0.0..=1e5).contains(&a.u_omega_ppm)) {
        return Err(usage(format!(
            "--u-omega-ppm must be within 0..1e5, got {}",
            crate::output::num(a.u_omega_ppm)
        )));
    }
    let cfg = sim_config(&a.truth, &a.rig, 0)?;
    let t = &cfg.truth;
    let opts = CentrifugeOptions {
        k0_g: ValueU {
            value: t.k0_g,
            u: a.u_k0,
        },
        k1: ValueU {
            value: t.k1_out_per_g,
            u: a.u_k1,
        },
        cov_k0_k1: 0.0,
        radius0_m: a.rig.radius_m,
        latitude_rad: a.rig.latitude_deg.to_radians(),
        g_local_m_s2: a.rig.g_local,
        opposite_sense: a.rig.opposite_sense,
        order: a.order,
        alignment_tolerance_rad: a.alignment_tolerance_deg.to_radians(),
        noise: incal::estimation::Noise::Known { sigma: a.rig.noise },
        terms: None,
        u_omega_ppm: a.u_omega_ppm,
    };
    let r = incal::sim::centrifuge::plan(&cfg, &opts).map_err(crate::error::core)?;
    let unit = |n: &str| -> String {
        match n {
            "tilt_rad" => "rad".into(),
            n if n.ends_with("_m") => "m".into(),
            n => Term::parse(n).map_or("g/g^2".to_string(), |t| t.unit().as_str().to_string()),
        }
    };
    let mut rows: Vec<(String, f64, String)> = Vec::new();
    for e in [&r.coefficients, &r.joint] {
        for (k, n) in e.names().iter().enumerate() {
            if rows.iter().any(|(m, _, _)| m == n) {
                continue;
            }
            rows.push((n.clone(), e.u_at(k), unit(n)));
        }
    }
    if a.json {
        let mut u = serde_json::Map::new();
        let mut units = serde_json::Map::new();
        for (n, v, un) in &rows {
            u.insert(n.clone(), json!(v));
            units.insert(n.clone(), json!(un));
        }
        let doc = json!({
            "plan": "centrifuge",
            "positions": a.rig.positions,
            "single_polarity": a.rig.single_polarity,
            "levels_g": a.rig.levels_g,
            "radius_m": a.rig.radius_m,
            "samples": a.rig.samples,
            "noise": a.rig.noise,
            "k0": t.k0_g,
            "k1": t.k1_out_per_g,
            "u_k0": a.u_k0,
            "u_k1": a.u_k1,
            "order": a.order,
            "u_omega_ppm": a.u_omega_ppm,
            "latitude_deg": a.rig.latitude_deg,
            "predicted_u": u,
            "units": units,
            "warnings": r.warnings,
        });
        return write_text(a.output.as_deref(), &json_text(&doc));
    }
    let mut s = format!(
        "Centrifuge plan: {} positions x {} levels, {} samples per point, noise {:e} per sample, K1 = {}\n",
        cfg.positions.len(),
        a.rig.levels_g.len(),
        a.rig.samples,
        a.rig.noise,
        t.k1_out_per_g
    );
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|(n, v, un)| vec![n.clone(), sig(*v, 3), un.clone()])
        .collect();
    s.push_str(&table(&["term", "predicted u", "unit"], &body));
    for w in &r.warnings {
        s.push_str(&format!("warning [{}]: {}\n", w.code, w.message));
    }
    write_text(a.output.as_deref(), &s)
}
