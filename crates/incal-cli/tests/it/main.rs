//! Every integration test of `incal-cli` in one binary (one link instead of
//! one per file); each file is a module. The statistical tier runs with
//! `INCAL_TESTS=full` (see `incal::sim::tier`).

mod centrifuge_cli;
mod cli_manners;
mod common;
mod fixture_units_cli;
mod gfimu_cli;
mod gyro_cli;
mod hardening;
mod hardening3;
mod imu_cli;
mod limits_cli;
mod mag_cli;
mod misalign_cli;
mod monte_carlo_cli;
mod noise_cli;
mod noise_davar_cli;
mod noise_preprocess_cli;
mod noise_temperature_cli;
mod noise_tones_cli;
mod one_reader;
mod record_cli;
mod recordings_cli;
mod registry;
mod repeatability_cli;
mod report_cli;
mod response_cli;
mod result_document;
mod rig_logs_cli;
mod robot_logs_cli;
mod segments_cli;
mod sensitivity_cli;
mod stacks_cli;
mod thermal_cli;
mod threshold_cli;
mod tumble_cli;
mod typed;
mod warmup_cli;
