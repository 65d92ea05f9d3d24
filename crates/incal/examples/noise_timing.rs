//! Time incal's deviation kernels on a raw f64le rate file, in the form
//! `scripts/bench-allantools.sh` compares with allantools:
//! `cargo run --release -p incal --example noise_timing -- FILE GRID`
//! (GRID `octave` or `all`); prints `name seconds` lines (best of 3).

use std::time::Instant;

use incal::noise::{dev, phase_from_rate, TauGrid};

/// A deviation kernel of `incal::noise::dev`.
type Kernel = fn(&[f64], usize, f64, bool) -> Option<dev::VarN>;

/// A kernel of `incal::noise::dev` over a whole grid of factors.
type Many = fn(&[f64], &[usize], f64, bool) -> Vec<Option<dev::VarN>>;

fn best(f: &mut dyn FnMut() -> f64) -> f64 {
    let mut t = f64::INFINITY;
    let mut sink = 0.0;
    for _ in 0..3 {
        let s = Instant::now();
        sink += f();
        t = t.min(s.elapsed().as_secs_f64());
    }
    assert!(sink.is_finite());
    t
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (path, grid) = (&args[1], args.get(2).map_or("octave", String::as_str));
    let bytes = std::fs::read(path).expect("read the file");
    let y: Vec<f64> = bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let x = phase_from_rate(&y, 1.0);
    let g = TauGrid::parse(grid).expect("octave or all");
    let ms = g.factors(x.len());
    let kernels: [(&str, Kernel); 4] = [
        ("oadev", dev::oavar),
        ("mdev", dev::mvar),
        ("ohdev", dev::ohvar),
        ("totdev", dev::totvar),
    ];
    // The kernels over the whole grid at once; TOTDEV with its interior
    // from the OADEV sums (OADEV's work included).
    let fused: [(&str, Many); 4] = [
        ("oadev_fused", dev::oavar_many),
        ("ohdev_fused", dev::ohvar_many),
        ("mdev_fused", dev::mvar_many),
        ("totdev_fused", |x, ms, t, p| {
            dev::oavar_totvar_many(x, ms, t, p).1
        }),
    ];
    for (name, f) in fused {
        let t = best(&mut || f(&x, &ms, 1.0, true).iter().flatten().map(|v| v.var).sum());
        println!("{name} {t:.6}");
    }
    for (name, k) in kernels {
        let t = best(&mut || {
            ms.iter()
                .filter_map(|&m| k(&x, m, 1.0, true))
                .map(|v| v.var)
                .sum()
        });
        println!("{name} {t:.6}");
    }
}
