//! `incal imu ferraris|multipos|autocal|apply` and `incal simulate imu`:
//! IMU triad calibration (three accelerometers, three gyros).

use std::path::{Path, PathBuf};

use clap::Subcommand;
use incal::procedures::imu::ferraris::{self as fe, FerrarisOptions};

use crate::error::{in_file, usage, CliResult};
use crate::input::Table;
use crate::output::{num, ResultArgs};

/// `incal imu …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Ferraris six-position + three-rotation calibration (imucal's method, keys and definitions) with the u of every element.
    Ferraris(FerrarisArgs),
    /// Autocalibration without a fixture (Tedaldi et al. 2014): still intervals found automatically, accelerometer and gyro triads in imu_tk's convention.
    Autocal(AutocalArgs),
}

/// Accelerometer columns of a session.
pub const ACC: [&str; 3] = ["acc_x", "acc_y", "acc_z"];
/// Gyro columns of a session.
pub const GYR: [&str; 3] = ["gyr_x", "gyr_y", "gyr_z"];

/// A session CSV read into memory: the optional time and part columns and
/// the two triads (either may be absent).
pub struct Session {
    /// The table (for file name, lines, hash).
    pub table: Table,
    /// `time_s` per row, when the column is there.
    pub time: Option<Vec<f64>>,
    /// Accelerometer triad per row.
    pub acc: Option<Vec<[f64; 3]>>,
    /// Gyro triad per row.
    pub gyr: Option<Vec<[f64; 3]>>,
}

fn triad(t: &Table, names: [&str; 3]) -> CliResult<Option<Vec<[f64; 3]>>> {
    let cols: Vec<Option<usize>> = names.iter().map(|n| t.opt_column(n)).collect();
    if cols.iter().all(|c| c.is_none()) {
        return Ok(None);
    }
    let mut idx = [0usize; 3];
    for k in 0..3 {
        idx[k] = t.column(names[k])?;
    }
    let mut out = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        out.push([
            t.f64(row, idx[0])?,
            t.f64(row, idx[1])?,
            t.f64(row, idx[2])?,
        ]);
    }
    Ok(Some(out))
}

/// Read a session CSV; `need_acc`/`need_gyr` make a triad required.
pub fn read_session(path: &Path, need_acc: bool, need_gyr: bool) -> CliResult<Session> {
    let table = Table::read(path)?;
    let acc = triad(&table, ACC)?;
    let gyr = triad(&table, GYR)?;
    if need_acc && acc.is_none() {
        table.column("acc_x")?;
    }
    if need_gyr && gyr.is_none() {
        table.column("gyr_x")?;
    }
    if acc.is_none() && gyr.is_none() {
        table.column("acc_x")?;
    }
    let time = match table.opt_column("time_s") {
        None => None,
        Some(c) => {
            let mut v = Vec::with_capacity(table.row_count());
            for row in 0..table.row_count() {
                let x = table.f64(row, c)?;
                if let Some(&prev) = v.last() {
                    if x <= prev {
                        return Err(table.error_at(
                            row,
                            format!(
                                "time_s {} does not increase (previous row {})",
                                num(x),
                                num(prev)
                            ),
                        ));
                    }
                }
                v.push(x);
            }
            Some(v)
        }
    };
    Ok(Session {
        table,
        time,
        acc,
        gyr,
    })
}

fn positive(name: &str, x: f64, max: f64) -> CliResult<f64> {
    if x.is_finite() && x > 0.0 && x <= max {
        Ok(x)
    } else {
        Err(usage(format!(
            "{name} must be > 0 and <= {max}, got {}",
            num(x)
        )))
    }
}

fn gravity(x: f64) -> CliResult<f64> {
    if x.is_finite() && x != 0.0 && x.abs() <= 100.0 {
        Ok(x)
    } else {
        Err(usage(format!(
            "--gravity-m-s2 must be non-zero with |g| <= 100, got {}",
            num(x)
        )))
    }
}

