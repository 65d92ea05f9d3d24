//! Time incal's deviation kernels on a raw f64le rate file, in the form
//! `scripts/bench-allantools.sh` compares with allantools:
//! `cargo run --release -p incal --example noise_timing -- FILE GRID`
//! (GRID `octave` or `all`); prints `name seconds` lines (best of 3).

use std::time::Instant;

use incal::noise::{dev, phase_from_rate, TauGrid};

/// A deviation kernel of `incal::noise::dev`.
type Kernel = fn(&[f64], usize, f64, bool) -> Option<dev::VarN>;

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
    let t = best(&mut || {
        dev::oavar_many(&x, &ms, 1.0, true)
            .iter()
            .flatten()
            .map(|v| v.var)
            .sum()
    });
    println!("oadev_fused {t:.6}");
    let t = best(&mut || {
        dev::ohvar_many(&x, &ms, 1.0, true)
            .iter()
            .flatten()
            .map(|v| v.var)
            .sum()
    });
    println!("ohdev_fused {t:.6}");
    let t = best(&mut || {
        dev::mvar_many(&x, &ms, 1.0, true)
            .iter()
            .flatten()
            .map(|v| v.var)
            .sum()
    });
    println!("mdev_fused {t:.6}");
    // TOTDEV with its interior from the OADEV sums (OADEV's work included).
    let t = best(&mut || {
        dev::oavar_totvar_many(&x, &ms, 1.0, true)
            .1
            .iter()
            .flatten()
            .map(|v| v.var)
            .sum()
    });
    println!("totdev_fused {t:.6}");
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
