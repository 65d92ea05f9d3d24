//! Executions per second of every fuzz target, in process, on mutations
//! of its seed (one byte flipped, a cut, a token spliced in), and the share
//! accepted: `cargo run --release -p incal-fuzz --example rate [SECONDS]`.
//! Any broken contract stops the run with the target and the input's size.

use std::time::{Duration, Instant};

use incal_fuzz::{check, run, seed, Outcome, TARGETS};

const TOKENS: &[&[u8]] = &[
    b"nan", b"inf", b"1e308", b"", b",", b"\n", b"-1", b"0", b"abc", b"\"",
];

/// xorshift64*: a fixed stream, so a run is reproducible.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn mutate(base: &[u8], r: &mut Rng) -> Vec<u8> {
    let mut v = base.to_vec();
    for _ in 0..1 + r.below(3) {
        let n = v.len().max(1);
        match r.below(3) {
            0 if !v.is_empty() => {
                let at = r.below(n);
                v[at] ^= 1 << r.below(8);
            }
            1 => v.truncate(r.below(n + 1)),
            _ => {
                let at = r.below(n).min(v.len());
                let end = (at + r.below(8)).min(v.len());
                let t = TOKENS[r.below(TOKENS.len())];
                v.splice(at..end, t.iter().copied());
            }
        }
    }
    v
}

fn main() {
    let secs: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.0);
    println!(
        "{:<20} {:>10} {:>10} {:>9}",
        "target", "execs", "execs/s", "accepted"
    );
    let mut r = Rng(0x9E37_79B9_7F4A_7C15);
    for (t, _) in TARGETS {
        let base = seed(t);
        let (mut n, mut accepted) = (0u64, 0u64);
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs_f64(secs) {
            let data = mutate(base, &mut r);
            if let Err(e) = check(t, &data) {
                eprintln!(
                    "{t}: contract broken on a {}-byte input: {e}\n{:?}\n{:?}",
                    data.len(),
                    String::from_utf8_lossy(&data),
                    run(t, &data)
                );
                std::process::exit(1);
            }
            if matches!(run(t, &data), Outcome::Accepted(_)) {
                accepted += 1;
            }
            n += 1;
        }
        let dt = start.elapsed().as_secs_f64();
        println!(
            "{t:<20} {n:>10} {:>10.0} {:>8.0}%",
            n as f64 / dt,
            100.0 * accepted as f64 / n.max(1) as f64
        );
    }
}
