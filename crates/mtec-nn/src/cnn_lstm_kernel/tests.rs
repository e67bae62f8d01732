//! The kernel against candle (forward, autograd gradients, AdamW step) and against central
//! finite differences in f64.

use super::*;
use crate::cnn_lstm::{Architecture, Net};
use crate::rng;
use candle_core::{Device, Tensor, Var, D};
use candle_nn::optim::{AdamW, Optimizer as _, ParamsAdamW};
use std::collections::BTreeMap;

fn dims(features: usize) -> Dims {
    Dims {
        window: 5,
        features,
        channels: 4,
        kernel: 3,
        hidden: 6,
        outputs: 3,
    }
}

/// Random weights (PyTorch-style bounds, scaled up so the gates leave their linear range),
/// windows and targets; the tensors by name as f32.
fn random_case(dm: Dims, n: usize, seed: u64) -> (BTreeMap<String, Vec<f32>>, Vec<f32>, Vec<f32>) {
    let mut r = rng::seeded(seed);
    let mut named = BTreeMap::new();
    for (name, shape) in PARAM_NAMES.iter().zip(dm.param_shapes()) {
        let len = shape.iter().product();
        let v = rng::uniform(&mut r, len, 0.8);
        named.insert(name.to_string(), v.iter().map(|v| *v as f32).collect());
    }
    let x = rng::uniform(&mut r, n * dm.window * dm.features, 2.0);
    let y = rng::uniform(&mut r, n * dm.outputs, 1.0);
    let f32s = |v: Vec<f64>| v.into_iter().map(|v| v as f32).collect();
    (named, f32s(x), f32s(y))
}

fn params<T: Real>(dm: Dims, named: &BTreeMap<String, Vec<f32>>) -> Params<T> {
    Params::from_named(dm, |k| named.get(k).map(|v| v.as_slice())).unwrap()
}

fn candle_net(dm: Dims, named: &BTreeMap<String, Vec<f32>>) -> (Net, BTreeMap<String, Var>) {
    let dev = Device::Cpu;
    let mut vars = BTreeMap::new();
    for (name, shape) in PARAM_NAMES.iter().zip(dm.param_shapes()) {
        let t = Tensor::from_slice(&named[*name], shape, &dev).unwrap();
        vars.insert(name.to_string(), Var::from_tensor(&t).unwrap());
    }
    let arch = Architecture {
        window: dm.window,
        conv_channels: dm.channels,
        kernel: dm.kernel,
        lstm_hidden: dm.hidden,
    };
    let p = vars
        .iter()
        .map(|(k, v)| (k.clone(), v.as_tensor().clone()))
        .collect();
    (Net::new(arch, p), vars)
}

/// The network in candle from ops whose autograd is right: the convolution as im2col and a
/// matmul, the pooling as a max over pairs. (candle 0.11's own `conv1d` gradient of the kernel is
/// wrong on the CPU when the kernel is not contiguous, which its backward pass makes it, and its
/// `max_pool2d` gradient is halved, and misplaced for an odd width; the training before this
/// kernel used those: module docs.)
fn reference_forward(dm: Dims, net: &Net, vars: &BTreeMap<String, Var>, x: &Tensor) -> Tensor {
    let (n, w, f) = x.dims3().unwrap();
    let (c, k, pad, pl) = (dm.channels, dm.kernel, dm.kernel / 2, dm.pooled());
    let v = |name: &str| vars[name].as_tensor();
    let rows = x.reshape((n * w, f)).unwrap();
    let zeros = Tensor::zeros((n * w, pad), x.dtype(), x.device()).unwrap();
    let padded = Tensor::cat(&[&zeros, &rows, &zeros], 1).unwrap();
    let cols: Vec<Tensor> = (0..k).map(|q| padded.narrow(1, q, f).unwrap()).collect();
    let cols = Tensor::stack(&cols, 2)
        .unwrap()
        .reshape((n * w * f, k))
        .unwrap();
    let z = cols
        .matmul(&v("conv.weight").reshape((c, k)).unwrap().t().unwrap())
        .unwrap();
    let z = (z.reshape((n * w, f, c)).unwrap().transpose(1, 2).unwrap())
        .broadcast_add(&v("conv.bias").reshape((1, c, 1)).unwrap())
        .unwrap()
        .relu()
        .unwrap();
    let pairs = z.narrow(2, 0, 2 * pl).unwrap().contiguous().unwrap();
    let s = pairs
        .reshape((n * w, c, pl, 2))
        .unwrap()
        .max(D::Minus1)
        .unwrap();
    net.lstm_head(&s.reshape((n * w, c * pl)).unwrap(), n, w)
        .unwrap()
}

