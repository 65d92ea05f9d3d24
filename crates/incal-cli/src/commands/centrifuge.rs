//! `incal centrifuge`, `incal plan centrifuge` and `incal simulate
//! centrifuge`: arguments into the core's options
//! ([`incal::procedures::centrifuge`]), results rendered.

use std::path::PathBuf;

use incal::estimation::Noise;
use incal::models::Term;
use incal::procedures::centrifuge::plan::CentrifugePlanOptions;
use incal::procedures::centrifuge::sim::{CentrifugeSimOptions, CentrifugeTruth, RigPlan};
use incal::procedures::centrifuge::{CentrifugeOptions, CentrifugeTest, ChainedResult};
use incal::procedures::{Plan, Silent};
use incal::units::STANDARD_GRAVITY_M_S2;

use crate::documents::read_document;
use crate::error::{core, usage, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

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
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal centrifuge`.
pub fn run(a: &Args) -> CliResult<()> {
    let terms = match &a.terms {
        None => None,
        Some(v) => Some(
            v.iter()
                .map(|s| Term::parse(s).map_err(|e| usage(format!("--terms: {e}"))))
                .collect::<CliResult<Vec<Term>>>()?,
        ),
    };
    let from = match &a.from {
        Some(p) => {
            let (name, sha256, document) = read_document(p)?;
            Some(ChainedResult {
                name,
                sha256,
                document,
            })
        }
        None => None,
    };
    let options = CentrifugeOptions {
        from,
        k0: a.k0,
        u_k0: a.u_k0,
        k1: a.k1,
        u_k1: a.u_k1,
        cov_k0_k1: None,
        radius_m: a.radius_m,
        latitude_deg: a.latitude_deg,
        gravity_m_s2: a.gravity_m_s2,
        opposite_sense: a.opposite_sense,
        order: a.order,
        alignment_tolerance_deg: a.alignment_tolerance_deg,
        noise: Noise::from_option(a.noise).map_err(core)?,
        terms,
        u_omega_ppm: a.u_omega_ppm,
    };
    crate::run::reduce::<CentrifugeTest>(&a.input, &a.read, &options, &a.result, &Silent)
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
    pub k0: f64,
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
    /// The truth as the core takes it.
    pub fn truth(&self) -> CentrifugeTruth {
        CentrifugeTruth {
            k0: self.k0,
            k1: self.k1,
            k2: self.k2,
            k3: self.k3,
            delta_o_arcsec: self.delta_o_arcsec,
            delta_p_arcsec: self.delta_p_arcsec,
            k_ip: self.k_ip,
            k_io: self.k_io,
            k_po: self.k_po,
            k_pp: self.k_pp,
            k_oo: self.k_oo,
            k_oq: self.k_oq,
        }
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
    pub gravity_m_s2: f64,
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

impl RigArgs {
    /// The core's rig and plan.
    fn rig(&self) -> RigPlan {
        RigPlan {
            r_plus_m: self.r_plus_m,
            r_minus_m: self.r_minus_m,
            radius_m: self.radius_m,
            tilt_arcsec: self.tilt_arcsec,
            latitude_deg: self.latitude_deg,
            gravity_m_s2: self.gravity_m_s2,
            opposite_sense: self.opposite_sense,
            positions: self.positions.clone(),
            single_polarity: self.single_polarity,
            levels_g: self.levels_g.clone(),
            samples: self.samples,
            noise: self.noise,
        }
    }
}

/// `incal simulate centrifuge`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let options = CentrifugeSimOptions {
        truth: a.truth.truth(),
        rig: a.rig.rig(),
        seed: a.seed,
    };
    crate::run::simulate::<CentrifugeTest>(&options, a.output.as_deref())
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
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan centrifuge`: the predicted u of every coefficient and radius
/// quantity for a station/speed plan (the reduction run on noise-free
/// outputs with an exact scatter of `--noise`).
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let options = CentrifugePlanOptions {
        truth: a.truth.truth(),
        rig: a.rig.rig(),
        u_k0: a.u_k0,
        u_k1: a.u_k1,
        order: a.order,
        alignment_tolerance_deg: a.alignment_tolerance_deg,
        u_omega_ppm: a.u_omega_ppm,
    };
    let doc = <CentrifugeTest as Plan>::plan(&options).map_err(core)?;
    a.out.emit(&doc)
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(clap::Subcommand, Debug)]
pub enum Reductions {
    /// Calibrate an accelerometer on a precision centrifuge: radius, K2/K3, cross-axis and cross-coupling terms (He & Yin 2017; IEEE Std 836).
    Centrifuge(Args),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Centrifuge(a) => run(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(clap::Subcommand, Debug)]
pub enum Plans {
    /// Centrifuge plan: predicted u of the radius quantities and of every coefficient for a station/speed plan.
    Centrifuge(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Centrifuge(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(clap::Subcommand, Debug)]
pub enum Simulations {
    /// Precision centrifuge test (IA, PA, OA radial and 45-degree cross positions).
    Centrifuge(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Centrifuge(a) => simulate(a),
        }
    }
}
