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