/// Options of `incal imu ferraris`.
#[derive(clap::Args, Debug)]
pub struct FerrarisArgs {
    /// Session CSV: part,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z (other columns ignored); part is one of x_p, x_a, y_p, y_a, z_p, z_a, x_rot, y_rot, z_rot, or empty for rows between sections; - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Sample rate (Hz): integrates the rotations.
    #[arg(long)]
    pub rate_hz: f64,
    /// Gravity (m/s^2); negative when the positive axis is the one reading -g (imucal's convention).
    #[arg(long, default_value_t = 9.81, allow_hyphen_values = true)]
    pub gravity_m_s2: f64,
    /// Angle of each rotation section (deg); negative is clockwise seen from the axis tip (imucal's default -360).
    #[arg(long, default_value_t = -360.0, allow_hyphen_values = true)]
    pub rotation_deg: f64,
    /// Standard uncertainty of the rotation angle (deg).
    #[arg(long, default_value_t = 0.0)]
    pub u_rotation_deg: f64,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal imu ferraris`.
pub fn run_ferraris(a: &FerrarisArgs) -> CliResult<()> {
    let rate = positive("--rate-hz", a.rate_hz, 1e6)?;
    let g = gravity(a.gravity_m_s2)?;
    if !(a.rotation_deg.is_finite() && a.rotation_deg != 0.0 && a.rotation_deg.abs() <= 36000.0) {
        return Err(usage(format!(
            "--rotation-deg must be non-zero with |A| <= 36000, got {}",
            num(a.rotation_deg)
        )));
    }
    if !(a.u_rotation_deg.is_finite() && (0.0..=360.0).contains(&a.u_rotation_deg)) {
        return Err(usage(format!(
            "--u-rotation-deg must be within 0..360, got {}",
            num(a.u_rotation_deg)
        )));
    }
    let s = read_session(&a.input, true, true)?;
    let t = &s.table;
    let cp = t.column("part")?;
    let (Some(acc), Some(gyr)) = (s.acc.as_ref(), s.gyr.as_ref()) else {
        return Err(usage("the Ferraris method needs both triads".to_string()));
    };
    let mut secs: [Vec<[f64; 6]>; 9] = Default::default();
    for row in 0..t.row_count() {
        let label = t.text(row, cp).trim();
        if label.is_empty() {
            continue;
        }
        let k = fe::SECTIONS
            .iter()
            .position(|l| *l == label)
            .ok_or_else(|| {
                t.error_at(
                    row,
                    format!(
                        "part '{}' is not a Ferraris section (one of {}, or empty)",
                        crate::output::clip(label),
                        fe::SECTIONS.join(", ")
                    ),
                )
            })?;
        let (a3, g3) = (acc[row], gyr[row]);
        secs[k].push([a3[0], a3[1], a3[2], g3[0], g3[1], g3[2]]);
    }
    let missing: Vec<&str> = fe::SECTIONS
        .iter()
        .zip(&secs)
        .filter(|(_, v)| v.len() < 2)
        .map(|(l, _)| *l)
        .collect();
    if !missing.is_empty() {
        return Err(in_file(
            &t.path,
            format!(
                "the Ferraris method needs all nine sections with at least 2 samples each; missing or too short: {}",
                missing.join(", ")
            ),
        ));
    }
    let r = fe::ferraris(
        &secs,
        &FerrarisOptions {
            rate_hz: rate,
            gravity: g,
            rotation_deg: a.rotation_deg,
            u_rotation_deg: a.u_rotation_deg,
        },
    )
    .map_err(|e| in_file(&t.path, e))?;
    let mut doc = r.document().map_err(|e| in_file(&t.path, e))?;
    doc.inputs.push(t.input_file("input"));
    a.result.emit(doc)
}

/// Autocalibration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// incal's weighted least squares with the covariance of every parameter.
    Incal,
    /// imu_tk's exact steps (Tedaldi et al. 2014), for comparison.
    Tedaldi,
}

/// Options of `incal imu autocal`.
#[derive(clap::Args, Debug)]
pub struct AutocalArgs {
    /// Record CSV: time_s (optional),acc_x,acc_y,acc_z[,gyr_x,gyr_y,gyr_z], raw counts or physical units; starts still; - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Sample rate (Hz); the time_s column, when present, gives the time steps instead.
    #[arg(long)]
    pub rate_hz: f64,
    /// Gravity magnitude (m/s^2): the calibrated accelerometer output is in this unit.
    #[arg(long, default_value_t = 9.81)]
    pub gravity_m_s2: f64,
    /// Duration of the still start (s): its variance sets the static threshold, its gyro mean the gyro bias.
    #[arg(long, default_value_t = 50.0)]
    pub init_static_s: f64,
    /// incal (weighted, with covariance) or tedaldi (imu_tk's exact steps).
    #[arg(long, value_enum, default_value = "incal")]
    pub method: MethodArg,
    /// Time trimmed from both ends of every still interval (s; method incal).
    #[arg(long, default_value_t = 0.1)]
    pub settle_s: f64,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal imu autocal`.
pub fn run_autocal(a: &AutocalArgs) -> CliResult<()> {
    use incal::procedures::imu::autocal::{autocal, AutocalOptions, Method};
    let rate = positive("--rate-hz", a.rate_hz, 1e6)?;
    if !(a.gravity_m_s2.is_finite() && a.gravity_m_s2 > 0.0 && a.gravity_m_s2 <= 100.0) {
        return Err(usage(format!(
            "--gravity-m-s2 must be > 0 and <= 100, got {}",
            num(a.gravity_m_s2)
        )));
    }
    positive("--init-static-s", a.init_static_s, 1e6)?;
    if !(a.settle_s.is_finite() && (0.0..=1e3).contains(&a.settle_s)) {
        return Err(usage(format!(
            "--settle-s must be within 0..1000, got {}",
            num(a.settle_s)
        )));
    }
    let s = read_session(&a.input, true, false)?;
    let t = &s.table;
    let Some(acc) = s.acc.as_ref() else {
        return Err(usage("the accelerometer columns are required".to_string()));
    };
    let time: Vec<f64> = match &s.time {
        Some(v) => v.clone(),
        None => (0..acc.len()).map(|i| i as f64 / rate).collect(),
    };
    let method = match a.method {
        MethodArg::Incal => Method::Incal,
        MethodArg::Tedaldi => Method::Tedaldi,
    };
    let mut opts = AutocalOptions::new(method, a.gravity_m_s2, a.init_static_s);
    if method == Method::Incal {
        opts.settle_s = a.settle_s;
    }
    let r = autocal(&time, acc, s.gyr.as_deref(), &opts).map_err(|e| in_file(&t.path, e))?;
    let mut doc = r.document().map_err(|e| in_file(&t.path, e))?;
    doc.inputs.push(t.input_file("input"));
    doc.options
        .insert("rate_hz".into(), serde_json::json!(rate));
    a.result.emit(doc)
}

/// Session sequence of `incal simulate imu`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SequenceArg {
    /// imucal's nine labelled sections (input of `incal imu ferraris`).
    Ferraris,
    /// A still start, then random orientations joined by rotations (input of `incal imu autocal`).
    Random,
    /// Static positions with their labels and fx,fy,fz (input of `incal imu multipos`).
    Positions,
}

