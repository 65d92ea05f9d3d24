//! Spectral estimates shared by the procedures: Welch's averaged
//! periodograms of one or two channels ([`welch`]) and the power spectral
//! density of a noise record with its χ² bounds ([`psd`]) and the lines
//! standing above its noise floor ([`tones`]).

pub mod psd;
pub mod tones;
pub mod welch;
