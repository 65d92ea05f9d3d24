//! `incal centrifuge`, `incal simulate centrifuge` and the centrifuge
//! section of `incal demo` (seed 001, methods.md §2).

use std::path::PathBuf;

use incal::estimation::Noise;
use incal::models::{AccelerometerModel, Term};
use incal::procedures::centrifuge::radius::ValueU;
use incal::procedures::centrifuge::{calibrate, CentrifugeOptions, CentrifugeResult, Observation};
use incal::rigs::centrifuge::{Centrifuge, Plane, Position};
use incal::sim::centrifuge::{rates_for_levels, simulate as sim_centrifuge, CentrifugeSim};
use incal::units::{arcsec_to_rad, rad_to_arcsec, rad_to_deg, STANDARD_GRAVITY_M_S2};
use serde_json::{json, Map, Value};

use crate::commands::demo::{truth_rows, TRUTH_HEADER};
use crate::commands::tumble::write_output;
use crate::error::{core, in_file, usage, CliResult};
use crate::input::Table;
use crate::output::{coefficients_json, display_scale, num, print_json, sig, table, term_unit};

/// Options of `incal centrifuge`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input CSV with columns plane, phi_deg, polarity, omega_rad_s, output (one row per sample).
    #[arg(long)]
    pub input: PathBuf,
    /// Bias K0 from the 1 g calibration (g).
    #[arg(long)]
    pub k0: f64,
    /// Scale factor K1 from the 1 g calibration (output/g).
    #[arg(long)]
    pub k1: f64,
    /// Standard uncertainty of K0 (g).
    #[arg(long, default_value_t = 0.0)]
    pub u_k0: f64,
    /// Standard uncertainty of K1 (output/g).
    #[arg(long, default_value_t = 0.0)]
    pub u_k1: f64,
    /// Nominal test radius R0 (m): start of the regression iteration.
    #[arg(long)]
    pub radius_m: f64,
    /// Latitude of the centrifuge (deg, north positive).
    #[arg(long, allow_hyphen_values = true)]
    pub latitude_deg: f64,
    /// Local gravity g_L (m/s^2): the g unit of every coefficient.
    #[arg(long, default_value_t = STANDARD_GRAVITY_M_S2)]
    pub g_local: f64,
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
    /// Print one JSON object instead of the readable report.
    #[arg(long)]
    pub json: bool,
}

fn read_observations(path: &std::path::Path) -> CliResult<(String, Vec<Observation>)> {
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
    Ok((t.path.clone(), obs))
}

/// `incal centrifuge`.
pub fn run(a: &Args) -> CliResult<()> {
    let noise = match a.noise {
        None => Noise::Auto,
        Some(s) if s.is_finite() && s > 0.0 => Noise::Known { sigma: s },
        Some(s) => return Err(usage(format!("--noise must be a positive number, got {s}"))),
    };
    let terms = match &a.terms {
        None => None,
        Some(v) => Some(
            v.iter()
                .map(|s| Term::parse(s).map_err(|e| usage(format!("--terms: {e}"))))
                .collect::<CliResult<Vec<Term>>>()?,
        ),
    };
    let opts = CentrifugeOptions {
        k0_g: ValueU {
            value: a.k0,
            u: a.u_k0,
        },
        k1: ValueU {
            value: a.k1,
            u: a.u_k1,
        },
        radius0_m: a.radius_m,
        latitude_rad: a.latitude_deg.to_radians(),
        g_local_m_s2: a.g_local,
        opposite_sense: a.opposite_sense,
        order: a.order,
        alignment_tolerance_rad: a.alignment_tolerance_deg.to_radians(),
        noise,
        terms,
    };
    let (file, obs) = read_observations(&a.input)?;
    let r = calibrate(&obs, &opts).map_err(|e| in_file(&file, e))?;
    if a.json {
        print_json(&result_json(&file, &r));
    } else {
        print!("{}", report(&file, &r));
    }
    Ok(())
}

fn vu(v: Option<ValueU>) -> Value {
    match v {
        Some(x) => json!({"value": num(x.value), "u": num(x.u)}),
        None => Value::Null,
    }
}

