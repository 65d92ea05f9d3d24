//! Samples at a converter's rail: clipped.
//!
//! A channel whose converter runs out of range reads its largest or
//! smallest code for as long as the input stays beyond it (a 16-bit gyro
//! at −32768 through a fast rotation). Those samples are not what the
//! sensor sensed, and a rotation integrated over them is wrong. The
//! reader names them for every procedure ([`Clipped`], the `clipped`
//! warning of the result).
//!
//! # Rule
//! A numeric cell is *at a rail* when its value is an integer converter's
//! end for 12, 14, 16, 18, 20, 24 or 32 bits (`−2^(b−1)`, `2^(b−1) − 1`,
//! `2^b − 1`: −32768, 32767, 65535, …) or, with `--full-scale X`
//! ([`crate::ReadOptions::full_scale`]), when `|value| ≥ X`. Two or more
//! consecutive rows of one column at the same rail are clipped, when the
//! rail is also the column's extreme (a 16-bit unsigned channel near its
//! mid-scale 32767 with values above it is not at a rail), and when the
//! column holds another value too (a column always at 65535 is a status
//! word). Beyond `--full-scale` a run is at the rail of its sign (`±X`),
//! whatever values it prints. `time_s` and the environmental columns are
//! not watched. Narrower ends (255,
//! 1023) are not rails here: they are ordinary angles and counts.

use super::{parse_f64, Header};

/// Converter widths whose ends are rails.
const BITS: [u32; 7] = [12, 14, 16, 18, 20, 24, 32];
/// Runs listed per column and rail (the rest counted).
const LISTED: usize = 5;

/// One column's samples at one rail.
#[derive(Debug, Clone, PartialEq)]
pub struct Clipped {
    /// The column (incal's name).
    pub column: String,
    /// The rail's value.
    pub value: f64,
    /// Runs of two or more consecutive rows at it.
    pub runs: usize,
    /// Samples in those runs.
    pub samples: usize,
    /// The first runs' file lines (first, last), at most five.
    pub lines: Vec<(usize, usize)>,
}

/// Is `v` at a rail (module docs)?
pub fn at_rail(v: f64, full_scale: Option<f64>) -> bool {
    if let Some(fs) = full_scale {
        if v.abs() >= fs {
            return true;
        }
    }
    if v.fract() != 0.0 || v.abs() < 2047.0 {
        return false;
    }
    BITS.iter().any(|&b| {
        let half = 2f64.powi(b as i32 - 1);
        v == -half || v == half - 1.0 || v == 2.0 * half - 1.0
    })
}

/// The rails of one channel held in memory: its smallest and largest
/// values that are at a rail ([`at_rail`], no full scale) — the extremes
/// a clipped channel piles up at.
pub fn extreme_rails(x: impl Iterator<Item = f64>) -> Vec<f64> {
    let (lo, hi) = x.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    [lo, hi].into_iter().filter(|&r| at_rail(r, None)).collect()
}

/// The samples of `x` that sit at one of `rails` in a run of two or more
/// (the input layer's `clipped` rule, for a channel held in memory).
pub fn rail_runs(x: &[f64], rails: &[f64]) -> Vec<bool> {
    let at = |j: usize| x.get(j).is_some_and(|v| rails.contains(v));
    (0..x.len())
        .map(|i| at(i) && (at(i + 1) || (i > 0 && at(i - 1))))
        .collect()
}

/// Could the text be a rail's value? A cheap test before parsing: an
/// integer part of at least four digits (rails are ≥ 2047 in magnitude).
fn may_be_rail(bytes: &[u8]) -> bool {
    let digits = bytes
        .strip_prefix(b"-")
        .or_else(|| bytes.strip_prefix(b"+"))
        .unwrap_or(bytes);
    let int = digits.iter().take_while(|c| c.is_ascii_digit()).count();
    int >= 4 && !digits.iter().any(|&c| c == b'e' || c == b'E')
}

/// The run being followed in one column.
#[derive(Debug, Clone, Default)]
pub(super) struct Watch {
    col: usize,
    current: Option<(f64, usize, usize, usize)>, // value, first line, last line, samples
    found: Vec<Clipped>,
    /// Extremes of the values parsed (every value of magnitude ≥ 1000).
    min: f64,
    max: f64,
    /// A value not at a rail was seen (a column always at one rail is a
    /// status word or a dead channel, not a clipped one).
    other: bool,
}

impl Watch {
    /// One watch per numeric column of `header` but `time_s` and the
    /// environmental columns.
    pub(super) fn columns(header: &Header) -> Vec<Watch> {
        (0..header.width())
            .filter(|&k| {
                let n = header.names()[k].as_str();
                n != "time_s" && !super::CONDITION_COLUMNS.contains(&n)
            })
            .map(|col| Watch {
                col,
                min: f64::INFINITY,
                max: f64::NEG_INFINITY,
                ..Watch::default()
            })
            .collect()
    }

    /// The cell of this row (its bytes; `numeric`: binary64 bytes).
    pub(super) fn push(&mut self, bytes: &[u8], numeric: bool, line: usize, fs: Option<f64>) {
        let value = if numeric {
            Some(super::frames::decode(bytes))
        } else if fs.is_some() || may_be_rail(bytes) {
            parse_f64(bytes)
        } else {
            None
        };
        if let Some(v) = value {
            self.min = self.min.min(v);
            self.max = self.max.max(v);
        }
        // Beyond a full scale given, a run is at the rail of its sign
        // (±full scale), whatever value the converter printed.
        let rail = value.filter(|v| at_rail(*v, fs)).map(|v| match fs {
            Some(fs) if v.abs() >= fs => fs.copysign(v),
            _ => v,
        });
        if rail.is_none() && !bytes.is_empty() {
            self.other = true;
        }
        match rail {
            Some(v) => match &mut self.current {
                Some((w, _, last, n)) if *w == v => {
                    *last = line;
                    *n += 1;
                }
                _ => {
                    self.close();
                    self.current = Some((v, line, line, 1));
                }
            },
            None => self.close(),
        }
    }

    fn close(&mut self) {
        let Some((v, first, last, n)) = self.current.take() else {
            return;
        };
        if n < 2 {
            return;
        }
        match self.found.iter_mut().find(|c| c.value == v) {
            Some(c) => {
                c.runs += 1;
                c.samples += n;
                if c.lines.len() < LISTED {
                    c.lines.push((first, last));
                }
            }
            None => self.found.push(Clipped {
                column: String::new(),
                value: v,
                runs: 1,
                samples: n,
                lines: vec![(first, last)],
            }),
        }
    }

    /// The column watched.
    pub(super) fn col(&self) -> usize {
        self.col
    }

    /// What was found, named.
    pub(super) fn finish(mut self, header: &Header, fs: Option<f64>) -> Vec<Clipped> {
        self.close();
        let name = &header.names()[self.col];
        let (min, max, other) = (self.min, self.max, self.other);
        self.found
            .into_iter()
            .filter(|c| {
                let varies = other || min < max;
                varies
                    && (fs.is_some_and(|fs| c.value.abs() >= fs)
                        || (c.value > 0.0 && c.value >= max)
                        || (c.value < 0.0 && c.value <= min))
            })
            .map(|mut c| {
                c.column = name.clone();
                c
            })
            .collect()
    }
}
