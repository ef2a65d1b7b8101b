//! How well a model's outputs match measured ones.

use nalgebra::DMatrix;

/// FIT in percent per output as MATLAB's `compare` defines it:
/// `100 (1 - ||y - yhat|| / ||y - mean(y)||)`. 100 is a perfect match, 0 is no
/// better than the output's mean, negative is worse. `y` and `yhat` are
/// `ny x N`. `None` for an output whose model output is not finite (an unstable
/// simulation) or whose measurement is constant.
pub fn fit_percent(y: &DMatrix<f64>, yhat: &DMatrix<f64>) -> Vec<Option<f64>> {
    (0..y.nrows())
        .map(|i| {
            let (yr, hr) = (y.row(i), yhat.row(i));
            let mean = yr.mean();
            let err = (yr - hr).norm();
            let dev = yr.map(|v| v - mean).norm();
            let f = 100.0 * (1.0 - err / dev);
            (f.is_finite() && dev > 0.0).then_some(f)
        })
        .collect()
}

/// The seed's own measure (seed 003, eq 10): `FIT = ||y - ysim||_2 / ||y||_2 x 100`.
/// Despite its name it is a relative error: 0 is a perfect match, lower is better,
/// and it is not normalised by the mean (an output with a large offset scores well).
pub fn seed_eq10_percent(y: &DMatrix<f64>, yhat: &DMatrix<f64>) -> Vec<Option<f64>> {
    (0..y.nrows())
        .map(|i| {
            let (yr, hr) = (y.row(i), yhat.row(i));
            let f = 100.0 * (yr - hr).norm() / yr.norm();
            f.is_finite().then_some(f)
        })
        .collect()
}
