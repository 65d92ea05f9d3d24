//! `incal tumble`, `incal plan tumble`, `incal simulate tumble`.

use std::io::Write;
use std::path::PathBuf;

use clap::ValueEnum;
use incal::estimation::Noise;
use incal::models::{AccelerometerModel, Term};
use incal::procedures::tumble::plan::{predict, TumblePlan};
use incal::procedures::tumble::{
    calibrate, default_terms, Observation, TumbleOptions, TumbleResult,
};
use incal::rigs::Mount;
use incal::sim::tumble::{simulate as sim_tumble, TumbleSim};
use incal::units::{arcsec_to_rad, rad_to_arcsec, rad_to_deg};
use serde_json::{json, Map, Value};

use crate::error::{core, in_file, usage, CliError, CliResult};
use crate::input::Table;
use crate::output::{coefficients_json, display_scale, num, print_json, sig, table, term_unit};

/// Mount on the dividing head.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MountArg {
    /// Output axis along the head axis: a_i = sin θ, a_p = cos θ.
    Pendulum,
    /// Pendulous axis along the head axis: a_i = sin θ, a_o = cos θ.
    Gate,
}

impl From<MountArg> for Mount {
    fn from(m: MountArg) -> Mount {
        match m {
            MountArg::Pendulum => Mount::Pendulum,
            MountArg::Gate => Mount::Gate,
        }
    }
}

/// Options of `incal tumble`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Mount on the dividing head.
    #[arg(long, value_enum)]
    pub mount: MountArg,
    /// Input CSV with columns angle_deg and output (optional: pass; others ignored).
    #[arg(long)]
    pub input: PathBuf,
    /// Terms to fit, comma separated (default: K0,K1,K2,K3 and the mount's misalignment and cross-coupling).
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Print one JSON object instead of the readable report.
    #[arg(long)]
    pub json: bool,
}

fn parse_terms(list: &Option<Vec<String>>, mount: Mount) -> CliResult<Vec<Term>> {
    match list {
        None => Ok(default_terms(mount)),
        Some(v) => v
            .iter()
            .map(|s| Term::parse(s).map_err(|e| usage(format!("--terms: {e}"))))
            .collect(),
    }
}

fn read_observations(path: &std::path::Path) -> CliResult<(String, Vec<Observation>)> {
    let t = Table::read(path)?;
    let ca = t.column("angle_deg")?;
    let co = t.column("output")?;
    let cp = t.opt_column("pass");
    let mut obs = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        let angle = t.f64(row, ca)?;
        let output = t.f64(row, co)?;
        let pass = cp
            .map(|c| t.text(row, c).to_string())
            .filter(|s| !s.is_empty());
        obs.push(Observation {
            angle_rad: angle.to_radians(),
            output,
            pass,
        });
    }
    Ok((t.path.clone(), obs))
}

/// `incal tumble`.
pub fn run(a: &Args) -> CliResult<()> {
    let mount: Mount = a.mount.into();
    let terms = parse_terms(&a.terms, mount)?;
    let noise = match a.noise {
        None => Noise::Auto,
        Some(s) if s.is_finite() && s > 0.0 => Noise::Known { sigma: s },
        Some(s) => return Err(usage(format!("--noise must be a positive number, got {s}"))),
    };
    let (file, obs) = read_observations(&a.input)?;
    let result = calibrate(
        &obs,
        &TumbleOptions {
            mount,
            terms,
            noise,
        },
    )
    .map_err(|e| in_file(&file, e))?;
    if a.json {
        print_json(&result_json(&file, &result));
    } else {
        print!("{}", report(&file, &result));
    }
    Ok(())
}

