//! A noise channel with gaps: its contiguous stretches, each analysed on
//! its own and pooled.

use super::*;

/// The contiguous stretches of a channel with gaps: split at every gap of
/// the stamps (`gaps`: index of the first sample after it) and around
/// every missing sample (`NaN`); as ranges of sample indices.
pub(crate) fn stretches(col: &[f64], gaps: &[(usize, usize)]) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut start = None;
    let mut next_gap = gaps.iter().map(|g| g.0).peekable();
    for (i, v) in col.iter().enumerate() {
        let at_gap = next_gap.peek() == Some(&i);
        if at_gap {
            next_gap.next();
        }
        if at_gap || v.is_nan() {
            if let Some(s) = start.take() {
                out.push(s..i);
            }
        }
        if !v.is_nan() && start.is_none() {
            start = Some(i);
        }
    }
    if let Some(s) = start {
        out.push(s..col.len());
    }
    out
}

/// One channel with gaps: each stretch of at least `o.min_samples()`
/// samples analysed on its own and pooled ([`crate::noise::stability_segments`]),
/// the term fit on the pooled deviations, bias stability on the stretches'
/// τ-averages. `samples` counts the samples analysed.
pub(super) fn gapped(
    name: &str,
    col: &[f64],
    gaps: &[(usize, usize)],
    build: Build,
    opts: &StabilityOptions,
    o: &NoiseOptions,
    tick: &(dyn Fn(usize) + Sync),
) -> Result<ChannelResult> {
    let factor = build.factor;
    let parts = stretches(col, gaps);
    let longest = parts.iter().map(|r| r.len()).max().unwrap_or(0);
    if longest < o.min_samples() {
        return Err(Error::Unsupported(format!(
            "the longest stretch between gaps and missing samples has {longest} samples; at least {} are needed for one averaging time",
            o.min_samples()
        )));
    }
    let xs: Vec<Vec<f64>> = parts
        .into_iter()
        .filter(|r| r.len() >= o.min_samples())
        .map(|r| build.whole(r.len(), |i| col[r.start + i] * factor))
        .collect();
    if xs.len() > MAX_STRETCHES {
        return Err(Error::Unsupported(format!(
            "{} stretches between gaps: gap-aware estimation is limited to {MAX_STRETCHES}; the record is too fragmented to analyse",
            xs.len()
        )));
    }
    let st = crate::noise::stability_segments(&xs, opts, tick)?;
    let n_phase: usize = xs.iter().map(Vec::len).sum();
    let fit = terms::fit_terms(&st.taus_s, &st.oadev, &st.alpha, build.tau0, n_phase)?;
    let slope = terms::slope_readings(&st.taus_s, &st.oadev);
    let parts: Vec<&[f64]> = xs.iter().map(Vec::as_slice).collect();
    let bias_stability = o
        .stability_tau_s
        .iter()
        .map(|&t| {
            let b = terms::bias_stability_segments(&parts, build.tau0, t);
            (t, b.map(|b| terms::with_model_dof(b, &fit, build.tau0, t)))
        })
        .collect();
    let gauss_markov = o.markov.compute(&st, build.tau0);
    // The spectrum of the longest stretch (Welch's segments need no gap).
    let spectrum = match xs.iter().max_by_key(|x| x.len()) {
        Some(x) => o.spectrum.compute(x, build.tau0)?.map(|mut s| {
            s.note = Some(format!(
                "the longest of {} stretches between gaps ({} samples)",
                xs.len(),
                x.len().saturating_sub(1)
            ));
            s
        }),
        None => None,
    };
    // The dynamic Allan variance of the longest stretch (its windows need
    // no gap).
    let davar = match xs.iter().max_by_key(|x| x.len()) {
        Some(x) => o
            .davar
            .compute(x, build.tau0, &st, o.confidence, o.parallel)?
            .map(|mut d| {
                d.note = Some(format!(
                    "the longest of {} stretches between gaps ({} samples)",
                    xs.len(),
                    x.len().saturating_sub(1)
                ));
                d
            }),
        None => None,
    };
    Ok(ChannelResult {
        name: name.to_string(),
        samples: n_phase - xs.len() * usize::from(build.rate),
        stability: st,
        fit,
        slope,
        bias_stability,
        more: Vec::new(),
        to_input: 1.0 / factor,
        gauss_markov,
        spectrum,
        davar,
        temperature: None,
    })
}

/// The most stretches between gaps a channel is analysed in (each is a
/// full analysis of its own; beyond this the record is a scatter of
/// samples, not a stability record).
pub const MAX_STRETCHES: usize = 10_000;
