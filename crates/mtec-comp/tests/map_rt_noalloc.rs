//! The real-time path allocates nothing per call: a counting global allocator watches
//! `Compensator::correction_um` over many cycles.

use mtec_comp::map::{GridMap, Outside};
use mtec_comp::{Compensator, CorrectionOptions};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn correction_does_not_allocate() {
    let axes = [
        vec![0.0, 100.0, 200.0],
        vec![0.0, 50.0, 100.0],
        vec![-50.0, 0.0],
    ];
    let values: Vec<[f64; 3]> = (0..18)
        .map(|i| [i as f64, -(i as f64) * 0.5, 2.0])
        .collect();
    let map = GridMap::new(axes, values, Outside::Refuse, "rt test").unwrap();
    let comp = Compensator::new(Box::new(map), CorrectionOptions::default());
    let mut acc = 0.0;
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for i in 0..10_000 {
        // targets at least 1 mm inside the grid: with `refuse`, a target on the edge whose
        // corrected command falls outside is refused (see map docs)
        let t = [1.0 + (i % 198) as f64, 1.0 + (i % 98) as f64, -25.0];
        let c = comp.correction_um(t).unwrap();
        acc += c[0];
    }
    // error paths too: outside the grid (refuse) and too large
    let outside = comp.correction_um([500.0, 0.0, 0.0]);
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert!(outside.is_err());
    assert!(acc.is_finite());
    assert_eq!(after - before, 0, "allocations during 10 001 corrections");
}
