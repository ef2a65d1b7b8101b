//! A multilayer perceptron trained by back-propagation (seed 000 section V.C: "3
//! layered perceptrons with 5, 10 and 5 neurons ... with back-propagation learning").
//!
//! Hidden layers use `tanh` (the classical sigmoid-type unit of back-propagation
//! networks), the output layer is linear (the outputs are positions, unbounded). Inputs
//! and outputs are standardised (zero mean, unit deviation over the training set); the
//! scalings are part of the network and saved with it, so a loaded network takes and
//! gives physical units.
//!
//! Training minimises the mean squared error of the standardised outputs over mini
//! batches. The gradient is back-propagation; the update is Adam (Kingma and Ba, 2015):
//! the standardised outputs still differ in how much they vary with the inputs (the
//! hip mass moves with every change, a leg's mass only with changes on that leg), and
//! Adam's per-weight step sizes let one learning rate serve all of them (SGD with
//! momentum would need its rate tuned to the fastest-moving weights; it was not
//! tried). The testing set picks
//! the epoch (the weights with its lowest error are kept; the step size halves after
//! each quarter of `patience` epochs without a new lowest, and training stops after
//! `patience` of them). Everything random (initial weights,
//! batch order) comes from one [`SplitMix64`] seeded by the caller: the same seed and
//! data give the same network bit for bit.

use crate::error::IdentError;
use serde::{Deserialize, Serialize};
use twinloop_random::SplitMix64;

/// One fully connected layer: `y = W x + b`, `W` row-major (`outputs` rows of
/// `inputs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    pub inputs: usize,
    pub outputs: usize,
    pub weights: Vec<f64>,
    pub biases: Vec<f64>,
}

/// Standardisation of a vector: `(v - mean) / std` per entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scaling {
    pub mean: Vec<f64>,
    pub std: Vec<f64>,
}

impl Scaling {
    /// Mean and standard deviation of each column of `rows` (a constant column gets
    /// deviation 1, so it maps to 0).
    pub fn fit(rows: &[Vec<f64>]) -> Scaling {
        let w = rows.first().map_or(0, Vec::len);
        let n = rows.len().max(1) as f64;
        let mut mean = vec![0.0; w];
        for r in rows {
            for (m, v) in mean.iter_mut().zip(r) {
                *m += v / n;
            }
        }
        let mut std = vec![0.0; w];
        for r in rows {
            for ((s, v), m) in std.iter_mut().zip(r).zip(&mean) {
                *s += (v - m).powi(2) / n;
            }
        }
        for s in &mut std {
            *s = if *s > 1e-24 { s.sqrt() } else { 1.0 };
        }
        Scaling { mean, std }
    }
}

/// The network: layers, and the scalings of its inputs and outputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mlp {
    pub layers: Vec<Layer>,
    pub input_scaling: Scaling,
    pub output_scaling: Scaling,
}

/// Buffers of one forward and backward pass: allocated once, reused for every sample.
#[derive(Debug, Clone)]
pub struct MlpWork {
    /// Activations: `acts[0]` the standardised input, `acts[k + 1]` layer k's output.
    acts: Vec<Vec<f64>>,
    /// Back-propagated errors at each layer's pre-activation.
    deltas: Vec<Vec<f64>>,
}

impl MlpWork {
    pub fn new(net: &Mlp) -> MlpWork {
        let mut acts = vec![vec![0.0; net.n_inputs()]];
        acts.extend(net.layers.iter().map(|l| vec![0.0; l.outputs]));
        let deltas = net.layers.iter().map(|l| vec![0.0; l.outputs]).collect();
        MlpWork { acts, deltas }
    }
}

/// Settings of [`train`].
#[derive(Debug, Clone, PartialEq)]
pub struct TrainOptions {
    /// Hidden layer sizes: the seed's 5, 10, 5.
    pub hidden: Vec<usize>,
    /// Most epochs (passes over the training set).
    pub max_epochs: usize,
    /// Stop after this many epochs without a lower testing error; the step size is
    /// halved after each quarter of it without one.
    pub patience: usize,
    pub batch: usize,
    /// Adam's step size.
    pub learning_rate: f64,
    pub seed: u64,
}

impl Default for TrainOptions {
    fn default() -> Self {
        TrainOptions {
            hidden: vec![5, 10, 5],
            max_epochs: 1000,
            patience: 80,
            batch: 32,
            learning_rate: 3e-3,
            seed: 1,
        }
    }
}

/// How training went: the mean squared error (standardised outputs) of the training
/// and testing sets after each epoch, and the epoch whose weights were kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainLog {
    pub train_mse: Vec<f64>,
    pub test_mse: Vec<f64>,
    /// 1-based.
    pub best_epoch: usize,
}

