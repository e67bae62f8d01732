//! CPU cost of one volumetric evaluation of the XYFZ machine with 21 elements, measured as the
//! process's CPU time over many calls (robust on a loaded machine, unlike wall time):
//!   cargo build --release -p mtec-model --example eval_cost
//!   /usr/bin/time -f "%U s user" target/release/examples/eval_cost first 10000000

use mtec_model::*;
use std::hint::black_box;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let form = args.get(1).map(String::as_str).unwrap_or("first");
    let n: usize = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000_000);
    let mut set = ErrorSet::new("cost");
    for (i, e) in three_axis_elements().into_iter().enumerate() {
        let f = if e.location {
            ErrorFunction::constant(20.0)
        } else {
            ErrorFunction::polynomial(vec![0.0, 1e-2 * (i as f64 + 1.0), 1e-5, -1e-8])
        };
        set.insert(e, f);
    }
    let vm = VolumetricModel::new(&Machine::vmc_xyfz(100.0), &set);
    let (f, o) = match form {
        "exact" => (Formalism::Htm, Order::Exact),
        "poe" => (Formalism::Poe, Order::FirstOrder),
        _ => (Formalism::Htm, Order::FirstOrder),
    };
    let mut acc = 0.0;
    for k in 0..n {
        let q = [(k % 600) as f64, (k % 800) as f64, (k % 300) as f64];
        acc += vm.error(black_box(&q), f, o).position_um[0];
    }
    println!("{form}: {n} evaluations, checksum {acc:.3}");
}
