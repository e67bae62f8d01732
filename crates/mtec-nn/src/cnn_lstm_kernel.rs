//! The CNN-LSTM of [`crate::cnn_lstm`], forward and backward by hand, in plain Rust on
//! `matrixmultiply`'s GEMM (issue 22, build item 5): the same network, parameters and algorithm
//! as the candle version it replaces, without a graph, allocation or thread pool per op.
//!
//! Layout. A batch of n windows x [n, W, F] (row-major, as the model's windows) is worked on in
//! time-major order: row `t·n + b` is step t of window b, so the rows of one step are contiguous
//! and every step's GEMM reads and writes one block. Buffers are allocated once per
//! [`Workspace`] (for up to `capacity` windows) and reused by every batch.
//!
//! Forward (PyTorch's definitions; gate order i, f, g, o):
//! - Conv1d 1→C, kernel k, zero "same" padding, cross-correlation:
//!   z[c, j] = b_c + Σ_q w[c, q]·x[j + q − k/2];
//! - ReLU and max pooling by 2 (the odd last feature dropped): s[c·P + m] = max(0, z[c, 2m],
//!   z[c, 2m+1]), P = ⌊F/2⌋, D = C·P; the winning position is kept for the backward pass
//!   (the first of equal values, as PyTorch);
//! - the input projection of all W·n rows in one GEMM: A = S·W_ihᵀ + b_ih + b_hh;
//! - per step one GEMM adds h_{t−1}·W_hhᵀ onto the step's block of A, then one pass over it
//!   computes i = σ(a_i), f = σ(a_f), g = tanh(a_g), o = σ(a_o), c_t = f⊙c_{t−1} + i⊙g,
//!   h_t = o⊙tanh(c_t) (Hochreiter & Schmidhuber 1997 with the forget gate of Gers et al. 2000);
//! - y = h_W·W_fcᵀ + b_fc; the loss is the mean squared error over the n·O outputs.
//!
//! Backward (back-propagation through time): one pass per step from the last to the first
//! turns (dh_t, dc_t) into the gates' pre-activation gradients dA_t (written over A_t), and one
//! GEMM gives dh_{t−1} = dA_t·W_hh; after the loop three GEMMs over all rows give
//! dW_hh = Σ_t dA_tᵀ·h_{t−1}, dW_ih = dAᵀ·S and dS = dA·W_ih; dS flows back through the kept
//! max positions and the ReLU into the convolution's weights.
//!
//! Decision where candle and PyTorch differ: candle 0.11's max-pool gradient upsamples the
//! pooled values with a nearest-neighbour scale of ⌊F/2⌋/F, which for an odd F lines the
//! windows up wrongly (position j is compared with window ⌊j·P/F⌋, not ⌊j/2⌋), so its
//! convolution gradients were wrong for odd feature counts (e.g. 9 temperatures + 6 angle
//! harmonics). This kernel follows PyTorch (the gradient goes to the window's maximum); for
//! an even F it equals candle's (tests below).
//!
//! Generic over f32 (training, prediction) and f64 (the finite-difference check of the tests).

use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub};

/// The scalar type of the kernel: f32 or f64, with its GEMM.
pub trait Real:
    Copy
    + Default
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + Send
    + Sync
    + std::fmt::Debug
    + 'static
{
    fn of(v: f64) -> Self;
    fn to_f64(self) -> f64;
    fn exp(self) -> Self;
    fn tanh(self) -> Self;
    fn sqrt(self) -> Self;
    /// C ← α·A·B + β·C for an m×k A and a k×n B with element strides (row, column).
    ///
    /// # Safety
    /// Every element addressed through the strides must lie inside the pointed-to buffers.
    #[allow(clippy::too_many_arguments)]
    unsafe fn gemm_raw(
        m: usize,
        k: usize,
        n: usize,
        alpha: Self,
        a: *const Self,
        rsa: isize,
        csa: isize,
        b: *const Self,
        rsb: isize,
        csb: isize,
        beta: Self,
        c: *mut Self,
        rsc: isize,
        csc: isize,
    );
}