/// The JSON document of a centrifuge result.
pub fn result_json(file: &str, r: &CentrifugeResult) -> Value {
    let reg = |k: usize| r.regression[k].as_ref().map(|f| f.radius_m);
    let by_range: Vec<Value> = r
        .radius_table
        .iter()
        .map(|row| {
            json!({
                "order": row.order,
                "polarity": row.polarity,
                "max_input_g": row.max_input_g,
                "radius_m": match &row.radius { Ok(v) => vu(Some(*v)), Err(_) => Value::Null },
                "error": row.radius.as_ref().err(),
                "chi2_p_value": row.chi2_p_value.map(num),
            })
        })
        .collect();
    let positions: Vec<Value> = r
        .stations
        .iter()
        .flat_map(|s| {
            s.alignment.iter().map(move |a| {
                json!({
                    "station": s.label(),
                    "polarity": a.polarity,
                    "radius_m": a.radius_m,
                    "delta_phi_rad": a.delta_phi_rad,
                    "delta_c2": a.delta_c2,
                })
            })
        })
        .collect();
    let stations: Vec<Value> = r
        .stations
        .iter()
        .map(|s| {
            json!({
                "station": s.label(),
                "polarities": s.polarities,
                "points": s.points,
                "c2": vu(Some(s.c2)),
                "q": vu(s.q),
                "c3": vu(s.c3),
                "delta_c2_half_width": s.delta_c2_half_width,
                "dof": s.fit.dof,
                "chi2_p_value": s.fit.chi2_p_value.map(num),
                "variance_source": s.fit.variance_source,
            })
        })
        .collect();
    let mut budgets = Map::new();
    for b in &r.budgets {
        let lines: Vec<Value> = b
            .lines
            .iter()
            .map(|l| {
                json!({
                    "component": l.component,
                    "type": l.kind,
                    "u": l.u,
                    "sensitivity": l.sensitivity,
                    "contribution": l.contribution,
                })
            })
            .collect();
        budgets.insert(
            b.coefficient.clone(),
            json!({
                "lines": lines,
                "combined_u": b.combined_u,
                "combined_u_paper_eq10": b.combined_u_paper_eq10,
                "effective_dof": num(b.effective_dof),
                "unit": term_unit(&b.coefficient),
            }),
        );
    }
    let unsupported: Map<String, Value> = r
        .unsupported
        .iter()
        .map(|(t, w)| (t.name().to_string(), json!(w)))
        .collect();
    json!({
        "procedure": "centrifuge",
        "input": file,
        "radius": {
            "static": {"R_plus_m": vu(r.static_radius[0]), "R_minus_m": vu(r.static_radius[1])},
            "regression": {"R_plus_m": vu(reg(0)), "R_minus_m": vu(reg(1))},
        },
        "radius_static_eq6_uncorrected": {"R_plus_m": vu(r.static_radius_uncorrected[0]), "R_minus_m": vu(r.static_radius_uncorrected[1])},
        "coefficients": coefficients_json(&r.coefficients, term_unit),
        "alignment": {"ecm_offset_m": vu(Some(ValueU { value: r.ecm_offset_m.value.abs(), u: r.ecm_offset_m.u }))},
        "tilt_rad": vu(r.tilt_rad),
        "centre_radius_m": vu(Some(r.centre_radius_m)),
        "regression_order": r.regression.iter().flatten().map(|f| f.order).next(),
        "radius_by_range": by_range,
        "alignment_positions": positions,
        "stations": stations,
        "station_errors": r.station_errors.iter().map(|(s, e)| json!({"station": s, "error": e})).collect::<Vec<_>>(),
        "budgets": Value::Object(budgets),
        "budget_convention": "GUM: u^2 = sum (sensitivity*u)^2; combined_u_paper_eq10 weights u(c2), u(dc2) of the cross position by 2 instead of 4 (seed 001 eq. 10)",
        "coverage": {
            "dof": num(r.coefficients.dof()),
            "k95": r.coefficients.coverage_factor(0.95),
            "note": "u is the standard uncertainty; U95 = k95 * u"
        },
        "unsupported": Value::Object(unsupported),
        "warnings": r.warnings,
    })
}

