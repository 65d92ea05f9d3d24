//! `incal misalign gyro|accel`, `incal simulate misalign gyro|accel`,
//! `incal plan misalign`, and the misalignment section of `incal demo`
//! (seed 003; methods.md §3).

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use incal::procedures::misalign::accel::{self, AccelObservation, AccelOptions};
use incal::procedures::misalign::averaging::{
    average_record, RawSample, Record, RecordMean, TurnPolicy,
};
use incal::procedures::misalign::gyro::{self, GyroConfig, GyroObservation, GyroOptions};
use incal::procedures::misalign::plan::{predict_accel, predict_gyro, Prediction};
use incal::rigs::rate_table::{FaceMounting, GyroMounting};
use incal::sim::misalign::{
    simulate_accel, simulate_gyro, simulate_gyro_records, AccelSim, GyroSim,
};
use incal::units::{arcsec_to_rad, rad_to_arcsec, rad_to_deg};
use serde_json::{json, Map, Value};

use crate::error::{core, in_file, usage, CliError, CliResult};
use crate::input::Table;
use crate::options::noise_option;
use crate::output::{json_text, sig, table, write_text, ResultArgs};

/// `incal misalign …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Gyro on a rate table: table, fixture and input-axis misalignment from forward/reverse rates.
    Gyro(GyroArgs),
    /// Accelerometer on a vertical reference face: input-axis misalignment from turns about the face normal.
    Accel(AccelArgs),
}

/// `incal simulate misalign …`.
#[derive(Subcommand, Debug)]
pub enum SimCommand {
    /// Gyro on a rate table (Earth rate included); writes the input CSV of `incal misalign gyro`.
    Gyro(SimGyroArgs),
    /// Accelerometer on a vertical face; writes the input CSV of `incal misalign accel`.
    Accel(SimAccelArgs),
}

/// Which samples of a raw record are averaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TurnsArg {
    /// The first whole table revolutions of each record (Earth rate cancels).
    Whole,
    /// Every sample, whole revolutions or not.
    All,
}