/// e^x in f32 without a branch or a library call, so that the gate loops vectorise: Cephes'
/// `expf` (range reduction x = n·ln 2 + r with ln 2 in two parts, a degree-6 polynomial for
/// e^r, 2^n put into the exponent bits), relative error ≈ 1e-7; x clamped to [−87.3, 88.3],
/// where e^x is a normal f32.
#[inline(always)]
fn exp_f32(x: f32) -> f32 {
    let x = x.clamp(-87.3, 88.3);
    // round(x·log2 e) by the 1.5·2²³ trick (no rounding instruction needed)
    let n = (x * std::f32::consts::LOG2_E + 12_582_912.0) - 12_582_912.0;
    let r = x - n * 0.693_359_4 + n * 2.121_944_4e-4;
    let p = ((((1.987_569_1e-4 * r + 1.398_199_9e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r
        + 1.666_666_5e-1)
        * r
        + 0.5;
    let e = p * (r * r) + r + 1.0;
    e * f32::from_bits(((n as i32 + 127) as u32) << 23)
}

macro_rules! real {
    ($t:ty, $gemm:path, $exp:expr) => {
        impl Real for $t {
            fn of(v: f64) -> Self {
                v as $t
            }
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn exp(self) -> Self {
                $exp(self)
            }
            fn tanh(self) -> Self {
                <$t>::tanh(self)
            }
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            unsafe fn gemm_raw(
                m: usize,
                k: usize,
                n: usize,
                alpha: Self,
                a: *const Self,
                rsa: isize,
                csa: isize,
                b: *const Self,
                rsb: isize,
                csb: isize,
                beta: Self,
                c: *mut Self,
                rsc: isize,
                csc: isize,
            ) {
                // SAFETY: forwarded; the caller guarantees the strides stay in bounds
                unsafe { $gemm(m, k, n, alpha, a, rsa, csa, b, rsb, csb, beta, c, rsc, csc) }
            }
        }
    };
}
real!(f32, matrixmultiply::sgemm, exp_f32);
real!(f64, matrixmultiply::dgemm, f64::exp);

/// A strided matrix view: (rows, columns, row stride, column stride).
type View = (usize, usize, usize, usize);

/// Elements a strided view reaches: one past its last element.
fn reach((r, c, rs, cs): View) -> usize {
    if r == 0 || c == 0 {
        0
    } else {
        (r - 1) * rs + (c - 1) * cs + 1
    }
}

/// C ← A·B + β·C on slices, the views' bounds checked (always: it costs nothing next to a GEMM).
fn gemm<T: Real>(a: &[T], av: View, b: &[T], bv: View, beta: T, c: &mut [T], cv: View) {
    let (m, k, n) = (av.0, av.1, bv.1);
    assert!(bv.0 == k && cv.0 == m && cv.1 == n, "GEMM shapes");
    assert!(reach(av) <= a.len() && reach(bv) <= b.len() && reach(cv) <= c.len());
    if m == 0 || n == 0 {
        return;
    }
    // SAFETY: the asserts above keep every addressed element inside the three slices
    unsafe {
        T::gemm_raw(
            m,
            k,
            n,
            T::of(1.0),
            a.as_ptr(),
            av.2 as isize,
            av.3 as isize,
            b.as_ptr(),
            bv.2 as isize,
            bv.3 as isize,
            beta,
            c.as_mut_ptr(),
            cv.2 as isize,
            cv.3 as isize,
        )
    }
}

#[inline(always)]
fn sigmoid<T: Real>(x: T) -> T {
    T::of(1.0) / (T::of(1.0) + (-x).exp())
}

/// tanh x = 2σ(2x) − 1: one `exp`, several times cheaper than the C library's `tanhf`;
/// absolute error a few f32 ulps of 1, saturating cleanly (e^{±2x} overflows to ±1).
#[inline(always)]
fn tanh<T: Real>(x: T) -> T {
    T::of(2.0) * sigmoid(T::of(2.0) * x) - T::of(1.0)
}

/// The network's dimensions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dims {
    /// Time steps per window W.
    pub window: usize,
    /// Features per step F.
    pub features: usize,
    /// Convolution filters C.
    pub channels: usize,
    /// Convolution kernel k (odd).
    pub kernel: usize,
    /// LSTM hidden size H.
    pub hidden: usize,
    /// Outputs O.
    pub outputs: usize,
}

/// The parameter tensors in storage order, with PyTorch's names.
pub const PARAM_NAMES: [&str; 8] = [
    "conv.weight",
    "conv.bias",
    "lstm.weight_ih_l0",
    "lstm.weight_hh_l0",
    "lstm.bias_ih_l0",
    "lstm.bias_hh_l0",
    "fc.weight",
    "fc.bias",
];
const CONV_W: usize = 0;
const CONV_B: usize = 1;
const W_IH: usize = 2;
const W_HH: usize = 3;
const B_IH: usize = 4;
const B_HH: usize = 5;
const FC_W: usize = 6;
const FC_B: usize = 7;

impl Dims {
    /// Pooled features per channel P = ⌊F/2⌋.
    pub fn pooled(&self) -> usize {
        self.features / 2
    }
    /// LSTM input size D = C·P.
    pub fn lstm_input(&self) -> usize {
        self.channels * self.pooled()
    }
    /// The shapes of [`PARAM_NAMES`] (PyTorch's layouts).
    pub fn param_shapes(&self) -> [Vec<usize>; 8] {
        let (c, k, h, o, d) = (
            self.channels,
            self.kernel,
            self.hidden,
            self.outputs,
            self.lstm_input(),
        );
        [
            vec![c, 1, k],
            vec![c],
            vec![4 * h, d],
            vec![4 * h, h],
            vec![4 * h],
            vec![4 * h],
            vec![o, h],
            vec![o],
        ]
    }
    /// Start of each tensor in the flat parameter vector, and its end.
    fn offsets(&self) -> [usize; 9] {
        let mut off = [0; 9];
        for (i, s) in self.param_shapes().iter().enumerate() {
            off[i + 1] = off[i] + s.iter().product::<usize>();
        }
        off
    }
    /// Number of parameters.
    pub fn param_count(&self) -> usize {
        self.offsets()[8]
    }
}

/// The parameters as one flat vector (tensors in [`PARAM_NAMES`] order, each row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct Params<T> {
    pub dims: Dims,
    pub values: Vec<T>,
    offsets: [usize; 9],
}

impl<T: Real> Params<T> {
    /// From the tensors by name (row-major, in PyTorch's layouts); `None` if one is missing or
    /// has the wrong length.
    pub fn from_named<'a>(dims: Dims, get: impl Fn(&str) -> Option<&'a [f32]>) -> Option<Self> {
        let offsets = dims.offsets();
        let mut values = Vec::with_capacity(offsets[8]);
        for (i, name) in PARAM_NAMES.iter().enumerate() {
            let data = get(name)?;
            if data.len() != offsets[i + 1] - offsets[i] {
                return None;
            }
            values.extend(data.iter().map(|v| T::of(*v as f64)));
        }
        Some(Params {
            dims,
            values,
            offsets,
        })
    }
    /// Tensor `i` of [`PARAM_NAMES`].
    pub fn tensor(&self, i: usize) -> &[T] {
        &self.values[self.offsets[i]..self.offsets[i + 1]]
    }
    /// Tensor `i` of a vector laid out as the parameters (e.g. the gradient).
    fn part<'a>(&self, v: &'a [T], i: usize) -> &'a [T] {
        &v[self.offsets[i]..self.offsets[i + 1]]
    }
}