/// max |a − b| / max |b|
fn rel(a: &[f32], b: &[f32]) -> f64 {
    let d = a
        .iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    let s = b.iter().map(|b| b.abs()).fold(0.0f32, f32::max);
    (d / s.max(f32::MIN_POSITIVE)) as f64
}

#[test]
fn forward_equals_candle() {
    for features in [10, 11] {
        let dm = dims(features);
        let n = 7;
        let (named, x, _) = random_case(dm, n, 3);
        let mut ws = Workspace::new(dm, n);
        let y = ws.forward(&params::<f32>(dm, &named), &x).to_vec();
        let (net, _) = candle_net(dm, &named);
        let xt = Tensor::from_slice(&x, (n, dm.window, features), &Device::Cpu).unwrap();
        let yc: Vec<f32> = net
            .forward(&xt)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        let e = rel(&y, &yc);
        eprintln!("F = {features}: forward max relative difference {e:.2e}");
        assert!(e < 1e-5, "F = {features}: {e}");
        // the same windows in a larger workspace and after another batch: buffers reused
        let mut big = Workspace::new(dm, 3 * n);
        let (_, x2, _) = random_case(dm, 2 * n, 9);
        big.forward(&params::<f32>(dm, &named), &x2);
        assert_eq!(big.forward(&params::<f32>(dm, &named), &x), &y[..]);
    }
}

/// Every parameter gradient equals candle's autograd on [`reference_forward`].
#[test]
fn gradients_equal_candle_autograd() {
    let dm = dims(11);
    let n = 6;
    let (named, x, y) = random_case(dm, n, 4);
    let p = params::<f32>(dm, &named);
    let mut ws = Workspace::new(dm, n);
    let loss = ws.loss_and_grad(&p, &x, &y);
    let (net, vars) = candle_net(dm, &named);
    let dev = Device::Cpu;
    let xt = Tensor::from_slice(&x, (n, dm.window, dm.features), &dev).unwrap();
    let yt = Tensor::from_slice(&y, (n, dm.outputs), &dev).unwrap();
    let mse = |y: Tensor| (y - &yt).unwrap().sqr().unwrap().mean_all().unwrap();
    let lc = mse(reference_forward(dm, &net, &vars, &xt));
    let lcv = lc.to_scalar::<f32>().unwrap() as f64;
    assert!(
        (loss - lcv).abs() <= 1e-5 * lcv,
        "loss {loss} vs candle {lcv}"
    );
    let grads = lc.backward().unwrap();
    for (name, g) in named_parts(&p, &ws.grad) {
        let gc: Vec<f32> = grads
            .get(vars[name].as_tensor())
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        let e = rel(g, &gc);
        eprintln!("{name}: max relative difference to candle {e:.2e}");
        assert!(e < 1e-4, "{name}: {e}");
    }
    // candle's conv1d + max_pool2d graph, as trained before: its convolution gradient
    let old = mse(net.forward(&xt).unwrap()).backward().unwrap();
    let go: Vec<f32> = (old.get(vars["conv.weight"].as_tensor()).unwrap())
        .flatten_all()
        .unwrap()
        .to_vec1()
        .unwrap();
    eprintln!(
        "candle conv1d/max_pool2d graph: conv.weight gradient off by {:.2e} relative",
        rel(&go, named_parts(&p, &ws.grad)[0].1)
    );
}