/// Options of `incal misalign gyro`.
#[derive(clap::Args, Debug)]
pub struct GyroArgs {
    /// Input CSV: alpha_deg,beta_deg,rate,output (record means), or with time_s,table_angle_deg added (raw records).
    #[arg(long)]
    pub input: PathBuf,
    /// Known gyro scale factor kI (output per deg/s).
    #[arg(long, visible_alias = "k1", allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Fit one bias per (alpha, beta) configuration instead of a common one.
    #[arg(long)]
    pub per_config_bias: bool,
    /// Known standard deviation of one row's output (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Raw records: average whole table revolutions only, or every sample (--turns is an old name of this option).
    #[arg(long = "average", alias = "turns", value_enum, default_value = "whole")]
    pub turns: TurnsArg,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// Options of `incal misalign accel`.
#[derive(clap::Args, Debug)]
pub struct AccelArgs {
    /// Input CSV: beta_deg,output (rows repeat = samples).
    #[arg(long)]
    pub input: PathBuf,
    /// Known accelerometer scale factor kI (output per g).
    #[arg(long, visible_alias = "k1", allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Known standard deviation of one row's output (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    #[command(flatten)]
    pub result: ResultArgs,
}

fn scale_of(k: f64) -> CliResult<f64> {
    if k.is_finite() && k != 0.0 {
        Ok(k)
    } else {
        Err(usage(format!(
            "--scale-factor must be a finite non-zero number, got {k}"
        )))
    }
}

/// Raw records read from a table, with the first file line of each.
fn read_records(t: &Table) -> CliResult<Vec<(usize, Record)>> {
    let (ca, cb, cr) = (
        t.column("alpha_deg")?,
        t.column("beta_deg")?,
        t.column("rate")?,
    );
    let (ct, cg, co) = (
        t.column("time_s")?,
        t.column("table_angle_deg")?,
        t.column("output")?,
    );
    let mut out: Vec<(usize, Record)> = Vec::new();
    let mut last: Option<(f64, f64, f64)> = None;
    for row in 0..t.row_count() {
        let key = (t.f64(row, ca)?, t.f64(row, cb)?, t.f64(row, cr)?);
        if key.2 == 0.0 {
            return Err(t.error_at(row, "column 'rate': the table rate must not be 0".into()));
        }
        let s = RawSample {
            time_s: t.f64(row, ct)?,
            table_angle_rad: t.f64(row, cg)?.to_radians(),
            output: t.f64(row, co)?,
        };
        // A new record starts when the configuration or rate changes, or
        // when the time goes back (records of one configuration written one
        // after another, each from its own t = 0). Within a record the time
        // must increase: a repeated time is refused at its own line.
        let prev_time = out
            .last()
            .and_then(|(_, r)| r.samples.last())
            .map(|p| p.time_s);
        let restart = matches!(prev_time, Some(p) if s.time_s < p);
        if last == Some(key) && prev_time == Some(s.time_s) {
            return Err(t.error_at(
                row,
                format!("column 'time_s': {} repeats the previous sample's time (time must increase within a record)", s.time_s),
            ));
        }
        if last != Some(key) || restart {
            out.push((
                t.line(row),
                Record {
                    config: GyroConfig::deg(key.0, key.1),
                    rate_deg_s: key.2,
                    samples: Vec::new(),
                },
            ));
            last = Some(key);
        }
        if let Some((_, r)) = out.last_mut() {
            r.samples.push(s);
        }
    }
    Ok(out)
}

/// Raw records' reductions with their first file line.
type RecordRows = Vec<(usize, RecordMean)>;

fn read_gyro(a: &GyroArgs) -> CliResult<(Table, Vec<GyroObservation>, RecordRows)> {
    let t = Table::read(&a.input)?;
    let file = t.path.clone();
    if t.opt_column("table_angle_deg").is_some() || t.opt_column("time_s").is_some() {
        let policy = match a.turns {
            TurnsArg::Whole => TurnPolicy::Whole,
            TurnsArg::All => TurnPolicy::All,
        };
        let mut rows = Vec::new();
        for (line, r) in read_records(&t)? {
            let mean = average_record(&r, policy)
                .map_err(|e| CliError::Input(format!("{file}:{line}: {e}")))?;
            rows.push((line, mean));
        }
        let obs = rows.iter().map(|r| r.1.observation).collect();
        return Ok((t, obs, rows));
    }
    let (ca, cb, cr, co) = (
        t.column("alpha_deg")?,
        t.column("beta_deg")?,
        t.column("rate")?,
        t.column("output")?,
    );
    let mut obs = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        let rate = t.f64(row, cr)?;
        if rate == 0.0 {
            return Err(t.error_at(row, "column 'rate': the table rate must not be 0".into()));
        }
        obs.push(GyroObservation {
            alpha_rad: t.f64(row, ca)?.to_radians(),
            beta_rad: t.f64(row, cb)?.to_radians(),
            rate_deg_s: rate,
            output: t.f64(row, co)?,
        });
    }
    Ok((t, obs, Vec::new()))
}

/// `incal misalign gyro|accel`.
pub fn run(c: &Command) -> CliResult<()> {
    match c {
        Command::Gyro(a) => run_gyro(a),
        Command::Accel(a) => run_accel(a),
    }
}

fn run_gyro(a: &GyroArgs) -> CliResult<()> {
    let opts = GyroOptions {
        scale_factor: scale_of(a.scale_factor)?,
        per_config_bias: a.per_config_bias,
        noise: noise_option(a.noise)?,
    };
    let (table, obs, records) = read_gyro(a)?;
    let r = gyro::calibrate(&obs, &opts).map_err(|e| in_file(&table.path, e))?;
    let mut doc = r
        .document(&opts, &records)
        .map_err(|e| in_file(&table.path, e))?;
    doc.inputs.push(table.input_file("input"));
    doc.options.insert("noise".into(), json!(a.noise));
    if !records.is_empty() {
        let turns = match a.turns {
            TurnsArg::Whole => "whole",
            TurnsArg::All => "all",
        };
        doc.options.insert("average".into(), json!(turns));
    }
    a.result.emit(doc)
}

