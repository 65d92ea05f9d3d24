//! One module per subcommand family.

/// `model()` of a simulator's truth options: the tumble's and the
/// centrifuge's `TruthArgs` hold the same coefficients under the same
/// names, each with its own instrument as defaults. The accelerometer
/// model, misalignments from arcsec to rad, refused as a usage error
/// (`truth model: …`) on a non-finite value or K1 = 0.
macro_rules! truth_model {
    ($args:ty) => {
        impl $args {
            /// The truth model (fails on a non-finite value or K1 = 0).
            pub fn model(&self) -> crate::error::CliResult<incal::models::AccelerometerModel> {
                let m = incal::models::AccelerometerModel {
                    k0_g: self.k0_g,
                    k1_out_per_g: self.k1,
                    k2: self.k2,
                    k3: self.k3,
                    delta_o_rad: incal::units::arcsec_to_rad(self.delta_o_arcsec),
                    delta_p_rad: incal::units::arcsec_to_rad(self.delta_p_arcsec),
                    k_ip: self.k_ip,
                    k_io: self.k_io,
                    k_po: self.k_po,
                    k_pp: self.k_pp,
                    k_oo: self.k_oo,
                    k_oq: self.k_oq,
                };
                m.validate()
                    .map_err(|e| crate::error::usage(format!("truth model: {e}")))?;
                Ok(m)
            }
        }
    };
}
use truth_model;

pub mod batch;
pub mod centrifuge;
pub mod compare;
pub mod demo;
pub mod export;
pub mod gfimu;
pub mod gyro;
pub mod imu;
pub mod misalign;
pub mod noise;
pub mod procedures;
pub mod record;
pub mod report;
pub mod schema;
pub mod thermal;
pub mod tumble;