/// The f64 kernel's gradient against central differences of its loss, to 1e-6 relative
/// (odd and even F; step 1e-5: truncation error ~1e-10, rounding ~1e-11).
#[test]
fn gradients_equal_finite_differences() {
    for features in [11, 10] {
        let dm = dims(features);
        let n = 6;
        let (named, x, y) = random_case(dm, n, 4);
        let (x, y): (Vec<f64>, Vec<f64>) = (
            x.iter().map(|v| *v as f64).collect(),
            y.iter().map(|v| *v as f64).collect(),
        );
        let mut p = params::<f64>(dm, &named);
        let mut ws = Workspace::new(dm, n);
        ws.loss_and_grad(&p, &x, &y);
        let grad = ws.grad.clone();
        let scale = grad.iter().fold(0.0f64, |m, g| m.max(g.abs()));
        let eps = 1e-5;
        let mut worst = (0.0, 0);
        for (i, gi) in grad.iter().enumerate() {
            let v = p.values[i];
            p.values[i] = v + eps;
            let up = ws.loss_and_grad(&p, &x, &y);
            p.values[i] = v - eps;
            let down = ws.loss_and_grad(&p, &x, &y);
            p.values[i] = v;
            let fd = (up - down) / (2.0 * eps);
            // relative to the element, with a floor of 1e-3 of the largest gradient element
            let e = (fd - gi).abs() / (gi.abs() + 1e-3 * scale);
            if e > worst.0 {
                worst = (e, i);
            }
        }
        eprintln!(
            "F = {features}: {} parameters, worst relative difference to finite differences {:.2e} (parameter {})",
            grad.len(),
            worst.0,
            worst.1
        );
        assert!(worst.0 < 1e-6, "F = {features}: {worst:?}");
        // and a wrong gradient would not pass: the loss does depend on every tensor
        for (name, g) in named_parts(&p, &grad) {
            assert!(
                g.iter().any(|v| v.abs() > 1e-6 * scale),
                "{name} has no gradient"
            );
        }
    }
}

/// Three steps of [`Adam`] equal candle's `AdamW` (with and without weight decay, changing step
/// sizes) on the same gradients: loss = Σ θ⊙c has the gradient c exactly.
#[test]
fn adam_step_equals_candle_adamw() {
    let dev = Device::Cpu;
    let mut r = rng::seeded(11);
    let n = 40;
    let theta0: Vec<f32> = rng::uniform(&mut r, n, 1.0)
        .iter()
        .map(|v| *v as f32)
        .collect();
    for weight_decay in [0.0, 0.01] {
        let var = Var::from_tensor(&Tensor::from_slice(&theta0, n, &dev).unwrap()).unwrap();
        let params = ParamsAdamW {
            lr: 3e-3,
            weight_decay,
            ..ParamsAdamW::default()
        };
        let mut candle = AdamW::new(vec![var.clone()], params).unwrap();
        let mut ours = Adam::<f32>::new(n, weight_decay);
        let mut theta = theta0.clone();
        for (step, lr) in [3e-3, 2e-3, 1e-3].into_iter().enumerate() {
            let c: Vec<f32> = rng::uniform(&mut r, n, 1.0 + step as f64)
                .iter()
                .map(|v| *v as f32)
                .collect();
            let ct = Tensor::from_slice(&c, n, &dev).unwrap();
            let loss = (var.as_tensor() * &ct).unwrap().sum_all().unwrap();
            candle.set_learning_rate(lr);
            candle.backward_step(&loss).unwrap();
            ours.step(&mut theta, &c, lr);
        }
        let tc: Vec<f32> = var.as_tensor().to_vec1().unwrap();
        let moved: Vec<f32> = tc.iter().zip(&theta0).map(|(a, b)| a - b).collect();
        let ours_moved: Vec<f32> = theta.iter().zip(&theta0).map(|(a, b)| a - b).collect();
        let e = rel(&ours_moved, &moved);
        eprintln!("weight decay {weight_decay}: step max relative difference {e:.2e}");
        assert!(e < 1e-5, "{e}");
    }
}

/// The branch-free f32 exp against the library's, over the whole range the gates see, and
/// its saturation (sigmoid at ±100 is 1 and below 1e-37, tanh exactly ±1).
#[test]
fn fast_exp_is_accurate() {
    let mut worst = 0.0f64;
    for i in -87_000..=88_000 {
        let x = i as f32 * 1e-3;
        let (fast, exact) = (exp_f32(x) as f64, (x as f64).exp());
        worst = worst.max((fast - exact).abs() / exact);
    }
    eprintln!("exp_f32 worst relative error {worst:.2e}");
    assert!(worst < 3e-7, "{worst}");
    assert!(sigmoid(100.0f32) == 1.0 && (0.0..1e-37).contains(&sigmoid(-100.0f32)));
    assert_eq!((tanh(100.0f32), tanh(-100.0f32)), (1.0, -1.0));
}