fn run_accel(a: &AccelArgs) -> CliResult<()> {
    let opts = AccelOptions {
        scale_factor: scale_of(a.scale_factor)?,
        noise: noise_option(a.noise)?,
    };
    let t = Table::read(&a.input)?;
    let (cb, co) = (t.column("beta_deg")?, t.column("output")?);
    let mut obs = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        obs.push(AccelObservation {
            beta_rad: t.f64(row, cb)?.to_radians(),
            output: t.f64(row, co)?,
        });
    }
    let r = accel::calibrate(&obs, &opts).map_err(|e| in_file(&t.path, e))?;
    let mut doc = r.document(&opts).map_err(|e| in_file(&t.path, e))?;
    doc.inputs.push(t.input_file("input"));
    doc.options.insert("noise".into(), json!(a.noise));
    a.result.emit(doc)
}

/// Parse `A:B` (deg) configuration pairs.
fn parse_configs(list: &[String]) -> CliResult<Vec<GyroConfig>> {
    list.iter()
        .map(|p| {
            let bad = || {
                usage(format!(
                    "--configs: '{p}' is not ALPHA:BETA in degrees (e.g. 0:180)"
                ))
            };
            let (a, b) = p.split_once(':').ok_or_else(bad)?;
            let a: f64 = a.trim().parse().map_err(|_| bad())?;
            let b: f64 = b.trim().parse().map_err(|_| bad())?;
            if !(a.is_finite() && b.is_finite()) {
                return Err(bad());
            }
            Ok(GyroConfig::deg(a, b))
        })
        .collect()
}

fn finite_list(name: &str, v: &[f64]) -> CliResult<()> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(usage(format!("{name}: {x} is not a finite number"))),
        None if v.is_empty() => Err(usage(format!("{name}: empty list"))),
        None => Ok(()),
    }
}

const PAPER_CONFIGS: &str = "0:0,0:180,180:180,90:180,0:90";

/// Which instrument a plan is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Instrument {
    /// Gyro on a rate table.
    Gyro,
    /// Accelerometer on a vertical face.
    Accel,
}