/// Adam / AdamW as candle-nn 0.11's `AdamW` computes it (Loshchilov & Hutter 2019, Alg. 2;
/// with `weight_decay` 0 it is Kingma & Ba's Adam): per element
/// m ← β₁m + (1−β₁)g, v ← β₂v + (1−β₂)g², θ ← θ(1 − ηλ) − η·(m/(1−β₁ᵗ)) / (√(v/(1−β₂ᵗ)) + ε).
#[derive(Debug, Clone)]
pub struct Adam<T> {
    pub beta1: f64,
    pub beta2: f64,
    pub eps: f64,
    pub weight_decay: f64,
    m: Vec<T>,
    v: Vec<T>,
    t: i32,
}

impl<T: Real> Adam<T> {
    /// candle's `ParamsAdamW` defaults (β₁ 0.9, β₂ 0.999, ε 1e-8) with the given weight decay.
    pub fn new(n_params: usize, weight_decay: f64) -> Self {
        Adam {
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
            weight_decay,
            m: vec![T::default(); n_params],
            v: vec![T::default(); n_params],
            t: 0,
        }
    }

    /// One step with step size `lr`.
    pub fn step(&mut self, theta: &mut [T], grad: &[T], lr: f64) {
        assert!(theta.len() == self.m.len() && grad.len() == self.m.len());
        self.t += 1;
        let (b1, b2) = (self.beta1, self.beta2);
        let scale_m = T::of(1.0 / (1.0 - b1.powi(self.t)));
        let scale_v = T::of(1.0 / (1.0 - b2.powi(self.t)));
        let decay = T::of(1.0 - lr * self.weight_decay);
        let (b1, b2, c1, c2) = (T::of(b1), T::of(b2), T::of(1.0 - b1), T::of(1.0 - b2));
        let (eps, lr) = (T::of(self.eps), T::of(lr));
        for (((p, g), m), v) in theta.iter_mut().zip(grad).zip(&mut self.m).zip(&mut self.v) {
            *m = *m * b1 + *g * c1;
            *v = *v * b2 + (*g * *g) * c2;
            let step = (*m * scale_m) / ((*v * scale_v).sqrt() + eps);
            *p = *p * decay - step * lr;
        }
    }
}