impl Mlp {
    /// A network of the given layer sizes (inputs, hidden..., outputs) with Glorot
    /// uniform initial weights and zero biases, identity scalings.
    pub fn new(sizes: &[usize], rng: &mut SplitMix64) -> Mlp {
        let layers = sizes
            .windows(2)
            .map(|w| {
                let a = (6.0 / (w[0] + w[1]) as f64).sqrt();
                Layer {
                    inputs: w[0],
                    outputs: w[1],
                    weights: (0..w[0] * w[1]).map(|_| rng.uniform(-a, a)).collect(),
                    biases: vec![0.0; w[1]],
                }
            })
            .collect();
        let id = |n: usize| Scaling {
            mean: vec![0.0; n],
            std: vec![1.0; n],
        };
        Mlp {
            layers,
            input_scaling: id(sizes[0]),
            output_scaling: id(*sizes.last().unwrap_or(&0)),
        }
    }

    pub fn n_inputs(&self) -> usize {
        self.layers.first().map_or(0, |l| l.inputs)
    }

    pub fn n_outputs(&self) -> usize {
        self.layers.last().map_or(0, |l| l.outputs)
    }

    /// The layer sizes, inputs first.
    pub fn sizes(&self) -> Vec<usize> {
        let mut s = vec![self.n_inputs()];
        s.extend(self.layers.iter().map(|l| l.outputs));
        s
    }

    /// Forward pass on an already standardised input (`work.acts[0]`); the
    /// standardised output is left in the last activation.
    fn forward_scaled(&self, work: &mut MlpWork) {
        let last = self.layers.len() - 1;
        for (k, l) in self.layers.iter().enumerate() {
            let (before, after) = work.acts.split_at_mut(k + 1);
            let (x, y) = (&before[k], &mut after[0]);
            for ((yo, row), b) in y
                .iter_mut()
                .zip(l.weights.chunks_exact(l.inputs))
                .zip(&l.biases)
            {
                let s = b + row.iter().zip(x.iter()).map(|(w, v)| w * v).sum::<f64>();
                *yo = if k == last { s } else { s.tanh() };
            }
        }
    }

    /// The network's output for `input` (physical units in and out), written to `out`.
    /// Allocates nothing.
    pub fn predict_into(&self, input: &[f64], work: &mut MlpWork, out: &mut [f64]) {
        let sc = &self.input_scaling;
        for (i, a) in work.acts[0].iter_mut().enumerate() {
            *a = (input[i] - sc.mean[i]) / sc.std[i];
        }
        self.forward_scaled(work);
        let y = &work.acts[self.layers.len()];
        let sc = &self.output_scaling;
        for (i, o) in out.iter_mut().enumerate() {
            *o = sc.mean[i] + sc.std[i] * y[i];
        }
    }

    /// The network's output for `input`, physical units.
    pub fn predict(&self, input: &[f64]) -> Vec<f64> {
        let mut work = MlpWork::new(self);
        let mut out = vec![0.0; self.n_outputs()];
        self.predict_into(input, &mut work, &mut out);
        out
    }

    /// Back-propagation of one standardised sample (`x`, target `t`): adds the
    /// gradient of `0.5 |y - t|^2` to `grad` (same layout as the layers, weights then
    /// biases per layer) and returns the squared error.
    fn backprop(&self, x: &[f64], t: &[f64], work: &mut MlpWork, grad: &mut [f64]) -> f64 {
        work.acts[0].copy_from_slice(x);
        self.forward_scaled(work);
        let n = self.layers.len();
        let mut se = 0.0;
        for (d, (y, t)) in work.deltas[n - 1]
            .iter_mut()
            .zip(work.acts[n].iter().zip(t))
        {
            *d = y - t;
            se += (y - t) * (y - t);
        }
        let mut offset = grad.len();
        for k in (0..n).rev() {
            let l = &self.layers[k];
            offset -= l.weights.len() + l.biases.len();
            let (gw, gb) = grad[offset..offset + l.weights.len() + l.biases.len()]
                .split_at_mut(l.weights.len());
            let x = &work.acts[k];
            // Rows of the weights as slices: no index arithmetic or bounds check in
            // the inner loops (the order of every sum is the indexed loops' own).
            for ((gw_row, g_b), &d) in gw
                .chunks_exact_mut(l.inputs)
                .zip(gb.iter_mut())
                .zip(&work.deltas[k])
            {
                *g_b += d;
                for (g, v) in gw_row.iter_mut().zip(x) {
                    *g += d * v;
                }
            }
            if k > 0 {
                // Delta of the layer below: W^T d times tanh' = 1 - a^2, each sum over
                // the outputs in their order from -0.0 (as `Iterator::sum` adds).
                let (below, here) = work.deltas.split_at_mut(k);
                let (dl, dh) = (&mut below[k - 1], &here[0]);
                dl.fill(-0.0);
                for (row, &d) in l.weights.chunks_exact(l.inputs).zip(dh) {
                    for (s, w) in dl.iter_mut().zip(row) {
                        *s += w * d;
                    }
                }
                for (di, a) in dl.iter_mut().zip(x) {
                    *di *= 1.0 - a * a;
                }
            }
        }
        se
    }