fn coef_rows(r: &CentrifugeResult) -> Vec<Vec<String>> {
    let e = &r.coefficients;
    e.names()
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let (scale, unit) = Term::parse(name).map_or((1.0, ""), display_scale);
            vec![
                name.clone(),
                sig(e.values()[k] * scale, 6),
                sig(e.u_at(k) * scale, 3),
                unit.to_string(),
            ]
        })
        .collect()
}

fn mm(v: Option<ValueU>) -> (String, String) {
    v.map_or(("-".into(), "-".into()), |x| {
        (format!("{:.6}", x.value), sig(x.u * 1e6, 3))
    })
}

/// Rows `component, type, u, sensitivity, contribution (µg/g²)` of a
/// coefficient's uncertainty budget.
fn budget_rows(b: &incal::procedures::centrifuge::budget::Budget) -> Vec<Vec<String>> {
    b.lines
        .iter()
        .map(|l| {
            vec![
                l.component.clone(),
                l.kind.to_string(),
                sig(l.u, 3),
                sig(l.sensitivity, 4),
                sig(l.contribution * 1e6, 3),
            ]
        })
        .collect()
}

/// The readable report of a centrifuge result.
pub fn report(file: &str, r: &CentrifugeResult) -> String {
    let mut s = format!("Centrifuge calibration, {file}\n\n");
    if let Some(t) = r.tilt_rad {
        s.push_str(&format!(
            "Static tilt (eq. 4): {} arcsec, u {} arcsec\n",
            sig(rad_to_arcsec(t.value), 4),
            sig(rad_to_arcsec(t.u), 3)
        ));
    }
    let reg = |k: usize| r.regression[k].as_ref().map(|f| f.radius_m);
    let rows = vec![
        {
            let (v, u) = mm(r.static_radius[0]);
            let (v2, u2) = mm(r.static_radius[1]);
            vec![
                "static (eq. 5-6, K2/K3 at 1 g removed)".into(),
                v,
                u,
                v2,
                u2,
            ]
        },
        {
            let (v, u) = mm(r.static_radius_uncorrected[0]);
            let (v2, u2) = mm(r.static_radius_uncorrected[1]);
            vec!["static (eq. 5-6 as printed)".into(), v, u, v2, u2]
        },
        {
            let (v, u) = mm(reg(0));
            let (v2, u2) = mm(reg(1));
            vec!["regression (eq. 7)".into(), v, u, v2, u2]
        },
    ];
    s.push_str(&table(
        &["radius", "R+ (m)", "u (um)", "R- (m)", "u (um)"],
        &rows,
    ));
    s.push_str("\nRegression radius by range and model order (seed 001 Table 2)\n");
    let rows: Vec<Vec<String>> = r
        .radius_table
        .iter()
        .map(|row| {
            vec![
                row.order.to_string(),
                format!("{:+}", row.polarity),
                sig(row.max_input_g, 3),
                row.radius
                    .as_ref()
                    .map_or_else(|e| e.clone(), |v| format!("{:.6}", v.value)),
                row.chi2_p_value.map_or("-".into(), |p| sig(p, 2)),
            ]
        })
        .collect();
    s.push_str(&table(
        &["order", "pol", "max g", "R (m)", "lack-of-fit p"],
        &rows,
    ));
    s.push_str(&format!(
        "\nECM offset r = {} mm (u {} um), fixture centre R = {:.6} m\n",
        sig(r.ecm_offset_m.value.abs() * 1e3, 4),
        sig(r.ecm_offset_m.u * 1e6, 3),
        r.centre_radius_m.value
    ));
    let rows: Vec<Vec<String>> = r
        .stations
        .iter()
        .flat_map(|st| {
            st.alignment.iter().map(move |a| {
                vec![
                    st.label(),
                    format!("{:+}", a.polarity),
                    format!("{:.6}", a.radius_m),
                    sig(a.delta_phi_rad, 3),
                    sig(a.delta_c2 * 1e6, 3),
                ]
            })
        })
        .collect();
    s.push_str(&table(
        &["station", "pol", "R_ecm (m)", "dphi (rad)", "dc2 (ug/g^2)"],
        &rows,
    ));
    s.push_str("\nCoefficients (g units)\n");
    s.push_str(&table(&["term", "value", "u", "unit"], &coef_rows(r)));
    for b in &r.budgets {
        let is_cross = matches!(b.coefficient.as_str(), "K_ip" | "K_io" | "K_po");
        if !is_cross {
            continue;
        }
        s.push_str(&format!(
            "\nBudget of {} (GUM; ug/g^2){}\n",
            b.coefficient,
            b.combined_u_paper_eq10.map_or(String::new(), |p| format!(
                "; paper eq. 10 would give u = {}",
                sig(p * 1e6, 3)
            ))
        ));
        let rows: Vec<Vec<String>> = budget_rows(b)
            .into_iter()
            .chain(std::iter::once(vec![
                "combined".into(),
                String::new(),
                String::new(),
                String::new(),
                sig(b.combined_u * 1e6, 3),
            ]))
            .collect();
        s.push_str(&table(
            &["component", "type", "u", "sensitivity", "contribution"],
            &rows,
        ));
    }
    for (t, w) in &r.unsupported {
        s.push_str(&format!("not determined: {t}: {w}\n"));
    }
    for (st, e) in &r.station_errors {
        s.push_str(&format!("station {st}: {e}\n"));
    }
    for w in &r.warnings {
        s.push_str(&format!("warning: {w}\n"));
    }
    s
}