/// Marks a pooled value whose maximum was ≤ 0 (ReLU): no gradient flows back.
const NO_MAX: u8 = 2;

/// The buffers of one forward/backward pass for up to `capacity` windows, allocated once.
#[derive(Debug, Clone)]
pub struct Workspace<T> {
    dims: Dims,
    capacity: usize,
    /// Windows in the current pass.
    n: usize,
    /// Pooled convolution features S [W·n, D], time-major.
    s: Vec<T>,
    /// Which of the two pooled positions won (0, 1) or [`NO_MAX`].
    sel: Vec<u8>,
    /// One step's features with k/2 zeros on either side [F + k − 1].
    xpad: Vec<T>,
    /// One channel's convolution before pooling [2P].
    zrow: Vec<T>,
    /// Gate activations (i, f, g, o) per row [W·n, 4H]; their pre-activation gradients after
    /// the backward pass.
    a: Vec<T>,
    /// Cell states, their tanh and the hidden states [W·n, H].
    c: Vec<T>,
    tc: Vec<T>,
    h: Vec<T>,
    /// Outputs [n, O] and their loss gradient.
    y: Vec<T>,
    dy: Vec<T>,
    /// Running dh_t, dc_t [n, H].
    dh: Vec<T>,
    dc: Vec<T>,
    /// dS [W·n, D].
    ds: Vec<T>,
    /// The bias sum b_ih + b_hh [4H].
    bias: Vec<T>,
    /// dLoss/dθ, laid out as [`Params::values`].
    pub grad: Vec<T>,
}

