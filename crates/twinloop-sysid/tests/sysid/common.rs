//! Shared test helpers: the committed fixtures of tools/oracle/sysid_reference.py.

use nalgebra::DMatrix;
use serde_json::Value;
use std::path::PathBuf;
use twinloop_sysid::{IoData, StateSpace};

pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// A fixture CSV as a record: columns u1..u10 are inputs, y1..y6 outputs.
pub fn record(name: &str) -> IoData {
    let text = std::fs::read_to_string(data_dir().join(name)).unwrap();
    let mut lines = text.lines();
    let columns: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let inputs: Vec<String> = (1..=10).map(|i| format!("u{i}")).collect();
    let outputs: Vec<String> = (1..=6).map(|i| format!("y{i}")).collect();
    IoData::from_table(&columns, &rows, &inputs, &outputs).unwrap()
}

pub fn reference() -> Value {
    let text = std::fs::read_to_string(data_dir().join("reference.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

pub fn matrix(v: &Value) -> DMatrix<f64> {
    let rows = v.as_array().unwrap();
    let nr = rows.len();
    let nc = rows.first().map_or(0, |r| r.as_array().unwrap().len());
    DMatrix::from_fn(nr, nc, |i, j| rows[i][j].as_f64().unwrap())
}

pub fn vector(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

pub fn true_system(r: &Value) -> StateSpace {
    let s = &r["system"];
    let ny = 6;
    StateSpace {
        a: matrix(&s["A"]),
        b: matrix(&s["B"]),
        c: matrix(&s["C"]),
        d: matrix(&s["D"]),
        k: matrix(&s["K"]),
        noise_covariance: DMatrix::identity(ny, ny) * r["noise_std"].as_f64().unwrap().powi(2),
        sample_time: r["sample_time"].as_f64(),
    }
}

/// Largest |a - b| / max(1, |b|).
pub fn max_rel_err(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    a.iter()
        .zip(b.iter())
        .map(|(x, y)| (x - y).abs() / y.abs().max(1.0))
        .fold(0.0, f64::max)
}

/// A small seeded generator of standard normal numbers (xorshift64* and Box-Muller),
/// so the tests can draw fresh records from the true system without dependencies.
pub struct Gaussian {
    state: u64,
    spare: Option<f64>,
}

impl Gaussian {
    pub fn new(seed: u64) -> Gaussian {
        Gaussian {
            state: seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1,
            spare: None,
        }
    }

    fn uniform(&mut self) -> f64 {
        self.state ^= self.state >> 12;
        self.state ^= self.state << 25;
        self.state ^= self.state >> 27;
        let x = self.state.wrapping_mul(0x2545_F491_4F6C_DD1D);
        ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    pub fn next(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let r = (-2.0 * u1.ln()).sqrt();
        let th = 2.0 * std::f64::consts::PI * u2;
        self.spare = Some(r * th.sin());
        r * th.cos()
    }
}

/// A record of `n` samples from `sys` in innovations form, white Gaussian inputs
/// (unit variance) and innovations (standard deviation `noise`), zero initial state.
pub fn draw_record(sys: &StateSpace, n: usize, noise: f64, rng: &mut Gaussian) -> IoData {
    let (nu, ny, nx) = (sys.nu(), sys.ny(), sys.n());
    let u = DMatrix::from_fn(nu, n, |_, _| rng.next());
    let e = DMatrix::from_fn(ny, n, |_, _| noise * rng.next());
    let mut y = DMatrix::zeros(ny, n);
    let mut x = nalgebra::DVector::zeros(nx);
    for k in 0..n {
        let yk = &sys.c * &x + &sys.d * u.column(k) + e.column(k);
        y.set_column(k, &yk);
        x = &sys.a * &x + &sys.b * u.column(k) + &sys.k * e.column(k);
    }
    let inputs = (1..=nu).map(|i| format!("u{i}")).collect();
    let outputs = (1..=ny).map(|i| format!("y{i}")).collect();
    IoData::new(inputs, outputs, u, y, sys.sample_time).unwrap()
}
