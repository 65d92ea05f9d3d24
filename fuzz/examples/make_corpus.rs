//! Write every target's seed (a valid input from the simulators) to
//! `fuzz/corpus/<target>/seed`, the starting corpus of
//! `INCAL_FUZZ_TARGET=<target> cargo fuzz run target corpus/<target>`.

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus");
    for (t, what) in incal_fuzz::targets() {
        let dir = root.join(t);
        std::fs::create_dir_all(&dir).expect("corpus directory");
        std::fs::write(dir.join("seed"), incal_fuzz::seed(t)).expect("seed file");
        println!("{t}: {what}");
    }
}
