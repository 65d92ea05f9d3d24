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
    /// Least squares over known orientations (dividing head, cube): bias, scale and misalignment of both triads, gyro g-sensitivity; rotations of a known angle for the gyro scale.
    Multipos(MultiposArgs),
    /// Apply a calibration (any of the three) to a raw series, row by row: calibrated accelerometer (m/s^2) and gyro.
    Apply(ApplyArgs),
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

/// Accelerometer matrix convention of `incal imu multipos`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MatrixArg {
    /// All nine elements (the fixture defines the IMU frame).
    Full,
    /// Upper-triangular (the accelerometers define the IMU frame).
    Upper,
}

/// Options of `incal imu multipos`.
#[derive(clap::Args, Debug)]
pub struct MultiposArgs {
    /// Session CSV: position (a label: x_p, x_a, … or 2-3 of them joined by '+'; x_rot, y_rot, z_rot for rotations; empty between positions) and/or fx,fy,fz (unit up direction in the IMU frame), optional nx,ny,nz (north), acc_x,acc_y,acc_z[,gyr_x,gyr_y,gyr_z]; consecutive rows of one position are its samples; - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Sample rate (Hz): times the rotations.
    #[arg(long)]
    pub rate_hz: f64,
    /// Gravity (m/s^2).
    #[arg(long, default_value_t = 9.81)]
    pub gravity_m_s2: f64,
    /// Accelerometer matrix: full or upper (triangular).
    #[arg(long, value_enum, default_value = "full")]
    pub matrix: MatrixArg,
    /// Latitude (deg): the Earth rate becomes a known gyro input (needs nx,ny,nz).
    #[arg(long, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: Option<f64>,
    /// Angle of each rotation section (deg; -360 is clockwise seen from the axis tip).
    #[arg(long, default_value_t = -360.0, allow_hyphen_values = true)]
    pub rotation_deg: f64,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal imu multipos`.
pub fn run_multipos(a: &MultiposArgs) -> CliResult<()> {
    use incal::procedures::imu::multipos::{
        multipos, MatrixForm, MultiposOptions, RotationSection, StaticPosition,
    };
    use incal::procedures::imu::{SectionStats, V3};
    let rate = positive("--rate-hz", a.rate_hz, 1e6)?;
    if !(a.gravity_m_s2.is_finite() && a.gravity_m_s2 > 0.0 && a.gravity_m_s2 <= 100.0) {
        return Err(usage(format!(
            "--gravity-m-s2 must be > 0 and <= 100, got {}",
            num(a.gravity_m_s2)
        )));
    }
    if !(a.rotation_deg.is_finite() && a.rotation_deg != 0.0 && a.rotation_deg.abs() <= 36000.0) {
        return Err(usage(format!(
            "--rotation-deg must be non-zero with |A| <= 36000, got {}",
            num(a.rotation_deg)
        )));
    }
    let s = read_session(&a.input, true, false)?;
    let t = &s.table;
    let Some(acc) = s.acc.as_ref() else {
        return Err(usage("the accelerometer columns are required".to_string()));
    };
    let cpos = t.opt_column("position");
    let cf: Option<[usize; 3]> = match (t.opt_column("fx"), t.opt_column("fy"), t.opt_column("fz"))
    {
        (Some(x), Some(y), Some(z)) => Some([x, y, z]),
        (None, None, None) => None,
        _ => {
            for c in ["fx", "fy", "fz"] {
                t.column(c)?;
            }
            None
        }
    };
    if cpos.is_none() && cf.is_none() {
        t.column("position")?;
    }
    let cn: Option<[usize; 3]> = match (t.opt_column("nx"), t.opt_column("ny"), t.opt_column("nz"))
    {
        (Some(x), Some(y), Some(z)) => Some([x, y, z]),
        _ => None,
    };
    if a.latitude_deg.is_some() && cn.is_none() {
        t.column("nx")?;
    }
    // Key and direction of every row.
    enum Row {
        Skip,
        Static(String, V3, Option<V3>),
        Rotation(String, usize),
    }
    let mut rows = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        let label = cpos.map(|c| t.text(row, c).trim().to_string());
        if let Some(l) = &label {
            if let Some(axis) = ["x_rot", "y_rot", "z_rot"].iter().position(|r| r == l) {
                rows.push(Row::Rotation(l.clone(), axis));
                continue;
            }
            if l.is_empty() && cf.is_none() {
                rows.push(Row::Skip);
                continue;
            }
        }
        let from_label = match &label {
            Some(l) if !l.is_empty() => Some(V3::from(
                position_direction(l).map_err(|e| t.error_at(row, e))?,
            )),
            _ => None,
        };
        let from_f = match cf {
            Some(c) => {
                let v = V3::new(t.f64(row, c[0])?, t.f64(row, c[1])?, t.f64(row, c[2])?);
                let n = v.norm();
                if (n - 1.0).abs() > 1e-3 {
                    return Err(t.error_at(
                        row,
                        format!("fx,fy,fz must be a unit vector, its norm is {}", num(n)),
                    ));
                }
                Some(v / n)
            }
            None => None,
        };
        let up = match (from_label, from_f) {
            (Some(l), Some(f)) => {
                if (l - f).norm() > 1e-3 {
                    return Err(t.error_at(
                        row,
                        format!(
                            "position '{}' points ({}, {}, {}) but fx,fy,fz say ({}, {}, {})",
                            crate::output::clip(label.as_deref().unwrap_or("")),
                            num(l[0]),
                            num(l[1]),
                            num(l[2]),
                            num(f[0]),
                            num(f[1]),
                            num(f[2])
                        ),
                    ));
                }
                f
            }
            (Some(l), None) => l,
            (None, Some(f)) => f,
            (None, None) => {
                rows.push(Row::Skip);
                continue;
            }
        };
        let north = match cn {
            Some(c) => {
                let v = V3::new(t.f64(row, c[0])?, t.f64(row, c[1])?, t.f64(row, c[2])?);
                if (v.norm() - 1.0).abs() > 1e-3 || v.dot(&up).abs() > 1e-3 {
                    return Err(t.error_at(
                        row,
                        "nx,ny,nz must be a unit vector normal to the up direction".to_string(),
                    ));
                }
                Some(v)
            }
            None => None,
        };
        let key = label
            .filter(|l| !l.is_empty())
            .unwrap_or_else(|| format!("({}, {}, {})", num(up[0]), num(up[1]), num(up[2])));
        rows.push(Row::Static(key, up, north));
    }
    let zero3 = [0.0; 3];
    let sample = |i: usize| -> [f64; 6] {
        let a3 = acc[i];
        let g3 = s.gyr.as_ref().map_or(zero3, |g| g[i]);
        [a3[0], a3[1], a3[2], g3[0], g3[1], g3[2]]
    };
    let mut statics = Vec::new();
    let mut rotations = Vec::new();
    let mut i = 0;
    while i < rows.len() {
        let start = i;
        let mut block = vec![sample(i)];
        i += 1;
        let same = |x: &Row, y: &Row| match (x, y) {
            (Row::Static(a, _, _), Row::Static(b, _, _)) => a == b,
            (Row::Rotation(a, _), Row::Rotation(b, _)) => a == b,
            (Row::Skip, Row::Skip) => true,
            _ => false,
        };
        while i < rows.len() && same(&rows[i], &rows[start]) {
            block.push(sample(i));
            i += 1;
        }
        let stats = || SectionStats::of(&block).map_err(|e| in_file(&t.path, e));
        match &rows[start] {
            Row::Skip => {}
            Row::Static(key, up, north) => {
                if block.len() < 2 {
                    return Err(t.error_at(
                        start,
                        format!("position {key} has a single sample (at least 2 are needed)"),
                    ));
                }
                statics.push(StaticPosition {
                    label: key.clone(),
                    up: *up,
                    north: *north,
                    stats: stats()?,
                });
            }
            Row::Rotation(label, axis) => {
                if s.gyr.is_none() {
                    return Err(t.error_at(start, format!("rotation {label} without gyro columns")));
                }
                rotations.push(RotationSection {
                    label: label.clone(),
                    axis: *axis,
                    stats: stats()?,
                });
            }
        }
    }
    let r = multipos(
        &statics,
        &rotations,
        &MultiposOptions {
            gravity: a.gravity_m_s2,
            matrix: match a.matrix {
                MatrixArg::Full => MatrixForm::Full,
                MatrixArg::Upper => MatrixForm::Upper,
            },
            rate_hz: rate,
            latitude_deg: a.latitude_deg,
            rotation_deg: a.rotation_deg,
            gyro: s.gyr.is_some(),
        },
    )
    .map_err(|e| in_file(&t.path, e))?;
    let mut doc = r.document().map_err(|e| in_file(&t.path, e))?;
    doc.inputs.push(t.input_file("input"));
    a.result.emit(doc)
}

/// Options of `incal imu apply`.
#[derive(clap::Args, Debug)]
pub struct ApplyArgs {
    /// Calibration: a result of incal imu ferraris, multipos or autocal (JSON).
    #[arg(long)]
    pub calibration: PathBuf,
    /// Raw CSV: acc_x,acc_y,acc_z[,gyr_x,gyr_y,gyr_z], optional time_s (copied); read and written row by row (any length); - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Write the calibrated CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// A calibration ready to apply: `f = M_a (a − b_a)`,
/// `ω = M_g (g − b_g − G f)`.
struct Applier {
    m_a: incal::procedures::imu::M3,
    b_a: incal::procedures::imu::V3,
    gyro: Option<(
        incal::procedures::imu::M3,
        incal::procedures::imu::V3,
        incal::procedures::imu::M3,
    )>,
    gyr_unit: &'static str,
}

fn json_m3(v: &serde_json::Value, path: &str) -> Result<incal::procedures::imu::M3, String> {
    let rows = v
        .as_array()
        .filter(|r| r.len() == 3)
        .ok_or_else(|| format!("{path}: expected a list of 3 rows"))?;
    let mut m = incal::procedures::imu::M3::zeros();
    for (i, r) in rows.iter().enumerate() {
        let r = r
            .as_array()
            .filter(|r| r.len() == 3)
            .ok_or_else(|| format!("{path}[{i}]: expected 3 numbers"))?;
        for (j, x) in r.iter().enumerate() {
            m[(i, j)] = x
                .as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("{path}[{i}][{j}]: not a finite number"))?;
        }
    }
    Ok(m)
}

fn json_v3(v: &serde_json::Value, path: &str) -> Result<incal::procedures::imu::V3, String> {
    let r = v
        .as_array()
        .filter(|r| r.len() == 3)
        .ok_or_else(|| format!("{path}: expected 3 numbers"))?;
    let mut out = incal::procedures::imu::V3::zeros();
    for (j, x) in r.iter().enumerate() {
        out[j] = x
            .as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{path}[{j}]: not a finite number"))?;
    }
    Ok(out)
}

fn inverse(
    m: incal::procedures::imu::M3,
    what: &str,
) -> Result<incal::procedures::imu::M3, String> {
    m.try_inverse()
        .filter(|i| i.iter().all(|v| v.is_finite()))
        .ok_or_else(|| format!("{what} is singular"))
}

impl Applier {
    fn from_document(doc: &incal::document::ResultDocument) -> Result<Applier, String> {
        use incal::document::Procedure;
        use incal::procedures::imu::M3;
        let x = &doc.extra;
        let get = |k: &str| x.get(k).ok_or_else(|| format!("$.{k}: missing"));
        match doc.procedure {
            Procedure::ImuFerraris => {
                let k_a = json_m3(get("K_a")?, "$.K_a")?;
                let r_a = json_m3(get("R_a")?, "$.R_a")?;
                let k_g = json_m3(get("K_g")?, "$.K_g")?;
                let r_g = json_m3(get("R_g")?, "$.R_g")?;
                Ok(Applier {
                    m_a: inverse(k_a * r_a, "K_a R_a")?,
                    b_a: json_v3(get("b_a")?, "$.b_a")?,
                    gyro: Some((
                        inverse(k_g * r_g, "K_g R_g")?,
                        json_v3(get("b_g")?, "$.b_g")?,
                        json_m3(get("K_ga")?, "$.K_ga")?,
                    )),
                    gyr_unit: "deg_s",
                })
            }
            Procedure::ImuAutocal => {
                let acc = get("acc")?;
                let tk = |v: &serde_json::Value, p: &str| -> Result<(M3, incal::procedures::imu::V3), String> {
                    let t = json_m3(&v["T"], &format!("{p}.T"))?;
                    let k = json_m3(&v["K"], &format!("{p}.K"))?;
                    Ok((t * k, json_v3(&v["b"], &format!("{p}.b"))?))
                };
                let (m_a, b_a) = tk(acc, "$.acc")?;
                let gyro = match x.get("gyr") {
                    Some(g) => {
                        let (m, b) = tk(g, "$.gyr")?;
                        Some((m, b, M3::zeros()))
                    }
                    None => None,
                };
                Ok(Applier {
                    m_a,
                    b_a,
                    gyro,
                    gyr_unit: "rad_s",
                })
            }
            Procedure::ImuMultipos => {
                let acc = get("acc")?;
                let m_a = inverse(json_m3(&acc["A"], "$.acc.A")?, "$.acc.A")?;
                let b_a = json_v3(&acc["b"], "$.acc.b")?;
                let gyro = match x.get("gyr") {
                    Some(g) if g.get("A").is_some() => Some((
                        inverse(json_m3(&g["A"], "$.gyr.A")?, "$.gyr.A")?,
                        json_v3(&g["b"], "$.gyr.b")?,
                        json_m3(&g["G"], "$.gyr.G")?,
                    )),
                    _ => None,
                };
                Ok(Applier {
                    m_a,
                    b_a,
                    gyro,
                    gyr_unit: "deg_s",
                })
            }
            other => Err(format!(
                "$.procedure: '{other}' is not an IMU calibration (imu-ferraris, imu-multipos or imu-autocal)"
            )),
        }
    }
}

/// `incal imu apply`.
pub fn run_apply(a: &ApplyArgs) -> CliResult<()> {
    use crate::error::CliError;
    use incal::procedures::imu::V3;
    use std::io::Write;
    let (cal_name, _, doc) = crate::documents::read_document(&a.calibration)?;
    let cal =
        Applier::from_document(&doc).map_err(|e| CliError::Input(format!("{cal_name}: {e}")))?;
    let (name, reader) = crate::io::open_input(&a.input)?;
    let mut csv = csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(reader);
    let mut w = crate::io::open_output(a.output.as_deref())?;
    let wfail = |e: std::io::Error| CliError::Failure(anyhow::anyhow!("cannot write: {e}"));
    let mut rec = csv::ByteRecord::new();
    // (time column, acc columns, gyro columns, width)
    type Columns = (Option<usize>, [usize; 3], Option<[usize; 3]>, usize);
    let mut cols: Option<Columns> = None;
    let mut fmt = ryu::Buffer::new();
    let mut line_buf = String::with_capacity(256);
    let mut rows = 0u64;
    loop {
        let more = csv.read_byte_record(&mut rec).map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            CliError::Input(format!("{name}:{line}: not valid CSV"))
        })?;
        if !more {
            break;
        }
        let line = rec.position().map_or(0, |p| p.line());
        if rec.iter().all(|f| f.is_empty()) {
            continue;
        }
        let Some((ct, ca, cg, width)) = cols else {
            let headers: Vec<String> = rec
                .iter()
                .map(|h| String::from_utf8_lossy(h).to_string())
                .collect();
            let find = |n: &str| headers.iter().position(|h| h == n);
            let need = |n: &str| {
                find(n).ok_or_else(|| {
                    CliError::Input(format!(
                        "{name}: missing column '{n}' (columns: {})",
                        crate::output::clip(&headers.join(", "))
                    ))
                })
            };
            let ca = [need("acc_x")?, need("acc_y")?, need("acc_z")?];
            let cg = match (find("gyr_x"), cal.gyro.is_some()) {
                (Some(_), true) => Some([need("gyr_x")?, need("gyr_y")?, need("gyr_z")?]),
                _ => None,
            };
            let ct = find("time_s");
            cols = Some((ct, ca, cg, headers.len()));
            let mut head = String::new();
            if ct.is_some() {
                head.push_str("time_s,");
            }
            head.push_str("acc_x_m_s2,acc_y_m_s2,acc_z_m_s2");
            if cg.is_some() {
                let u = cal.gyr_unit;
                head.push_str(&format!(",gyr_x_{u},gyr_y_{u},gyr_z_{u}"));
            }
            head.push('\n');
            w.write_all(head.as_bytes()).map_err(wfail)?;
            continue;
        };
        if rec.len() != width {
            return Err(CliError::Input(format!(
                "{name}:{line}: {} fields, but the header has {width}",
                rec.len()
            )));
        }
        let num = |k: usize| -> CliResult<f64> {
            let text = std::str::from_utf8(&rec[k]).unwrap_or("");
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() && v.abs() <= crate::input::MAX_ABS_VALUE => Ok(v),
                _ => Err(CliError::Input(format!(
                    "{name}:{line}: field {}: '{}' is not a finite number within 1e15",
                    k + 1,
                    crate::output::clip(&String::from_utf8_lossy(&rec[k]))
                ))),
            }
        };
        line_buf.clear();
        if let Some(c) = ct {
            line_buf.push_str(fmt.format(num(c)?));
            line_buf.push(',');
        }
        let raw_a = V3::new(num(ca[0])?, num(ca[1])?, num(ca[2])?);
        let f = cal.m_a * (raw_a - cal.b_a);
        for k in 0..3 {
            if k > 0 {
                line_buf.push(',');
            }
            line_buf.push_str(fmt.format(f[k]));
        }
        if let (Some(c), Some((m, b, gs))) = (cg, cal.gyro.as_ref()) {
            let raw_g = V3::new(num(c[0])?, num(c[1])?, num(c[2])?);
            let wv = m * (raw_g - b - gs * f);
            for k in 0..3 {
                line_buf.push(',');
                line_buf.push_str(fmt.format(wv[k]));
            }
        }
        line_buf.push('\n');
        w.write_all(line_buf.as_bytes()).map_err(wfail)?;
        rows += 1;
    }
    if cols.is_none() || rows == 0 {
        return Err(CliError::Input(format!("{name}: no data rows")));
    }
    w.flush().map_err(wfail)?;
    Ok(())
}