/// Options of `incal simulate imu`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// ferraris, random or positions.
    #[arg(long, value_enum, default_value = "ferraris")]
    pub sequence: SequenceArg,
    /// Sample rate (Hz).
    #[arg(long, default_value_t = 100.0)]
    pub rate_hz: f64,
    /// Duration of every static position (s).
    #[arg(long, default_value_t = 3.0)]
    pub static_s: f64,
    /// Random: orientations after the still start.
    #[arg(long, default_value_t = 30)]
    pub orientations: usize,
    /// Random: duration of the still start (s).
    #[arg(long, default_value_t = 50.0)]
    pub init_static_s: f64,
    /// Random: duration of each rotation between orientations (s).
    #[arg(long, default_value_t = 1.5)]
    pub move_s: f64,
    /// Positions: labels, comma separated (faces x_p..z_a, edges and corners as x_p+y_a, x_p+y_p+z_a).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "x_p,x_a,y_p,y_a,z_p,z_a,x_p+y_p,x_p+y_a,x_a+y_p,x_a+y_a,x_p+z_p,x_p+z_a,x_a+z_p,x_a+z_a,y_p+z_p,y_p+z_a,y_a+z_p,y_a+z_a"
    )]
    pub positions: Vec<String>,
    /// Positions: append the rotations x_rot, y_rot, z_rot (--rotation-deg, --rotation-s) for the gyro scale.
    #[arg(long)]
    pub rotations: bool,
    /// Ferraris and positions: angle of each rotation (deg; imucal's sign: -360 is clockwise seen from the tip).
    #[arg(long, default_value_t = -360.0, allow_hyphen_values = true)]
    pub rotation_deg: f64,
    /// Ferraris: duration of each rotation (s).
    #[arg(long, default_value_t = 6.0)]
    pub rotation_s: f64,
    /// Gravity (m/s^2).
    #[arg(long, default_value_t = 9.81)]
    pub gravity_m_s2: f64,
    /// Accelerometer white noise, one sample (output units).
    #[arg(long, default_value_t = 3.0)]
    pub noise_acc: f64,
    /// Gyro white noise, one sample (output units).
    #[arg(long, default_value_t = 2.0)]
    pub noise_gyr: f64,
    /// Latitude (deg): adds the Earth rate (positions also get the north direction nx,ny,nz).
    #[arg(long, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: Option<f64>,
    /// Sensor: 0 is a typical MEMS IMU in counts; any other number draws scales, biases, misalignments and g-sensitivity around it with that seed.
    #[arg(long, default_value_t = 0)]
    pub truth_seed: u64,
    /// No gyro g-sensitivity (K_ga = 0), as the autocalibration model assumes.
    #[arg(long)]
    pub no_g_sensitivity: bool,
    /// Random seed of the noise and the orientations.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Write the truth (imucal's, imu_tk's and the sensor model's parameters) as JSON here.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
}