/// Options of `incal plan misalign`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    /// Instrument of the plan.
    #[arg(long, value_enum, default_value = "gyro")]
    pub instrument: Instrument,
    /// Gyro: configurations ALPHA:BETA (deg), comma separated (default: the paper's five).
    #[arg(long, value_delimiter = ',', default_value = PAPER_CONFIGS)]
    pub configs: Vec<String>,
    /// Gyro: table rate magnitudes (deg/s), each run forward and reverse.
    #[arg(long, value_delimiter = ',', default_value = "20,30,40")]
    pub rates_deg_s: Vec<f64>,
    /// Gyro: fit one bias per configuration.
    #[arg(long)]
    pub per_config_bias: bool,
    /// Accelerometer: angles beta (deg), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,90,180,270",
        allow_hyphen_values = true
    )]
    pub betas_deg: Vec<f64>,
    /// Samples (rows: record means or single readings) per position.
    #[arg(long = "samples", visible_alias = "readings", default_value_t = 1)]
    pub readings: usize,
    /// Scale factor kI (gyro: output per deg/s; accelerometer: output per g).
    #[arg(long, visible_alias = "k1", allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Standard deviation of one reading (output units).
    #[arg(long)]
    pub noise: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal plan misalign`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let k = scale_of(a.scale_factor)?;
    if a.readings == 0 {
        return Err(usage("--samples must be at least 1"));
    }
    let p: Prediction = match a.instrument {
        Instrument::Gyro => {
            finite_list("--rates-deg-s", &a.rates_deg_s)?;
            let configs = parse_configs(&a.configs)?;
            predict_gyro(
                &configs,
                &a.rates_deg_s,
                a.readings,
                k,
                a.noise,
                a.per_config_bias,
            )
            .map_err(core)?
        }
        Instrument::Accel => {
            finite_list("--betas-deg", &a.betas_deg)?;
            let b: Vec<f64> = a.betas_deg.iter().map(|x| x.to_radians()).collect();
            predict_accel(&b, a.readings, k, a.noise).map_err(core)?
        }
    };
    if a.json {
        let mut u = Map::new();
        for (j, n) in p.angles.names().iter().enumerate() {
            u.insert(n.clone(), json!({"u": p.angles.u_at(j), "unit": "rad"}));
        }
        u.insert(
            "gamma".into(),
            json!({"u": p.u_gamma_max, "unit": "rad", "note": "worst direction"}),
        );
        let doc = json!({
            "instrument": match a.instrument { Instrument::Gyro => "gyro", Instrument::Accel => "accel" },
            "observations": p.n_obs,
            "parameters": p.n_params,
            "predicted_u": Value::Object(u),
        });
        return write_text(a.output.as_deref(), &json_text(&doc));
    }
    let mut s = format!(
        "Misalignment plan ({}): {} samples, {} terms, noise {} per sample, kI = {k}\n",
        match a.instrument {
            Instrument::Gyro => "gyro on a rate table",
            Instrument::Accel => "accelerometer on a vertical face",
        },
        p.n_obs,
        p.n_params,
        sig(a.noise, 3)
    );
    let mut rows: Vec<Vec<String>> = p
        .angles
        .names()
        .iter()
        .enumerate()
        .map(|(j, n)| {
            vec![
                n.clone(),
                format!("{:.3}", rad_to_arcsec(p.angles.u_at(j))),
                "arcsec".into(),
            ]
        })
        .collect();
    rows.push(vec![
        "gamma (worst direction)".into(),
        format!("{:.3}", rad_to_arcsec(p.u_gamma_max)),
        "arcsec".into(),
    ]);
    s.push_str(&table(&["angle", "predicted u", "unit"], &rows));
    write_text(a.output.as_deref(), &s)
}

/// Options of `incal simulate misalign gyro`.
#[derive(clap::Args, Debug)]
pub struct SimGyroArgs {
    /// Scale factor kI (output per deg/s).
    #[arg(long, default_value_t = -2.9222, allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Bias V0 (output).
    #[arg(long, default_value_t = 0.002, allow_hyphen_values = true)]
    pub bias: f64,
    /// Standard deviation of the bias shift per configuration (output).
    #[arg(long, default_value_t = 0.0)]
    pub bias_shift: f64,
    /// True table-face angle about x (arcsec).
    #[arg(long, default_value_t = 2.4, allow_hyphen_values = true)]
    pub dtheta_x0_arcsec: f64,
    /// True table-face angle about y (arcsec).
    #[arg(long, default_value_t = -7.5, allow_hyphen_values = true)]
    pub dtheta_y0_arcsec: f64,
    /// True fixture-face angle about y (arcsec).
    #[arg(long, default_value_t = -54.0, allow_hyphen_values = true)]
    pub dtheta_y1_arcsec: f64,
    /// True fixture-face angle about z (arcsec; second order, not estimable).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub dtheta_z1_arcsec: f64,
    /// True input-axis misalignment about y (arcsec).
    #[arg(long, default_value_t = -162.2, allow_hyphen_values = true)]
    pub dtheta_y2_arcsec: f64,
    /// True input-axis misalignment about z (arcsec).
    #[arg(long, default_value_t = 55.8, allow_hyphen_values = true)]
    pub dtheta_z2_arcsec: f64,
    /// Configurations ALPHA:BETA (deg), comma separated.
    #[arg(long, value_delimiter = ',', default_value = PAPER_CONFIGS)]
    pub configs: Vec<String>,
    /// Table rate magnitudes (deg/s); each is run forward then reverse.
    #[arg(long, value_delimiter = ',', default_value = "20,30,40")]
    pub rates_deg_s: Vec<f64>,
    /// Records per configuration and signed rate.
    #[arg(long, default_value_t = 2)]
    pub records: usize,
    /// Table revolutions per record (a non-whole number shows the Earth-rate error).
    #[arg(long, default_value_t = 1.0)]
    pub turns: f64,
    /// Samples per revolution.
    #[arg(long, default_value_t = 36)]
    pub samples_per_turn: usize,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 1e-3)]
    pub noise: f64,
    /// Latitude (deg), for the Earth rate.
    #[arg(long, default_value_t = 45.75, allow_hyphen_values = true, value_parser = crate::options::latitude_deg)]
    pub latitude_deg: f64,
    /// Write raw records (time_s, table_angle_deg per sample) instead of record means.
    #[arg(long)]
    pub time_series: bool,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

fn nonneg(name: &str, x: f64) -> CliResult<()> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(usage(format!(
            "{name} must be a non-negative number, got {x}"
        )))
    }
}

fn gyro_sim_of(a: &SimGyroArgs) -> CliResult<GyroSim> {
    nonneg("--noise", a.noise)?;
    nonneg("--bias-shift", a.bias_shift)?;
    finite_list("--rates-deg-s", &a.rates_deg_s)?;
    if a.rates_deg_s.iter().any(|r| *r <= 0.0) {
        return Err(usage("--rates-deg-s: rate magnitudes must be positive"));
    }
    if !(a.turns.is_finite() && a.turns > 0.0) {
        return Err(usage("--turns must be positive"));
    }
    if a.records == 0 || a.samples_per_turn < 2 {
        return Err(usage(
            "--records must be at least 1 and --samples-per-turn at least 2",
        ));
    }
    if a.turns > 1000.0 {
        return Err(usage(format!(
            "--turns must be at most 1000, got {}",
            crate::output::num(a.turns)
        )));
    }
    let configs = parse_configs(&a.configs)?;
    let rows_per_record = if a.time_series {
        (a.turns * a.samples_per_turn as f64).ceil()
    } else {
        1.0
    };
    crate::options::sim_size(&[
        ("configurations", configs.len() as f64),
        ("rates x 2 signs", 2.0 * a.rates_deg_s.len() as f64),
        ("--records", a.records as f64),
        ("samples per record", rows_per_record),
    ])?;
    for (n, v) in [
        ("--scale-factor", a.scale_factor),
        ("--bias", a.bias),
        ("--latitude-deg", a.latitude_deg),
        ("--dtheta-x0-arcsec", a.dtheta_x0_arcsec),
        ("--dtheta-y0-arcsec", a.dtheta_y0_arcsec),
        ("--dtheta-y1-arcsec", a.dtheta_y1_arcsec),
        ("--dtheta-z1-arcsec", a.dtheta_z1_arcsec),
        ("--dtheta-y2-arcsec", a.dtheta_y2_arcsec),
        ("--dtheta-z2-arcsec", a.dtheta_z2_arcsec),
    ] {
        if !v.is_finite() {
            return Err(usage(format!("{n} must be finite")));
        }
    }
    Ok(GyroSim {
        mounting: GyroMounting {
            dtheta_x0: arcsec_to_rad(a.dtheta_x0_arcsec),
            dtheta_y0: arcsec_to_rad(a.dtheta_y0_arcsec),
            dtheta_y1: arcsec_to_rad(a.dtheta_y1_arcsec),
            dtheta_z1: arcsec_to_rad(a.dtheta_z1_arcsec),
            dtheta_y2: arcsec_to_rad(a.dtheta_y2_arcsec),
            dtheta_z2: arcsec_to_rad(a.dtheta_z2_arcsec),
        },
        scale_factor: a.scale_factor,
        bias: a.bias,
        bias_shift: a.bias_shift,
        configs,
        rates_deg_s: a.rates_deg_s.clone(),
        records: a.records,
        turns: a.turns,
        samples_per_turn: a.samples_per_turn,
        noise: a.noise,
        latitude_rad: a.latitude_deg.to_radians(),
        seed: a.seed,
    })
}

/// Degrees printed to 1e-9 deg (round-trip exact for plan angles).
fn deg9(rad: f64) -> f64 {
    (rad_to_deg(rad) * 1e9).round() / 1e9
}

/// `incal simulate misalign gyro|accel`.
pub fn simulate(c: &SimCommand) -> CliResult<()> {
    match c {
        SimCommand::Gyro(a) => {
            let cfg = gyro_sim_of(a)?;
            let mut text = String::new();
            if a.time_series {
                text.push_str("alpha_deg,beta_deg,rate,time_s,table_angle_deg,output\n");
                for r in simulate_gyro_records(&cfg) {
                    for s in &r.samples {
                        text.push_str(&format!(
                            "{},{},{},{},{},{}\n",
                            deg9(r.config.alpha_rad),
                            deg9(r.config.beta_rad),
                            r.rate_deg_s,
                            s.time_s,
                            deg9(s.table_angle_rad),
                            crate::options::finite_output(s.output)?
                        ));
                    }
                }
            } else {
                text.push_str("alpha_deg,beta_deg,rate,output\n");
                for o in simulate_gyro(&cfg).map_err(core)? {
                    text.push_str(&format!(
                        "{},{},{},{}\n",
                        deg9(o.alpha_rad),
                        deg9(o.beta_rad),
                        o.rate_deg_s,
                        crate::options::finite_output(o.output)?
                    ));
                }
            }
            write_text(a.output.as_deref(), &text)
        }
        SimCommand::Accel(a) => {
            let cfg = accel_sim_of(a)?;
            let mut text = String::from("beta_deg,output\n");
            for o in simulate_accel(&cfg) {
                text.push_str(&format!(
                    "{},{}\n",
                    deg9(o.beta_rad),
                    crate::options::finite_output(o.output)?
                ));
            }
            write_text(a.output.as_deref(), &text)
        }
    }
}

/// Options of `incal simulate misalign accel`.
#[derive(clap::Args, Debug)]
pub struct SimAccelArgs {
    /// Scale factor kI (output per g).
    #[arg(long, default_value_t = 1.299, allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Bias V0 (output).
    #[arg(long, default_value_t = -0.002, allow_hyphen_values = true)]
    pub bias: f64,
    /// True verticality error of the face, about y (arcsec).
    #[arg(long, default_value_t = 30.0, allow_hyphen_values = true)]
    pub dtheta_y0_arcsec: f64,
    /// True input-axis misalignment about y (arcsec).
    #[arg(long, default_value_t = -5.3, allow_hyphen_values = true)]
    pub dtheta_y2_arcsec: f64,
    /// True input-axis misalignment about z (arcsec).
    #[arg(long, default_value_t = 20.5, allow_hyphen_values = true)]
    pub dtheta_z2_arcsec: f64,
    /// Angles beta (deg), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,90,180,270",
        allow_hyphen_values = true
    )]
    pub betas_deg: Vec<f64>,
    /// Samples per angle.
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

fn accel_sim_of(a: &SimAccelArgs) -> CliResult<AccelSim> {
    nonneg("--noise", a.noise)?;
    finite_list("--betas-deg", &a.betas_deg)?;
    for b in &a.betas_deg {
        crate::options::angle_deg("--betas-deg", *b)?;
    }
    if a.samples == 0 {
        return Err(usage("--samples must be at least 1"));
    }
    crate::options::sim_size(&[
        ("angles", a.betas_deg.len() as f64),
        ("--samples", a.samples as f64),
    ])?;
    for (n, v) in [
        ("--scale-factor", a.scale_factor),
        ("--bias", a.bias),
        ("--dtheta-y0-arcsec", a.dtheta_y0_arcsec),
        ("--dtheta-y2-arcsec", a.dtheta_y2_arcsec),
        ("--dtheta-z2-arcsec", a.dtheta_z2_arcsec),
    ] {
        if !v.is_finite() {
            return Err(usage(format!("{n} must be finite")));
        }
    }
    Ok(AccelSim {
        mounting: FaceMounting {
            dtheta_y0: arcsec_to_rad(a.dtheta_y0_arcsec),
            dtheta_y1: 0.0,
            dtheta_y2: arcsec_to_rad(a.dtheta_y2_arcsec),
            dtheta_z2: arcsec_to_rad(a.dtheta_z2_arcsec),
        },
        scale_factor: a.scale_factor,
        bias: a.bias,
        betas_rad: a.betas_deg.iter().map(|b| b.to_radians()).collect(),
        samples: a.samples,
        noise: a.noise,
        seed: a.seed,
    })
}
