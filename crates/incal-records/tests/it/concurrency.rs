//! Several writers at once: 8 threads, each with its own connection to one
//! store file, add records concurrently; nothing is lost, ids are 1..=N
//! without gaps and the hash chain verifies.

use crate::common;

use std::sync::{Arc, Barrier};

use common::{temp_dir, tumble_doc};
use incal_records::{NewRecord, Store};

#[test]
fn eight_concurrent_writers_lose_nothing() {
    const WRITERS: usize = 8;
    const EACH: usize = 10;
    let path = temp_dir("concurrent").join("incal.db");
    // Every writer opens the (not yet existing) store at the same moment:
    // creation and migration race too.
    let barrier = Arc::new(Barrier::new(WRITERS));
    let handles: Vec<_> = (0..WRITERS)
        .map(|w| {
            let path = path.clone();
            let barrier = Arc::clone(&barrier);
            std::thread::spawn(move || {
                barrier.wait();
                let mut s = Store::open(&path).unwrap();
                let serial = format!("SN-{w}");
                let mut ids = Vec::new();
                for k in 0..EACH {
                    let doc = tumble_doc(Some(&serial), 1e-3 + k as f64 * 1e-6, 1e-6, 30.0);
                    ids.push(s.add(&NewRecord::new(&doc)).unwrap().id);
                }
                ids
            })
        })
        .collect();
    let mut ids: Vec<i64> = handles
        .into_iter()
        .flat_map(|h| h.join().expect("a writer failed"))
        .collect();
    ids.sort_unstable();
    let n = (WRITERS * EACH) as i64;
    assert_eq!(ids, (1..=n).collect::<Vec<_>>(), "every add got its own id");
    let s = Store::open_existing(&path).unwrap();
    let list = s.list(None).unwrap();
    assert_eq!(list.len() as i64, n);
    for w in 0..WRITERS {
        let serial = format!("SN-{w}");
        assert_eq!(s.list(Some(&serial)).unwrap().len(), EACH, "{serial}");
        assert_eq!(s.history(&serial, "K0").unwrap().points.len(), EACH);
    }
    assert_eq!(s.verify().unwrap().records, n);
}