/// Direction of a position label: one to three face labels (`x_p`, `y_a`,
/// …) on different axes joined by `+`; the normalised sum of their unit
/// vectors (`x_p` is +x up, `x_a` is −x up).
pub fn position_direction(label: &str) -> Result<[f64; 3], String> {
    let mut v = [0.0f64; 3];
    let mut used = [false; 3];
    let parts: Vec<&str> = label.split('+').collect();
    if parts.is_empty() || parts.len() > 3 {
        return Err(format!(
            "position '{}' is not 1 to 3 face labels joined by '+'",
            crate::output::clip(label)
        ));
    }
    for p in parts {
        let (axis, sign) = match p.trim() {
            "x_p" => (0, 1.0),
            "x_a" => (0, -1.0),
            "y_p" => (1, 1.0),
            "y_a" => (1, -1.0),
            "z_p" => (2, 1.0),
            "z_a" => (2, -1.0),
            other => {
                return Err(format!(
                    "position '{}': '{}' is not a face label (x_p, x_a, y_p, y_a, z_p, z_a)",
                    crate::output::clip(label),
                    crate::output::clip(other)
                ))
            }
        };
        if used[axis] {
            return Err(format!(
                "position '{}' names the {} axis twice",
                crate::output::clip(label),
                ["x", "y", "z"][axis]
            ));
        }
        used[axis] = true;
        v[axis] = sign;
    }
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    Ok(v.map(|c| c / n))
}

