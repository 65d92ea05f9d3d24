//! Reading a thermal ramp recording: its columns (`temperature_c`,
//! optional `chamber_c` and `time_s`, the channels) averaged in blocks as
//! the rows are read ([`super::ramp`] module docs).

use std::io::Read;

use super::ramp::RampOptions;
use crate::error::Result;

/// Columns that are never channels.
pub const NOT_CHANNELS: [&str; 4] = ["time_s", "temperature_c", "chamber_c", "humidity_pct"];

/// Welford accumulator of one channel in one block.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Acc {
    /// Samples.
    pub(crate) n: usize,
    /// Their mean.
    pub(crate) mean: f64,
    /// Sum of squared deviations from the mean.
    pub(crate) m2: f64,
}

impl Acc {
    fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }
}

/// One block of rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// `time_s` (or the row index over the rate), s.
    pub(crate) time: Acc,
    /// The sensor's `temperature_c`, °C.
    pub(crate) temp: Acc,
    /// The chamber's `chamber_c`, °C.
    pub(crate) chamber: Acc,
    /// Each channel.
    pub(crate) channels: Vec<Acc>,
}

/// A ramp recording as blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct RampInput {
    /// Channel names.
    pub names: Vec<String>,
    /// The blocks, in time order.
    pub blocks: Vec<Block>,
    /// True when the recording has `chamber_c`.
    pub has_chamber: bool,
    /// Per channel, the empty or NaN cells left out as missing samples.
    pub missing: Vec<usize>,
    /// The sample rate (Hz): as given, or the stamps' (rows − 1 over
    /// their span).
    pub rate_hz: f64,
}

/// `rate_hz` as given against the rate of the `time_s` stamps (rows − 1
/// over their span): more than 1 % apart is [`crate::Error::InvalidOption`]
/// on `rate_hz` (the blocks and the lag would be scaled wrong).
fn check_rate(rate_hz: f64, stamps_hz: f64) -> Result<()> {
    if (rate_hz / stamps_hz - 1.0).abs() > 0.01 {
        return crate::options::invalid(
            "rate_hz",
            format!(
                "{} Hz disagrees with the time_s stamps ({:.6} Hz from their span): give the recording's rate",
                crate::error::short_number(&rate_hz.to_string()),
                stamps_hz
            ),
        );
    }
    Ok(())
}

/// Rows per block at `rate_hz`.
fn block_rows(block_s: f64, rate_hz: f64) -> usize {
    ((block_s * rate_hz).round() as usize).max(2)
}

/// Read a ramp recording (module docs).
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>, o: &RampOptions) -> Result<RampInput> {
    let h = rows.header();
    let temp = h.column("temperature_c")?;
    let chamber = h.opt_column("chamber_c");
    let time = h.opt_column("time_s");
    let pick: Vec<usize> = if h.selected().is_empty() {
        (0..h.width())
            .filter(|&k| !NOT_CHANNELS.contains(&h.names()[k].as_str()))
            .collect()
    } else {
        h.selected()
            .iter()
            .copied()
            .filter(|&k| !NOT_CHANNELS.contains(&h.names()[k].as_str()))
            .collect()
    };
    if pick.is_empty() {
        return Err(h
            .error("no channel column besides time_s, temperature_c and chamber_c")
            .into());
    }
    let names: Vec<String> = pick.iter().map(|&k| h.names()[k].clone()).collect();
    // Blocks of a row count at a given rate; by time (block k holds the
    // stamps in [t0 + k block_s, t0 + (k+1) block_s)) when the stamps give it.
    let per = o.rate_hz.map(|r| block_rows(o.block_s, r));
    if per.is_none() && time.is_none() {
        return Err(crate::procedures::imu::input::no_rate(h));
    }
    let mut block_index = 0u64;
    let mut longest = 0usize;
    let mut blocks = Vec::new();
    let empty = Block {
        time: Acc::default(),
        temp: Acc::default(),
        chamber: Acc::default(),
        channels: vec![Acc::default(); pick.len()],
    };
    let mut cur = empty.clone();
    let mut index = 0usize;
    let mut in_block = 0usize;
    let mut last_t = f64::NEG_INFINITY;
    let mut first_t = f64::NAN;
    let mut missing = vec![0usize; pick.len()];
    while let Some(row) = rows.next_row()? {
        let t = match time {
            Some(c) => {
                let t = row.f64(c)?;
                if t <= last_t {
                    return Err(row
                        .cell_error(c, format!("time_s {t} does not increase (after {last_t})"))
                        .into());
                }
                last_t = t;
                if index == 0 {
                    first_t = t;
                }
                t
            }
            None => index as f64 / o.rate_hz.unwrap_or(f64::NAN),
        };
        if per.is_none() {
            let k = ((t - first_t) / o.block_s + 1e-9).floor() as u64;
            if k != block_index && in_block > 0 {
                longest = longest.max(in_block);
                blocks.push(std::mem::replace(&mut cur, empty.clone()));
                in_block = 0;
            }
            block_index = k;
        }
        index += 1;
        let tc = row.f64(temp)?;
        if !(-273.15..=1000.0).contains(&tc) {
            return Err(row
                .cell_error(temp, format!("{tc} is not a temperature in degC"))
                .into());
        }
        cur.time.push(t);
        cur.temp.push(tc);
        if let Some(c) = chamber {
            cur.chamber.push(row.f64(c)?);
        }
        for ((a, &k), gone) in cur.channels.iter_mut().zip(&pick).zip(&mut missing) {
            match row.f64_or_missing(k)? {
                Some(v) => a.push(v),
                None => *gone += 1,
            }
        }
        in_block += 1;
        if Some(in_block) == per {
            blocks.push(std::mem::replace(&mut cur, empty.clone()));
            in_block = 0;
        }
    }
    // A last block of at least half a block's rows is kept.
    let full = per.unwrap_or(longest.max(in_block));
    if in_block * 2 >= full {
        blocks.push(cur);
    }
    let stamps_hz = (time.is_some() && index > 1).then(|| (index - 1) as f64 / (last_t - first_t));
    let rate_hz = match (o.rate_hz, stamps_hz) {
        (Some(r), Some(s)) => {
            check_rate(r, s)?;
            r
        }
        (Some(r), None) => r,
        (None, Some(s)) => {
            super::ramp::check_block(o.block_s, s)?;
            s
        }
        (None, None) => {
            return Err(rows
                .header()
                .error("one row cannot give a sample rate: give --rate-hz")
                .into())
        }
    };
    Ok(RampInput {
        names,
        blocks,
        has_chamber: chamber.is_some(),
        missing,
        rate_hz,
    })
}
