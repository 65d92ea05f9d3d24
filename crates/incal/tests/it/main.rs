//! Every integration test of `incal` in one binary (one link instead of
//! one per file); each file is a module. The statistical tier runs with
//! `INCAL_TESTS=full` (see `incal::sim::tier`).

mod centrifuge_clip;
mod centrifuge_covariance;
mod centrifuge_mc;
mod centrifuge_roundtrip;
mod columns_in_memory;
mod gfimu_note;
mod gfimu_plan;
mod gfimu_roundtrip;
mod gfimu_solve_long;
mod gyro_range;
mod gyro_roundtrip;
mod he2017;
mod imu_ferraris_imucal;
mod imu_roundtrip;
mod imu_tedaldi_reference;
mod imu_tk_recordings;
mod li2012;
mod mag;
mod misalign_roundtrip;
mod montecarlo;
mod noise_davar;
mod noise_markov;
mod noise_psd;
mod noise_reference;
mod noise_roundtrip;
mod noise_stable32;
mod noise_temperature;
mod noise_tones;
mod properties;
mod repeatability;
mod response_broadband;
mod response_excitation;
mod response_found;
mod response_roundtrip;
mod response_step;
mod schema_file;
mod sensitivity;
mod sim_plan;
mod thermal_roundtrip;
mod threshold;
mod tumble_roundtrip;
mod warmup;
mod wu2015;