/// The JSON document of a tumble result.
pub fn result_json(file: &str, r: &TumbleResult) -> Value {
    let f = &r.fit;
    let positions: Vec<Value> = r
        .positions
        .iter()
        .map(|p| {
            json!({
                "angle_deg": rad_to_deg(p.angle_rad),
                "pass": p.pass,
                "n": p.stats.n,
                "mean_output": p.stats.mean,
                "std_output": num(p.stats.std),
                "residual": p.residual,
                "standardized_residual": num(p.standardized_residual),
            })
        })
        .collect();
    let passes: Vec<Value> = r
        .passes
        .iter()
        .map(|p| {
            json!({
                "reference": p.reference,
                "other": p.other,
                "reference_coefficients": coefficients_json(&p.reference_coefficients, term_unit),
                "other_coefficients": coefficients_json(&p.other_coefficients, term_unit),
                "difference": coefficients_json(&p.difference, term_unit),
                "position_differences": p.position_differences.iter().map(|(t, d, u)| json!({
                    "angle_deg": rad_to_deg(*t), "difference_output": d, "u_output": num(*u),
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    json!({
        "procedure": "tumble",
        "input": file,
        "mount": r.mount.name(),
        "terms": r.terms.iter().map(|t| t.name()).collect::<Vec<_>>(),
        "coefficients": coefficients_json(&r.coefficients, term_unit),
        "coverage": {
            "dof": num(r.coefficients.dof()),
            "k95": r.coefficients.coverage_factor(0.95),
            "note": "u is the standard uncertainty; U95 = k95 * u"
        },
        "fit": {
            "positions": f.diagnostics.n_obs,
            "parameters": f.diagnostics.n_params,
            "dof": f.dof,
            "residual_rms_output": num(residual_rms(r)),
            "unit_weight_sigma": num(f.sigma),
            "chi2": f.weighted_rss,
            "chi2_p_value": f.chi2_p_value.map(num),
            "variance_source": f.variance_source,
            "rank": f.diagnostics.rank,
            "condition_number": num(f.diagnostics.condition),
            "weakest_combination": f.diagnostics.weakest.to_string(),
        },
        "index_error_arcsec": r.index_error_rad.map(|e| num(rad_to_arcsec(e))),
        "positions": positions,
        "absorbed": r.absorbed.iter().map(|a| a.to_string()).collect::<Vec<_>>(),
        "passes": passes,
        "pass_errors": r.pass_errors.iter().map(|(l, e)| json!({"pass": l, "error": e})).collect::<Vec<_>>(),
        "warnings": r.warnings,
    })
}

fn coefficient_rows(e: &incal::estimation::Estimates, k95: f64) -> Vec<Vec<String>> {
    e.names()
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let term = Term::parse(name).unwrap_or(Term::K0);
            let (scale, unit) = display_scale(term);
            let (v, u) = (e.values()[k] * scale, e.u_at(k) * scale);
            vec![
                name.clone(),
                sig(v, 7),
                sig(u, 3),
                sig(k95 * u, 3),
                unit.to_string(),
            ]
        })
        .collect()
}

/// Root-mean-square residual of the position means, `sqrt(Σ r²/(n−p))`
/// (output units; NaN without residual degrees of freedom).
fn residual_rms(r: &TumbleResult) -> f64 {
    let f = &r.fit;
    if f.dof == 0 {
        return f64::NAN;
    }
    (f.residuals.norm_squared() / f.dof as f64).sqrt()
}

/// The readable report of a tumble result.
pub fn report(file: &str, r: &TumbleResult) -> String {
    let mut s = String::new();
    let f = &r.fit;
    let k95 = r.coefficients.coverage_factor(0.95);
    s.push_str(&format!(
        "Tumble calibration, {} mount, {} ({} positions, {} terms)\n\n",
        r.mount.name(),
        file,
        f.diagnostics.n_obs,
        f.diagnostics.n_params
    ));
    s.push_str(&table(
        &["term", "value", "u", "U95", "unit"],
        &coefficient_rows(&r.coefficients, k95),
    ));
    s.push_str(&format!(
        "\nu: standard uncertainty; U95 = {k95:.3} u ({} degrees of freedom, variance from {})\n",
        sig(r.coefficients.dof(), 4),
        match f.variance_source {
            incal::estimation::VarianceSource::Prior => "the sample scatter",
            incal::estimation::VarianceSource::Residuals => "the residuals",
        }
    ));
    s.push_str(&format!(
        "fit: dof {}, residual rms {} (output units), condition number {}",
        f.dof,
        sig(residual_rms(r), 3),
        sig(f.diagnostics.condition, 3)
    ));
    if let Some(p) = f.chi2_p_value {
        s.push_str(&format!(", chi-square p {}", sig(p, 2)));
    }
    s.push('\n');
    if let Some(e) = r.index_error_rad {
        s.push_str(&format!(
            "index-angle error of the head estimated from the residuals: {} arcsec rms\n",
            sig(rad_to_arcsec(e), 3)
        ));
    }
    for a in &r.absorbed {
        s.push_str(&format!("note: {a}\n"));
    }
    for w in &r.warnings {
        s.push_str(&format!("warning: {w}\n"));
    }
    s.push_str("\nPositions\n");
    let rows: Vec<Vec<String>> = r
        .positions
        .iter()
        .map(|p| {
            vec![
                format!("{:.4}", rad_to_deg(p.angle_rad)),
                p.pass.clone().unwrap_or_default(),
                p.stats.n.to_string(),
                sig(p.stats.mean, 10),
                sig(p.stats.std, 3),
                sig(p.residual, 3),
                sig(p.standardized_residual, 3),
            ]
        })
        .collect();
    s.push_str(&table(
        &[
            "angle_deg",
            "pass",
            "n",
            "mean",
            "std",
            "residual",
            "std.res",
        ],
        &rows,
    ));
    for p in &r.passes {
        s.push_str(&format!(
            "\nPass difference: {} minus {} (u from both passes)\n",
            p.other, p.reference
        ));
        let k = p.difference.coverage_factor(0.95);
        s.push_str(&table(
            &["term", "difference", "u", "U95", "unit"],
            &coefficient_rows(&p.difference, k),
        ));
        let rows: Vec<Vec<String>> = p
            .position_differences
            .iter()
            .map(|(t, d, u)| vec![format!("{:.4}", rad_to_deg(*t)), sig(*d, 3), sig(*u, 3)])
            .collect();
        s.push_str(&format!(
            "\nPer-angle mean output, {} minus {} (hysteresis, drift)\n",
            p.other, p.reference
        ));
        s.push_str(&table(&["angle_deg", "difference", "u"], &rows));
    }
    for (l, e) in &r.pass_errors {
        s.push_str(&format!("pass {l} alone: {e}\n"));
    }
    s
}

/// Plan selection shared by `plan tumble` and `simulate tumble`.
#[derive(clap::Args, Debug, Clone)]
pub struct PlanChoice {
    /// Instrument range (g): the small-angle plan with the largest step whose inputs stay within it (GJB plan at 1 g and above).
    #[arg(long, group = "plan_kind")]
    pub range_g: Option<f64>,
    /// Small-angle 12-point plan with this step (deg, at most 18).
    #[arg(long, group = "plan_kind")]
    pub step_deg: Option<f64>,
    /// N equally spaced angles (GJB 12-point: --points 12).
    #[arg(long, group = "plan_kind")]
    pub points: Option<usize>,
    /// Explicit angles (deg), comma separated.
    #[arg(long, group = "plan_kind", value_delimiter = ',')]
    pub angles_deg: Option<Vec<f64>>,
    /// Dividing-head step resolution used with --range-g (deg).
    #[arg(long, default_value_t = 1.0)]
    pub step_resolution_deg: f64,
}

impl PlanChoice {
    /// The chosen plan (GJB 12-point when nothing is chosen).
    pub fn plan(&self) -> CliResult<TumblePlan> {
        let p = if let Some(r) = self.range_g {
            TumblePlan::for_range(r, self.step_resolution_deg)
        } else if let Some(a) = self.step_deg {
            TumblePlan::small_angle(a)
        } else if let Some(n) = self.points {
            TumblePlan::n_point(n)
        } else if let Some(angles) = &self.angles_deg {
            if let Some(x) = angles.iter().find(|x| !x.is_finite()) {
                return Err(usage(format!("--angles-deg: {x} is not a finite angle")));
            }
            Ok(TumblePlan {
                kind: incal::procedures::tumble::plan::PlanKind::NPoint { n: angles.len() },
                step_deg: f64::NAN,
                angles_deg: angles.clone(),
            })
        } else {
            Ok(TumblePlan::gjb12())
        };
        p.map_err(core)
    }
}

fn plan_name(p: &TumblePlan) -> &'static str {
    use incal::procedures::tumble::plan::PlanKind;
    match p.kind {
        PlanKind::Gjb12 => "gjb12",
        PlanKind::SmallAngle { .. } => "small-angle",
        PlanKind::NPoint { .. } => "n-point",
    }
}

/// Options of `incal plan tumble`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub plan: PlanChoice,
    /// Mount for the prediction.
    #[arg(long, value_enum, default_value = "pendulum")]
    pub mount: MountArg,
    /// Terms to predict, comma separated (default: the mount's default terms).
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Nominal scale factor K1 (output/g), needed for the prediction.
    #[arg(long)]
    pub k1: Option<f64>,
    /// Standard deviation of one position's averaged output (output units), needed for the prediction.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Standard deviation of the head's index-angle error (arcsec), added as output noise K1·cosθ·ε.
    #[arg(long, default_value_t = 0.0)]
    pub index_error_arcsec: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// `incal plan tumble`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let plan = a.plan.plan()?;
    let mount: Mount = a.mount.into();
    let terms = parse_terms(&a.terms, mount)?;
    let prediction = match (a.k1, a.noise) {
        (Some(k1), Some(noise)) => Some(
            predict(
                mount,
                &terms,
                &plan.angles_rad(),
                k1,
                noise,
                arcsec_to_rad(a.index_error_arcsec),
            )
            .map_err(core)?,
        ),
        (None, None) => None,
        _ => {
            return Err(usage(
                "--k1 and --noise go together (both are needed for a prediction)",
            ))
        }
    };
    if a.json {
        let mut doc = json!({
            "plan": plan_name(&plan),
            "step_deg": num(plan.step_deg),
            "angles_deg": plan.angles_deg,
            "max_input_g": plan.max_input_g(),
            "mount": mount.name(),
        });
        if let Some(p) = &prediction {
            let mut u = Map::new();
            let mut units = Map::new();
            for (k, n) in p.names().iter().enumerate() {
                u.insert(n.clone(), json!(p.u_at(k)));
                units.insert(n.clone(), json!(term_unit(n)));
            }
            doc["predicted_u"] = Value::Object(u);
            doc["units"] = Value::Object(units);
            doc["k1"] = json!(a.k1);
            doc["noise"] = json!(a.noise);
            doc["index_error_arcsec"] = json!(a.index_error_arcsec);
        }
        print_json(&doc);
        return Ok(());
    }
    println!(
        "Tumble plan: {} (step {} deg), {} positions, largest input {:.3} g",
        plan_name(&plan),
        if plan.step_deg.is_finite() {
            plan.step_deg.to_string()
        } else {
            "-".to_string()
        },
        plan.angles_deg.len(),
        plan.max_input_g()
    );
    println!(
        "angles (deg): {}",
        plan.angles_deg
            .iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(p) = prediction {
        println!(
            "\nPredicted standard uncertainty ({} mount, K1 = {}, noise {:e} per position, index error {} arcsec):",
            mount.name(),
            a.k1.unwrap_or(f64::NAN),
            a.noise.unwrap_or(f64::NAN),
            a.index_error_arcsec
        );
        let rows: Vec<Vec<String>> = p
            .names()
            .iter()
            .enumerate()
            .map(|(k, n)| {
                let term = Term::parse(n).unwrap_or(Term::K0);
                let (scale, unit) = display_scale(term);
                vec![n.clone(), sig(p.u_at(k) * scale, 3), unit.to_string()]
            })
            .collect();
        print!("{}", table(&["term", "predicted u", "unit"], &rows));
    } else {
        println!("(give --k1 and --noise for the predicted uncertainty of every coefficient)");
    }
    Ok(())
}

/// Truth coefficients for simulators (default: the seed 000 instrument).
#[derive(clap::Args, Debug, Clone)]
pub struct TruthArgs {
    /// Bias K0 (g).
    #[arg(long, default_value_t = 8e-3)]
    pub k0_g: f64,
    /// Scale factor K1 (output/g).
    #[arg(long, default_value_t = 10.0)]
    pub k1: f64,
    /// K2 (g/g^2).
    #[arg(long, default_value_t = 1e-6)]
    pub k2: f64,
    /// K3 (g/g^3).
    #[arg(long, default_value_t = 5e-5)]
    pub k3: f64,
    /// Misalignment delta_o (arcsec).
    #[arg(long, default_value_t = 618.794)]
    pub delta_o_arcsec: f64,
    /// Misalignment delta_p (arcsec).
    #[arg(long, default_value_t = -300.0)]
    pub delta_p_arcsec: f64,
    /// Cross-coupling K_ip (g/g^2).
    #[arg(long, default_value_t = 3e-7)]
    pub k_ip: f64,
    /// Cross-coupling K_io (g/g^2).
    #[arg(long, default_value_t = 5e-7)]
    pub k_io: f64,
    /// Cross-coupling K_po (g/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub k_po: f64,
    /// Cross-axis nonlinearity K_pp (g/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub k_pp: f64,
    /// Cross-axis nonlinearity K_oo (g/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub k_oo: f64,
    /// Odd quadratic K_oq (g/g^2).
    #[arg(long, default_value_t = 0.0)]
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

/// Options of `incal simulate tumble`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// Mount on the dividing head.
    #[arg(long, value_enum, default_value = "pendulum")]
    pub mount: MountArg,
    #[command(flatten)]
    pub plan: PlanChoice,
    #[command(flatten)]
    pub truth: TruthArgs,
    /// Samples per position.
    #[arg(long, default_value_t = 10)]
    pub samples: usize,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 1e-6)]
    pub noise: f64,
    /// Dividing-head index-angle error, standard deviation (arcsec), one draw per visit.
    #[arg(long, default_value_t = 0.0)]
    pub index_error_arcsec: f64,
    /// Passes: 1, or 2 (clockwise then counter-clockwise, labelled in a pass column).
    #[arg(long, default_value_t = 1)]
    pub passes: usize,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
}

/// `incal simulate tumble`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    if a.samples == 0 {
        return Err(usage("--samples must be at least 1"));
    }
    if !(1..=2).contains(&a.passes) {
        return Err(usage("--passes must be 1 or 2"));
    }
    if !(a.noise.is_finite() && a.noise >= 0.0) {
        return Err(usage("--noise must be a non-negative number"));
    }
    if !(a.index_error_arcsec.is_finite() && a.index_error_arcsec >= 0.0) {
        return Err(usage("--index-error-arcsec must be a non-negative number"));
    }
    let cfg = TumbleSim {
        truth: a.truth.model()?,
        mount: a.mount.into(),
        angles_deg: a.plan.plan()?.angles_deg,
        samples: a.samples,
        noise: a.noise,
        index_error_rad: arcsec_to_rad(a.index_error_arcsec),
        passes: a.passes,
        seed: a.seed,
    };
    let obs = sim_tumble(&cfg);
    let mut text = String::from(if a.passes > 1 {
        "angle_deg,output,pass\n"
    } else {
        "angle_deg,output\n"
    });
    for o in &obs {
        let angle = rad_to_deg(o.angle_rad);
        // Round-trip exact: the angle is printed to 1e-9 deg, the output in full.
        let angle = (angle * 1e9).round() / 1e9;
        match &o.pass {
            Some(p) => text.push_str(&format!("{angle},{},{p}\n", o.output)),
            None => text.push_str(&format!("{angle},{}\n", o.output)),
        }
    }
    write_output(a.output.as_ref(), &text)
}

/// Write `text` to `path`, or to stdout.
pub fn write_output(path: Option<&PathBuf>, text: &str) -> CliResult<()> {
    match path {
        Some(p) => std::fs::write(p, text)
            .map_err(|e| CliError::Failure(anyhow::anyhow!("{}: cannot write: {e}", p.display()))),
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(text.as_bytes())
                .map_err(|e| CliError::Failure(anyhow::anyhow!("stdout: {e}")))
        }
    }
}
