//! Cost of one training batch of the source-sized CNN-LSTM (issue 22, build 5): forward and
//! backward pass of 64 windows (W 16, F 15 = 9 temperatures + 3 angle harmonics as cos/sin,
//! Conv1d 16×3, LSTM 32, 5 outputs) with the hand-written kernel, plus the Adam step; and the
//! forward pass alone. About 115 MFLOP per forward+backward batch (see docs/methods.md).

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use mtec_nn::cnn_lstm_kernel::{Adam, Dims, Params, Workspace, PARAM_NAMES};
use std::collections::BTreeMap;

fn bench(c: &mut Criterion) {
    let dims = Dims {
        window: 16,
        features: 15,
        channels: 16,
        kernel: 3,
        hidden: 32,
        outputs: 5,
    };
    let n = 64;
    // deterministic pseudo-random values in [−0.3, 0.3] (a Weyl sequence: no RNG needed)
    let wave = |k: usize| ((k as f64 * 0.618_034).fract() - 0.5) as f32 * 0.6;
    let mut named = BTreeMap::new();
    let mut k = 0;
    for (name, shape) in PARAM_NAMES.iter().zip(dims.param_shapes()) {
        let len: usize = shape.iter().product();
        named.insert(*name, (k..k + len).map(wave).collect::<Vec<f32>>());
        k += len;
    }
    let mut p = Params::<f32>::from_named(dims, |n| named.get(n).map(|v| v.as_slice())).unwrap();
    let x: Vec<f32> = (0..n * 16 * 15).map(|i| 5.0 * wave(i + 7)).collect();
    let y: Vec<f32> = (0..n * 5).map(|i| 3.0 * wave(i + 11)).collect();
    let mut ws = Workspace::<f32>::new(dims, n);
    let mut adam = Adam::<f32>::new(p.values.len(), 0.0);
    c.bench_function("cnn_lstm_batch64_forward_backward_adam", |b| {
        b.iter(|| {
            let loss = ws.loss_and_grad(&p, black_box(&x), &y);
            adam.step(&mut p.values, &ws.grad, 1e-6);
            black_box(loss)
        })
    });
    c.bench_function("cnn_lstm_batch64_forward", |b| {
        b.iter(|| black_box(ws.forward(&p, black_box(&x))[0]))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