    fn n_params(&self) -> usize {
        self.layers
            .iter()
            .map(|l| l.weights.len() + l.biases.len())
            .sum()
    }

    fn params_mut(&mut self) -> impl Iterator<Item = &mut f64> {
        self.layers
            .iter_mut()
            .flat_map(|l| l.weights.iter_mut().chain(l.biases.iter_mut()))
    }

    /// Mean squared error per output of standardised rows (forward passes only).
    fn mse(&self, x: &[Vec<f64>], t: &[Vec<f64>], work: &mut MlpWork) -> f64 {
        let n = self.layers.len();
        let mut se = 0.0;
        for (xi, ti) in x.iter().zip(t) {
            work.acts[0].copy_from_slice(xi);
            self.forward_scaled(work);
            se += work.acts[n]
                .iter()
                .zip(ti)
                .map(|(y, t)| (y - t).powi(2))
                .sum::<f64>();
        }
        se / (x.len().max(1) * self.n_outputs()) as f64
    }

    /// The network as JSON (numbers in the shortest form that reads back to the same
    /// f64, so [`Mlp::from_json`] restores it exactly).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// A network from [`Mlp::to_json`]'s text; checks that the layer sizes chain and
    /// every array has its size.
    pub fn from_json(text: &str) -> Result<Mlp, IdentError> {
        let net: Mlp = serde_json::from_str(text).map_err(|e| IdentError::new(e.to_string()))?;
        net.check()?;
        Ok(net)
    }

    /// Sizes consistent and every number finite.
    pub fn check(&self) -> Result<(), IdentError> {
        if self.layers.is_empty() {
            return Err(IdentError::new("has no layers").field("layers"));
        }
        for (k, l) in self.layers.iter().enumerate() {
            let f = |s: &str| format!("layers[{k}].{s}");
            if l.weights.len() != l.inputs * l.outputs || l.biases.len() != l.outputs {
                return Err(IdentError::new(format!(
                    "{} weights and {} biases for {} inputs and {} outputs",
                    l.weights.len(),
                    l.biases.len(),
                    l.inputs,
                    l.outputs
                ))
                .field(f("weights")));
            }
            if k > 0 && self.layers[k - 1].outputs != l.inputs {
                return Err(IdentError::new(format!(
                    "{} inputs after a layer of {} outputs",
                    l.inputs,
                    self.layers[k - 1].outputs
                ))
                .field(f("inputs")));
            }
            if l.weights.iter().chain(&l.biases).any(|v| !v.is_finite()) {
                return Err(IdentError::new("a weight is not a finite number").field(f("weights")));
            }
        }
        for (name, s, n) in [
            ("input_scaling", &self.input_scaling, self.n_inputs()),
            ("output_scaling", &self.output_scaling, self.n_outputs()),
        ] {
            if s.mean.len() != n || s.std.len() != n {
                return Err(IdentError::new(format!("needs {n} entries")).field(name));
            }
            if s.mean.iter().any(|v| !v.is_finite())
                || s.std.iter().any(|v| v.is_nan() || *v <= 0.0)
            {
                return Err(
                    IdentError::new("means must be finite, deviations positive").field(name)
                );
            }
        }
        Ok(())
    }
}

fn standardise(rows: &[Vec<f64>], s: &Scaling) -> Vec<Vec<f64>> {
    rows.iter()
        .map(|r| {
            r.iter()
                .zip(s.mean.iter().zip(&s.std))
                .map(|(v, (m, d))| (v - m) / d)
                .collect()
        })
        .collect()
}

/// Adam's moment estimates.
struct Adam {
    m: Vec<f64>,
    v: Vec<f64>,
    t: i32,
}

impl Adam {
    const BETA1: f64 = 0.9;
    const BETA2: f64 = 0.999;
    const EPS: f64 = 1e-8;

    fn step(&mut self, net: &mut Mlp, grad: &[f64], rate: f64) {
        self.t += 1;
        let c1 = 1.0 - Self::BETA1.powi(self.t);
        let c2 = 1.0 - Self::BETA2.powi(self.t);
        for (((p, g), m), v) in net
            .params_mut()
            .zip(grad)
            .zip(self.m.iter_mut())
            .zip(self.v.iter_mut())
        {
            *m = Self::BETA1 * *m + (1.0 - Self::BETA1) * g;
            *v = Self::BETA2 * *v + (1.0 - Self::BETA2) * g * g;
            *p -= rate * (*m / c1) / ((*v / c2).sqrt() + Self::EPS);
        }
    }
}