impl<T: Real> Workspace<T> {
    pub fn new(dims: Dims, capacity: usize) -> Self {
        let (w, d, h, g, o) = (
            dims.window,
            dims.lstm_input(),
            dims.hidden,
            4 * dims.hidden,
            dims.outputs,
        );
        let z = |len: usize| vec![T::default(); len];
        let rows = w * capacity;
        Workspace {
            dims,
            capacity,
            n: 0,
            s: z(rows * d),
            sel: vec![0; rows * d],
            xpad: z(dims.features + dims.kernel - 1),
            zrow: z(2 * dims.pooled()),
            a: z(rows * g),
            c: z(rows * h),
            tc: z(rows * h),
            h: z(rows * h),
            y: z(capacity * o),
            dy: z(capacity * o),
            dh: z(capacity * h),
            dc: z(capacity * h),
            ds: z(rows * d),
            bias: z(g),
            grad: z(dims.param_count()),
        }
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Forward pass of n windows `x` [n, W, F] (normalised features); returns y [n, O].
    pub fn forward(&mut self, p: &Params<T>, x: &[T]) -> &[T] {
        let dm = self.dims;
        assert_eq!(p.dims, dm, "parameters of another architecture");
        let (w, f, ch, k) = (dm.window, dm.features, dm.channels, dm.kernel);
        let (pl, d, h, o) = (dm.pooled(), dm.lstm_input(), dm.hidden, dm.outputs);
        let g = 4 * h;
        assert!(x.len().is_multiple_of(w * f), "x is not [n, W, F]");
        let n = x.len() / (w * f);
        assert!(
            n <= self.capacity,
            "{n} windows > capacity {}",
            self.capacity
        );
        self.n = n;
        let rows = w * n;
        let pad = k / 2;
        let (cw, cb) = (p.tensor(CONV_W), p.tensor(CONV_B));
        let zero = T::default();
        // convolution, ReLU and max pooling, written time-major
        for b in 0..n {
            for t in 0..w {
                self.xpad[pad..pad + f].copy_from_slice(&x[(b * w + t) * f..][..f]);
                let xp = &self.xpad;
                let r = t * n + b;
                let (srow, selrow) = (&mut self.s[r * d..][..d], &mut self.sel[r * d..][..d]);
                let zc = &mut self.zrow;
                for c in 0..ch {
                    // z[c, j] = b_c + Σ_q w[c, q]·x[j + q − k/2] (zero outside 0..F), j < 2P
                    zc.fill(cb[c]);
                    for (q, wq) in cw[c * k..][..k].iter().enumerate() {
                        for (zj, xj) in zc.iter_mut().zip(&xp[q..q + 2 * pl]) {
                            *zj += *wq * *xj;
                        }
                    }
                    for m in 0..pl {
                        let (z0, z1) = (zc[2 * m], zc[2 * m + 1]);
                        let up = z1 > z0;
                        let v = if up { z1 } else { z0 };
                        let on = v > zero;
                        srow[c * pl + m] = if on { v } else { zero };
                        selrow[c * pl + m] = if on { up as u8 } else { NO_MAX };
                    }
                }
            }
        }
        // input projection of every row: A = S·W_ihᵀ + b_ih + b_hh
        for (s, (bi, bh)) in self
            .bias
            .iter_mut()
            .zip(p.tensor(B_IH).iter().zip(p.tensor(B_HH)))
        {
            *s = *bi + *bh;
        }
        for row in self.a[..rows * g].chunks_exact_mut(g) {
            row.copy_from_slice(&self.bias);
        }
        let w_ih = p.tensor(W_IH);
        gemm(
            &self.s,
            (rows, d, d, 1),
            w_ih,
            (d, g, 1, d),
            T::of(1.0),
            &mut self.a,
            (rows, g, g, 1),
        );
        // the recurrence, one GEMM and one fused pass per step
        let w_hh = p.tensor(W_HH);
        let one = T::of(1.0);
        for t in 0..w {
            let blk = t * n;
            let at = &mut self.a[blk * g..(blk + n) * g];
            if t > 0 {
                // A_t += h_{t−1}·W_hhᵀ
                let hp = &self.h[(blk - n) * h..blk * h];
                gemm(hp, (n, h, h, 1), w_hh, (h, g, 1, h), one, at, (n, g, g, 1));
            }
            let (c_prev, c_now) = self.c.split_at_mut(blk * h);
            let c_prev = if t > 0 {
                &c_prev[(blk - n) * h..]
            } else {
                &[][..]
            };
            for b in 0..n {
                let ar = &mut at[b * g..][..g];
                // i, f, o = σ(a), g = tanh(a): contiguous runs, so the loops vectorise
                let (ifg, go) = ar.split_at_mut(2 * h);
                let (gg, og) = go.split_at_mut(h);
                ifg.iter_mut().for_each(|v| *v = sigmoid(*v));
                gg.iter_mut().for_each(|v| *v = tanh(*v));
                og.iter_mut().for_each(|v| *v = sigmoid(*v));
                let (ig, fg) = ifg.split_at(h);
                let row = (blk + b) * h..(blk + b + 1) * h;
                let cn = &mut c_now[b * h..(b + 1) * h];
                // c_t = f ⊙ c_{t−1} + i ⊙ g
                if t > 0 {
                    let cp = &c_prev[b * h..(b + 1) * h];
                    for j in 0..h {
                        cn[j] = fg[j] * cp[j] + ig[j] * gg[j];
                    }
                } else {
                    for j in 0..h {
                        cn[j] = ig[j] * gg[j];
                    }
                }
                // h_t = o ⊙ tanh(c_t)
                let (tc, hs) = (&mut self.tc[row.clone()], &mut self.h[row]);
                for j in 0..h {
                    tc[j] = tanh(cn[j]);
                    hs[j] = og[j] * tc[j];
                }
            }
        }
        // y = h_W·W_fcᵀ + b_fc
        let last = &self.h[(w - 1) * n * h..rows * h];
        for row in self.y[..n * o].chunks_exact_mut(o) {
            row.copy_from_slice(p.tensor(FC_B));
        }
        gemm(
            last,
            (n, h, h, 1),
            p.tensor(FC_W),
            (h, o, 1, h),
            one,
            &mut self.y,
            (n, o, o, 1),
        );
        &self.y[..n * o]
    }

    /// Forward and backward pass of n windows `x` [n, W, F] against targets [n, O]: returns the
    /// mean squared error and leaves dLoss/dθ in [`Workspace::grad`].
    pub fn loss_and_grad(&mut self, p: &Params<T>, x: &[T], targets: &[T]) -> f64 {
        self.forward(p, x);
        let dm = self.dims;
        let (n, w, f, ch, k) = (self.n, dm.window, dm.features, dm.channels, dm.kernel);
        let (pl, d, h, o) = (dm.pooled(), dm.lstm_input(), dm.hidden, dm.outputs);
        let g = 4 * h;
        let rows = w * n;
        assert_eq!(targets.len(), n * o, "targets are not [n, O]");
        // loss = Σ(y − t)²/(n·O), dy = 2(y − t)/(n·O)
        let scale = 2.0 / (n * o) as f64;
        let mut loss = 0.0;
        for ((dy, y), t) in self.dy.iter_mut().zip(&self.y).zip(targets) {
            let e = *y - *t;
            loss += e.to_f64() * e.to_f64();
            *dy = e * T::of(scale);
        }
        let zero = T::default();
        let one = T::of(1.0);
        self.grad.fill(zero);
        let off = p.offsets;
        let grad = &mut self.grad;
        let dy = &self.dy[..n * o];
        // dense layer: dW_fc = dyᵀ·h_W, db_fc = Σ_b dy, dh_W = dy·W_fc
        let last = &self.h[(w - 1) * n * h..rows * h];
        gemm(
            dy,
            (o, n, 1, o),
            last,
            (n, h, h, 1),
            zero,
            &mut grad[off[FC_W]..off[FC_W + 1]],
            (o, h, h, 1),
        );
        for row in dy.chunks_exact(o) {
            for (gb, v) in grad[off[FC_B]..off[FC_B + 1]].iter_mut().zip(row) {
                *gb += *v;
            }
        }
        gemm(
            dy,
            (n, o, o, 1),
            p.tensor(FC_W),
            (o, h, h, 1),
            zero,
            &mut self.dh,
            (n, h, h, 1),
        );
        self.dc[..n * h].fill(zero);
        // back-propagation through time
        let w_hh = p.tensor(W_HH);
        for t in (0..w).rev() {
            let blk = t * n;
            let at = &mut self.a[blk * g..(blk + n) * g];
            for b in 0..n {
                let ar = &mut at[b * g..][..g];
                for j in 0..h {
                    let idx = (blk + b) * h + j;
                    let (i, fg, gg, og) = (ar[j], ar[h + j], ar[2 * h + j], ar[3 * h + j]);
                    let tcn = self.tc[idx];
                    let cp = if t > 0 { self.c[idx - n * h] } else { zero };
                    let dh = self.dh[b * h + j];
                    // dc_t += dh_t ⊙ o ⊙ (1 − tanh²c_t)
                    let dc = self.dc[b * h + j] + dh * og * (one - tcn * tcn);
                    ar[j] = dc * gg * i * (one - i); // da_i = dc ⊙ g ⊙ σ'
                    ar[h + j] = dc * cp * fg * (one - fg); // da_f = dc ⊙ c_{t−1} ⊙ σ'
                    ar[2 * h + j] = dc * i * (one - gg * gg); // da_g = dc ⊙ i ⊙ tanh'
                    ar[3 * h + j] = dh * tcn * og * (one - og); // da_o = dh ⊙ tanh c_t ⊙ σ'
                    self.dc[b * h + j] = dc * fg; // dc_{t−1} = dc_t ⊙ f
                }
            }
            if t > 0 {
                // dh_{t−1} = dA_t·W_hh
                gemm(
                    at,
                    (n, g, g, 1),
                    w_hh,
                    (g, h, h, 1),
                    zero,
                    &mut self.dh,
                    (n, h, h, 1),
                );
            }
        }
        let da = &self.a[..rows * g];
        // dW_hh = Σ_{t≥1} dA_tᵀ·h_{t−1}: one GEMM over the time-major rows
        if w > 1 {
            gemm(
                &da[n * g..],
                (g, (w - 1) * n, 1, g),
                &self.h,
                ((w - 1) * n, h, h, 1),
                zero,
                &mut grad[off[W_HH]..off[W_HH + 1]],
                (g, h, h, 1),
            );
        }
        // db_ih = db_hh = Σ_rows dA
        for row in da.chunks_exact(g) {
            for (gb, v) in grad[off[B_IH]..off[B_IH + 1]].iter_mut().zip(row) {
                *gb += *v;
            }
        }
        let (lo, hi) = grad.split_at_mut(off[B_HH]);
        hi[..g].copy_from_slice(&lo[off[B_IH]..off[B_IH + 1]]);
        // dW_ih = dAᵀ·S, dS = dA·W_ih
        gemm(
            da,
            (g, rows, 1, g),
            &self.s,
            (rows, d, d, 1),
            zero,
            &mut grad[off[W_IH]..off[W_IH + 1]],
            (g, d, d, 1),
        );
        gemm(
            da,
            (rows, g, g, 1),
            p.tensor(W_IH),
            (g, d, d, 1),
            zero,
            &mut self.ds,
            (rows, d, d, 1),
        );
        // max pooling, ReLU and convolution: dw[c, q] = Σ dz[c, j]·x[j + q − k/2]
        let pad = k / 2;
        let (gw, gb) = grad[off[CONV_W]..off[CONV_B + 1]].split_at_mut(ch * k);
        for b in 0..n {
            for t in 0..w {
                self.xpad[pad..pad + f].copy_from_slice(&x[(b * w + t) * f..][..f]);
                let xp = &self.xpad;
                let r = t * n + b;
                let (dsr, selr) = (&self.ds[r * d..][..d], &self.sel[r * d..][..d]);
                for c in 0..ch {
                    for m in 0..pl {
                        let i = c * pl + m;
                        if selr[i] == NO_MAX {
                            continue;
                        }
                        let (dz, j) = (dsr[i], 2 * m + selr[i] as usize);
                        gb[c] += dz;
                        for (gq, xq) in gw[c * k..][..k].iter_mut().zip(&xp[j..j + k]) {
                            *gq += dz * *xq;
                        }
                    }
                }
            }
        }
        loss / (n * o) as f64
    }
}

/// The named views of a gradient vector, for tests and reports.
pub fn named_parts<'a, T: Real>(p: &Params<T>, v: &'a [T]) -> Vec<(&'static str, &'a [T])> {
    (0..8).map(|i| (PARAM_NAMES[i], p.part(v, i))).collect()
}

#[cfg(test)]
mod tests;
