//! `incal tumble`, `incal plan tumble`, `incal simulate tumble`.

use std::path::PathBuf;

use clap::ValueEnum;
use incal::estimation::Noise;
use incal::models::Term;
use incal::procedures::tumble::plan::{TumblePlanChoice, TumblePlanOptions};
use incal::procedures::tumble::sim::{TumbleSimOptions, TumbleTruth};
use incal::procedures::tumble::{default_terms, Tumble, TumbleOptions};
use incal::procedures::{Plan, Silent};
use incal::rigs::Mount;

use crate::error::{core, usage, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

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
    /// Input CSV with columns angle_deg and output (optional: pass; others ignored); - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Terms to fit, comma separated (default: K0,K1,K2,K3 and the mount's misalignment and cross-coupling).
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
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

/// `incal tumble`.
pub fn run(a: &Args) -> CliResult<()> {
    let mount: Mount = a.mount.into();
    let options = TumbleOptions {
        mount,
        terms: parse_terms(&a.terms, mount)?,
        noise: Noise::from_option(a.noise).map_err(core)?,
    };
    crate::run::reduce::<Tumble>(&a.input, &a.read, &options, &a.result, &Silent)
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
    /// The plan choice as the core takes it.
    pub fn choice(&self) -> TumblePlanChoice {
        TumblePlanChoice {
            range_g: self.range_g,
            step_deg: self.step_deg,
            points: self.points,
            angles_deg: self.angles_deg.clone(),
            step_resolution_deg: Some(self.step_resolution_deg),
        }
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
    /// Standard deviation of one output sample (output units), needed for the prediction.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Samples averaged per position (the position mean has noise/sqrt(samples)).
    #[arg(long, default_value_t = 1)]
    pub samples: usize,
    /// Standard deviation of the head's index-angle error (arcsec), added as output noise K1·cosθ·ε.
    #[arg(long, default_value_t = 0.0)]
    pub index_error_arcsec: f64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan tumble`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let mount: Mount = a.mount.into();
    let options = TumblePlanOptions {
        choice: a.plan.choice(),
        mount,
        terms: parse_terms(&a.terms, mount)?,
        k1: a.k1,
        noise: a.noise,
        samples: a.samples,
        index_error_arcsec: a.index_error_arcsec,
    };
    let doc = <Tumble as Plan>::plan(&options).map_err(core)?;
    a.out.emit(&doc)
}

/// Truth coefficients for simulators (default: the instrument of Wu et al. 2015).
#[derive(clap::Args, Debug, Clone)]
pub struct TruthArgs {
    /// Bias K0 (g).
    #[arg(long = "k0", visible_alias = "k0-g", default_value_t = 8e-3)]
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
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate tumble`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let t = &a.truth;
    let options = TumbleSimOptions {
        mount: a.mount.into(),
        plan: a.plan.choice(),
        truth: TumbleTruth {
            k0_g: t.k0_g,
            k1: t.k1,
            k2: t.k2,
            k3: t.k3,
            delta_o_arcsec: t.delta_o_arcsec,
            delta_p_arcsec: t.delta_p_arcsec,
            k_ip: t.k_ip,
            k_io: t.k_io,
            k_po: t.k_po,
            k_pp: t.k_pp,
            k_oo: t.k_oo,
            k_oq: t.k_oq,
        },
        samples: a.samples,
        noise: a.noise,
        index_error_arcsec: a.index_error_arcsec,
        passes: a.passes,
        seed: a.seed,
    };
    crate::run::simulate::<Tumble>(&options, a.output.as_deref())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(clap::Subcommand, Debug)]
pub enum Reductions {
    /// Calibrate an accelerometer from a dividing-head tumble test (Wu et al. 2015; GJB 1037A).
    Tumble(Args),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Tumble(a) => run(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(clap::Subcommand, Debug)]
pub enum Plans {
    /// Tumble plan: GJB 12-point, small-angle 12-point for a range, or N-point.
    Tumble(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Tumble(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(clap::Subcommand, Debug)]
pub enum Simulations {
    /// Dividing-head tumble test.
    Tumble(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Tumble(a) => simulate(a),
        }
    }
}