/// Train a network mapping `train_x` rows to `train_y` rows (physical units): the
/// scalings from the training set, mini-batch back-propagation with Adam, the testing
/// set (`test_x`, `test_y`) choosing the epoch (see the module documentation).
pub fn train(
    train_x: &[Vec<f64>],
    train_y: &[Vec<f64>],
    test_x: &[Vec<f64>],
    test_y: &[Vec<f64>],
    opts: &TrainOptions,
) -> Result<(Mlp, TrainLog), IdentError> {
    if train_x.is_empty() || train_x.len() != train_y.len() || test_x.len() != test_y.len() {
        return Err(IdentError::new(format!(
            "needs as many inputs as outputs and at least one training row (training {} / {}, testing {} / {})",
            train_x.len(),
            train_y.len(),
            test_x.len(),
            test_y.len()
        ))
        .field("samples"));
    }
    if opts.batch == 0 || opts.hidden.contains(&0) {
        return Err(IdentError::new("batch and layer sizes must be at least 1").field("hidden"));
    }
    let mut rng = SplitMix64(opts.seed);
    let mut sizes = vec![train_x[0].len()];
    sizes.extend(&opts.hidden);
    sizes.push(train_y[0].len());
    let mut net = Mlp::new(&sizes, &mut rng);
    net.input_scaling = Scaling::fit(train_x);
    net.output_scaling = Scaling::fit(train_y);
    let (x, y) = (
        standardise(train_x, &net.input_scaling),
        standardise(train_y, &net.output_scaling),
    );
    let (tx, ty) = (
        standardise(test_x, &net.input_scaling),
        standardise(test_y, &net.output_scaling),
    );
    let np = net.n_params();
    let mut grad = vec![0.0; np];
    let mut work = MlpWork::new(&net);
    let mut adam = Adam {
        m: vec![0.0; np],
        v: vec![0.0; np],
        t: 0,
    };
    let mut order: Vec<usize> = (0..x.len()).collect();
    let mut log = TrainLog {
        train_mse: vec![],
        test_mse: vec![],
        best_epoch: 0,
    };
    let mut best = (f64::INFINITY, net.clone());
    let (mut rate, mut last_cut) = (opts.learning_rate, 0);
    for epoch in 1..=opts.max_epochs {
        // Fisher-Yates shuffle of the batch order.
        for i in (1..order.len()).rev() {
            order.swap(i, rng.below(i as u64 + 1) as usize);
        }
        let mut se = 0.0;
        for batch in order.chunks(opts.batch) {
            grad.iter_mut().for_each(|g| *g = 0.0);
            for &i in batch {
                se += net.backprop(&x[i], &y[i], &mut work, &mut grad);
            }
            let k = 1.0 / batch.len() as f64;
            grad.iter_mut().for_each(|g| *g *= k);
            adam.step(&mut net, &grad, rate);
        }
        log.train_mse.push(se / (x.len() * net.n_outputs()) as f64);
        let test = if tx.is_empty() {
            *log.train_mse.last().unwrap_or(&f64::INFINITY)
        } else {
            net.mse(&tx, &ty, &mut work)
        };
        log.test_mse.push(test);
        if !test.is_finite() {
            return Err(IdentError::new(format!(
                "training diverged at epoch {epoch}: lower the learning rate"
            ))
            .field("learning_rate"));
        }
        if test < best.0 {
            best = (test, net.clone());
            log.best_epoch = epoch;
        } else if epoch - log.best_epoch >= opts.patience {
            break;
        } else if epoch - log.best_epoch.max(last_cut) >= (opts.patience / 4).max(1) {
            // A plateau: smaller steps to settle into the minimum.
            rate *= 0.5;
            last_cut = epoch;
        }
    }
    Ok((best.1, log))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Back-propagation against central differences of the squared error.
    #[test]
    fn backprop_is_the_gradient() {
        let mut rng = SplitMix64(11);
        let net = Mlp::new(&[3, 5, 10, 5, 4], &mut rng);
        let x = [0.3, -0.7, 1.1];
        let t = [0.2, -0.1, 0.5, 1.0];
        let mut work = MlpWork::new(&net);
        let mut grad = vec![0.0; net.n_params()];
        net.backprop(&x, &t, &mut work, &mut grad);
        let mut scratch = vec![0.0; net.n_params()];
        let h = 1e-6;
        for (p, g) in grad.iter().enumerate() {
            let mut moved = |d: f64| {
                let mut n = net.clone();
                *n.params_mut().nth(p).unwrap() += d;
                0.5 * n.backprop(&x, &t, &mut work, &mut scratch)
            };
            let fd = (moved(h) - moved(-h)) / (2.0 * h);
            assert!((fd - g).abs() < 1e-7, "parameter {p}: {fd} vs {g}");
        }
    }
}
