//! Executions per second of every fuzz target, in process, on mutations
//! of its seed ([`incal_fuzz::mutate`]: a bit flipped, a cut, a token
//! spliced in), and the share accepted.
//!
//! * `cargo run --release -p incal-fuzz --example rate [SECONDS]`: each
//!   target for SECONDS (default 2).
//! * `cargo run --release -p incal-fuzz --example rate -- --executions N
//!   [TARGET…]`: N executions of each target (or of those named), the
//!   campaign recorded in the README (10⁶ per target).
//! * `... --executions N --from-chunk K TARGET`: the same campaign resumed
//!   at chunk K (executions 10⁴·K onwards, the same inputs as an unbroken
//!   run), for a long target run over several sittings.
//!
//! Any broken contract stops the run with the target, the execution and
//! the input's size (exit 1).

use std::time::Instant;

use incal_fuzz::{campaign, target_names};

/// The stream every campaign starts from (a campaign is reproducible).
const STREAM: u64 = 0x9E37_79B9_7F4A_7C15;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    println!(
        "{:<20} {:>10} {:>9} {:>10} {:>9}",
        "target", "execs", "seconds", "execs/s", "accepted"
    );
    if args.first().map(String::as_str) == Some("--executions") {
        let n: u64 = args
            .get(1)
            .and_then(|s| s.parse().ok())
            .expect("--executions N");
        let mut rest = &args[2..];
        let mut first_chunk = 0u64;
        if rest.first().map(String::as_str) == Some("--from-chunk") {
            first_chunk = rest
                .get(1)
                .and_then(|s| s.parse().ok())
                .expect("--from-chunk K");
            rest = &rest[2..];
        }
        let named: Vec<&str> = rest.iter().map(String::as_str).collect();
        for t in target_names() {
            if !named.is_empty() && !named.contains(&t) {
                continue;
            }
            // In chunks of 10⁴ (chunk k from stream STREAM + k), with the
            // running count on standard error, so a long campaign shows
            // where it is.
            let start = Instant::now();
            let (mut done, mut accepted, mut k) = (first_chunk * 10_000, 0u64, first_chunk);
            while done < n {
                let m = (n - done).min(10_000);
                match campaign(t, m, STREAM.wrapping_add(k)) {
                    Ok(c) => {
                        done += c.executions;
                        accepted += c.accepted;
                    }
                    Err(e) => {
                        eprintln!("{e} (chunk {k})");
                        std::process::exit(1);
                    }
                }
                k += 1;
                eprintln!(
                    "{t}: {done} executions, {:.0} s",
                    start.elapsed().as_secs_f64()
                );
            }
            // This sitting's executions (a resumed run counts from chunk K).
            report(t, done - first_chunk * 10_000, accepted, start);
        }
        return;
    }
    // Each target for SECONDS: the same campaign in chunks of 100 until
    // the time is up.
    let secs: f64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(2.0);
    for t in target_names() {
        let start = Instant::now();
        let (mut n, mut accepted, mut k) = (0u64, 0u64, 0u64);
        while start.elapsed().as_secs_f64() < secs {
            match campaign(t, 100, STREAM.wrapping_add(k)) {
                Ok(c) => {
                    n += c.executions;
                    accepted += c.accepted;
                }
                Err(e) => {
                    eprintln!("{e} (chunk {k})");
                    std::process::exit(1);
                }
            }
            k += 1;
        }
        report(t, n, accepted, start);
    }
}

fn report(t: &str, n: u64, accepted: u64, start: Instant) {
    let dt = start.elapsed().as_secs_f64();
    println!(
        "{t:<20} {n:>10} {dt:>9.0} {:>10.0} {:>8.0}%",
        n as f64 / dt,
        100.0 * accepted as f64 / n.max(1) as f64
    );
}