/// Truth instrument for the centrifuge simulator (g units).
#[derive(clap::Args, Debug, Clone)]
pub struct TruthArgs {
    /// Bias K0 (g).
    #[arg(long, default_value_t = 1.2e-4, allow_hyphen_values = true)]
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
    #[arg(long, default_value_t = 39.9, allow_hyphen_values = true)]
    pub latitude_deg: f64,
    /// Local gravity (m/s^2).
    #[arg(long, default_value_t = STANDARD_GRAVITY_M_S2)]
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
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
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

/// `incal simulate centrifuge`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    if a.samples == 0 {
        return Err(usage("--samples must be at least 1"));
    }
    if !(a.noise.is_finite() && a.noise >= 0.0) {
        return Err(usage("--noise must be a non-negative number"));
    }
    for (name, v) in [
        ("--r-plus-m", a.r_plus_m),
        ("--r-minus-m", a.r_minus_m),
        ("--radius-m", a.radius_m),
        ("--g-local", a.g_local),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(usage(format!("{name} must be a positive number")));
        }
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
        truth: a.truth.model()?,
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
        seed: a.seed,
    };
    let mut text = String::from("plane,phi_deg,polarity,omega_rad_s,output\n");
    for o in sim_centrifuge(&cfg) {
        let phi = (rad_to_deg(o.position.phi_rad) * 1e9).round() / 1e9;
        text.push_str(&format!(
            "{},{phi},{},{},{}\n",
            o.position.plane.name(),
            o.position.polarity,
            o.omega_rad_s,
            o.output
        ));
    }
    write_output(a.output.as_ref(), &text)
}