/// `incal simulate imu`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    use incal::procedures::imu::{rows, V3};
    use incal::sim::imu::{simulate as sim, ImuSim, ImuTruth, Sequence};
    use std::fmt::Write as _;
    let rate = positive("--rate-hz", a.rate_hz, 1e5)?;
    positive("--static-s", a.static_s, 1e5)?;
    if !(a.gravity_m_s2.is_finite() && a.gravity_m_s2 > 0.0 && a.gravity_m_s2 <= 100.0) {
        return Err(usage(format!(
            "--gravity-m-s2 must be > 0 and <= 100, got {}",
            num(a.gravity_m_s2)
        )));
    }
    for (n, v) in [("--noise-acc", a.noise_acc), ("--noise-gyr", a.noise_gyr)] {
        if !(v.is_finite() && (0.0..=1e6).contains(&v)) {
            return Err(usage(format!("{n} must be within 0..1e6, got {}", num(v))));
        }
    }
    let sequence = match a.sequence {
        SequenceArg::Ferraris => {
            if !(a.rotation_deg.is_finite()
                && a.rotation_deg != 0.0
                && a.rotation_deg.abs() <= 3600.0)
            {
                return Err(usage(format!(
                    "--rotation-deg must be non-zero with |A| <= 3600, got {}",
                    num(a.rotation_deg)
                )));
            }
            positive("--rotation-s", a.rotation_s, 1e4)?;
            crate::options::sim_size(&[
                ("--static-s x --rate-hz x 6", a.static_s * rate * 6.0),
                ("--rotation-s x --rate-hz x 3", a.rotation_s * rate * 3.0),
            ])?;
            Sequence::Ferraris {
                rotation_deg: a.rotation_deg,
                rotation_s: a.rotation_s,
            }
        }
        SequenceArg::Random => {
            positive("--init-static-s", a.init_static_s, 1e5)?;
            positive("--move-s", a.move_s, 1e4)?;
            if a.orientations == 0 || a.orientations > 10_000 {
                return Err(usage(format!(
                    "--orientations must be within 1..10000, got {}",
                    a.orientations
                )));
            }
            crate::options::sim_size(&[(
                "(--init-static-s + --orientations x (--static-s + --move-s)) x --rate-hz",
                (a.init_static_s + a.orientations as f64 * (a.static_s + a.move_s)) * rate,
            )])?;
            Sequence::Random {
                positions: a.orientations,
                init_s: a.init_static_s,
                move_s: a.move_s,
            }
        }
        SequenceArg::Positions => {
            if a.positions.is_empty() || a.positions.len() > 1000 {
                return Err(usage("--positions needs 1 to 1000 labels".to_string()));
            }
            let mut up = Vec::new();
            for p in &a.positions {
                up.push(V3::from(
                    position_direction(p).map_err(|e| usage(format!("--positions: {e}")))?,
                ));
            }
            crate::options::sim_size(&[(
                "positions x --static-s x --rate-hz",
                a.positions.len() as f64 * a.static_s * rate,
            )])?;
            Sequence::Positions {
                up,
                rotations: a.rotations.then_some((a.rotation_deg, a.rotation_s)),
            }
        }
    };
    let mut truth = if a.truth_seed == 0 {
        ImuTruth::mems_counts()
    } else {
        ImuTruth::random_around_mems(a.truth_seed)
    };
    if a.no_g_sensitivity {
        truth.gyr_k_ga = incal::procedures::imu::M3::zeros();
    }
    let cfg = ImuSim {
        truth: truth.clone(),
        sequence,
        rate_hz: rate,
        static_s: a.static_s,
        gravity: a.gravity_m_s2,
        noise_acc: a.noise_acc,
        noise_gyr: a.noise_gyr,
        latitude_deg: a.latitude_deg,
        seed: a.seed,
    };
    let samples = sim(&cfg).map_err(|e| usage(e.to_string()))?;
    let mut text = String::with_capacity(samples.len() * 120);
    let with_north = a.latitude_deg.is_some();
    match a.sequence {
        SequenceArg::Ferraris => text.push_str("time_s,part,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n"),
        SequenceArg::Random => text.push_str("time_s,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n"),
        SequenceArg::Positions => {
            text.push_str("time_s,position,fx,fy,fz,");
            if with_north {
                text.push_str("nx,ny,nz,");
            }
            text.push_str("acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
        }
    }
    for s in &samples {
        let _ = write!(text, "{}", s.time_s);
        match a.sequence {
            SequenceArg::Ferraris => {
                let _ = write!(text, ",{}", s.part);
            }
            SequenceArg::Random => {}
            SequenceArg::Positions => {
                let (label, up) = match s.part.as_str() {
                    r @ ("x_rot" | "y_rot" | "z_rot") => {
                        let mut up = V3::zeros();
                        up[["x_rot", "y_rot", "z_rot"]
                            .iter()
                            .position(|q| q == &r)
                            .unwrap_or(0)] = 1.0;
                        (r.to_string(), up)
                    }
                    p => {
                        let k: usize = p.trim_start_matches('p').parse().unwrap_or(1);
                        (a.positions[k - 1].clone(), s.up.unwrap_or_else(V3::zeros))
                    }
                };
                let _ = write!(text, ",{label},{},{},{}", up[0], up[1], up[2]);
                if with_north {
                    let n = s.north.unwrap_or_else(V3::zeros);
                    let _ = write!(text, ",{},{},{}", n[0], n[1], n[2]);
                }
            }
        }
        let _ = writeln!(
            text,
            ",{},{},{},{},{},{}",
            s.acc[0], s.acc[1], s.acc[2], s.gyr[0], s.gyr[1], s.gyr[2]
        );
    }
    crate::output::write_text(a.output.as_deref(), &text)?;
    if let Some(p) = &a.truth_out {
        let f = truth.ferraris();
        let mut imucal = serde_json::Map::new();
        for q in incal::procedures::imu::ferraris::QUANTITIES {
            let v = match f.matrix(q) {
                Some(m) => serde_json::json!(rows(&m)),
                None => {
                    let b = if q == "b_a" { f.b_a } else { f.b_g };
                    serde_json::json!([b[0], b[1], b[2]])
                }
            };
            imucal.insert(q.to_string(), v);
        }
        let tk = truth
            .imu_tk()
            .ok_or_else(|| usage("the truth is singular".to_string()))?;
        let triad = |p: &incal::sim::imu::TriadParams| serde_json::json!({"T": rows(&p.t()), "K": rows(&p.k()), "b": p.bias});
        let v = serde_json::json!({
            "imucal": imucal,
            "imu_tk": {"acc": triad(&tk.0), "gyr": triad(&tk.1)},
            "model": {
                "acc_A": rows(&truth.acc_a), "acc_b": [truth.acc_b[0], truth.acc_b[1], truth.acc_b[2]],
                "gyr_A": rows(&truth.gyr_a), "gyr_K_ga": rows(&truth.gyr_k_ga),
                "gyr_b": [truth.gyr_b[0], truth.gyr_b[1], truth.gyr_b[2]],
                "units": "acc_A output/(m/s^2), gyr_A output/(rad/s), gyr_K_ga output/(m/s^2), biases output"
            }
        });
        crate::output::write_text(Some(p), &format!("{}\n", crate::output::json_text(&v)))?;
    }
    Ok(())
}