/// The centrifuge section of `incal demo`.
pub fn demo_section(seed: u64) -> CliResult<()> {
    let sim_args = SimArgs {
        truth: TruthArgs {
            k0_g: 1.2e-4,
            k1: 1.3,
            k2: 3.9e-6,
            k3: 5e-9,
            delta_o_arcsec: 40.0,
            delta_p_arcsec: -20.0,
            k_ip: 7e-6,
            k_io: 2e-6,
            k_po: -1e-6,
            k_pp: 4.6e-7,
            k_oo: -3e-7,
            k_oq: 5e-7,
        },
        r_plus_m: 0.714775,
        r_minus_m: 0.705794,
        radius_m: 0.71,
        tilt_arcsec: 60.0,
        latitude_deg: 39.9,
        g_local: STANDARD_GRAVITY_M_S2,
        opposite_sense: false,
        positions: Vec::new(),
        single_polarity: false,
        levels_g: vec![0.0, 1.0, 2.0, 4.0, 7.0, 10.0, 14.0, 18.0, 22.0, 25.0],
        samples: 5,
        noise: 2e-6,
        seed,
        output: None,
    };
    let truth = sim_args.truth.model()?;
    let rig = Centrifuge {
        r_plus_m: sim_args.r_plus_m,
        r_minus_m: sim_args.r_minus_m,
        latitude_rad: sim_args.latitude_deg.to_radians(),
        g_local_m_s2: sim_args.g_local,
        opposite_sense: false,
        tilt_rad: arcsec_to_rad(sim_args.tilt_arcsec),
    };
    let obs = sim_centrifuge(&CentrifugeSim {
        truth,
        rig,
        positions: incal::sim::centrifuge::standard_positions(),
        rates_rad_s: rates_for_levels(&sim_args.levels_g, sim_args.radius_m, sim_args.g_local),
        samples: sim_args.samples,
        noise: sim_args.noise,
        seed,
    });
    let r = calibrate(
        &obs,
        &CentrifugeOptions {
            k0_g: ValueU {
                value: truth.k0_g,
                u: 2e-6,
            },
            k1: ValueU {
                value: truth.k1_out_per_g,
                u: 1.3e-6,
            },
            radius0_m: sim_args.radius_m,
            latitude_rad: rig.latitude_rad,
            g_local_m_s2: rig.g_local_m_s2,
            opposite_sense: false,
            order: 3,
            alignment_tolerance_rad: 0.0,
            noise: Noise::Auto,
            terms: None,
        },
    )
    .map_err(core)?;
    println!(
        "== Precision centrifuge: radius, nonlinearity, cross-coupling (seed 001, IEEE Std 836) =="
    );
    println!("Virtual accelerometer (K1 = 1.3 output/g), R+ = 0.714775 m, R- = 0.705794 m (ECM offset 4.49 mm),");
    println!("IA tilt 60 arcsec, latitude 39.9 deg, 0..25 g at ip,0 ip,90 io,90 ip,45 io,45 po,45, both polarities,");
    println!("5 samples per point, output noise 2e-6.\n");
    let eff = 1.0 + truth.k_io;
    let mut rows = Vec::new();
    for (k, (name, t)) in [("R+ (m)", rig.r_plus_m), ("R- (m)", rig.r_minus_m)]
        .into_iter()
        .enumerate()
    {
        if let Some(f) = &r.regression[k] {
            rows.push(vec![
                name.to_string(),
                format!("{:.7}", f.radius_m.value),
                format!("{:.7}", t * eff),
                sig(f.radius_m.u, 3),
                sig((f.radius_m.value - t * eff) / f.radius_m.u, 2),
                "m".into(),
            ]);
        }
    }
    rows.push(vec![
        "r ECM (m)".into(),
        format!("{:.7}", r.ecm_offset_m.value),
        format!("{:.7}", rig.ecm_offset_m() * eff),
        sig(r.ecm_offset_m.u, 3),
        sig(
            (r.ecm_offset_m.value - rig.ecm_offset_m() * eff) / r.ecm_offset_m.u,
            2,
        ),
        "m".into(),
    ]);
    println!("-- regression-iteration radius (truth = effective radius R(1 + K_io))");
    print!("{}", table(&TRUTH_HEADER, &rows));
    println!("\n-- coefficients");
    print!(
        "{}",
        table(
            &TRUTH_HEADER,
            &truth_rows(&r.coefficients, |n| Term::parse(n)
                .map_or(f64::NAN, |t| truth.get(t)))
        )
    );
    if let Some(b) = r.budgets.iter().find(|b| b.coefficient == "K_ip") {
        println!(
            "\n-- uncertainty budget of K_ip (GUM; the paper's eq. 10 weights c2 by 2, not 4)"
        );
        let rows = budget_rows(b);
        print!(
            "{}",
            table(
                &[
                    "component",
                    "type",
                    "u",
                    "sensitivity",
                    "contribution (ug/g^2)"
                ],
                &rows
            )
        );
        println!(
            "combined u = {} ug/g^2 (paper eq. 10: {})",
            sig(b.combined_u * 1e6, 3),
            b.combined_u_paper_eq10
                .map_or("-".into(), |p| sig(p * 1e6, 3))
        );
    }
    for w in &r.warnings {
        println!("warning: {w}");
    }
    println!();
    Ok(())
}
