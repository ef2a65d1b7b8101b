//! The parallel forms return the serial forms' results bit for bit, on one thread
//! and on several (issue 32 item 4: "results identical to one thread").

use twinloop_optim::parallel::{Scratch, on_threads};
use twinloop_optim::{
    CmaOptions, LmOptions, StepTolerance, levenberg_marquardt, levenberg_marquardt_parallel,
    minimize, minimize_parallel,
};

fn rosenbrock(x: &[f64]) -> f64 {
    (0..x.len() - 1)
        .map(|i| 100.0 * (x[i + 1] - x[i] * x[i]).powi(2) + (1.0 - x[i]).powi(2))
        .sum()
}

#[test]
fn cma_es_population_in_parallel_is_the_serial_search() {
    let o = CmaOptions {
        sigma: 0.5,
        max_evaluations: 3000,
        tolerance: StepTolerance::Relative(1e-12),
        target: f64::NEG_INFINITY,
        seed: 5,
    };
    let (lower, upper) = ([-0.5; 6], [2.0; 6]);
    let bounds = Some((&lower[..], &upper[..]));
    let mut serial_trace = Vec::new();
    let serial = minimize(
        &mut |x| rosenbrock(x),
        &[0.0; 6],
        bounds,
        &o,
        &mut |e, c, _| serial_trace.push((e, c.to_bits())),
    );
    for threads in [1, 4] {
        let mut trace = Vec::new();
        let r = on_threads(threads, || {
            minimize_parallel(&rosenbrock, &[0.0; 6], bounds, &o, &mut |e, c, _| {
                trace.push((e, c.to_bits()))
            })
        });
        assert_eq!(r.x, serial.x, "{threads} threads");
        assert_eq!(r.cost.to_bits(), serial.cost.to_bits());
        assert_eq!(
            (r.evaluations, r.generations),
            (serial.evaluations, serial.generations)
        );
        assert_eq!(
            trace, serial_trace,
            "{threads} threads: generation by generation"
        );
    }
    assert!(
        serial.generations > 50,
        "a search long enough to tell: {serial:?}"
    );
}

#[test]
fn lm_jacobian_in_parallel_is_the_serial_fit() {
    // y = a exp(-b t) + c sin(d t) from exact data, a start far off: several
    // iterations, damping rejected and accepted, every Jacobian column used.
    let t: Vec<f64> = (0..80).map(|i| i as f64 * 0.1).collect();
    let model = |x: &[f64], t: f64| x[0] * (-x[1] * t).exp() + x[2] * (x[3] * t).sin();
    let y: Vec<f64> = t.iter().map(|&t| model(&[2.5, 0.7, 0.3, 1.9], t)).collect();
    // Buffers of the kind a simulation needs, shared through the pool.
    let scratch = Scratch::new(|| vec![0.0; 80]);
    let residuals = |x: &[f64], out: &mut [f64]| {
        scratch.with(|buf: &mut Vec<f64>| {
            for (b, &t) in buf.iter_mut().zip(&t) {
                *b = model(x, t);
            }
            for i in 0..out.len() {
                out[i] = buf[i] - y[i];
            }
        })
    };
    let x0 = [1.0, 0.2, 0.1, 1.7];
    let o = LmOptions::default();
    let serial = levenberg_marquardt(&x0, t.len(), residuals, &o);
    assert!(serial.iterations > 3, "{serial:?}");
    for threads in [1, 4] {
        let r = on_threads(threads, || {
            levenberg_marquardt_parallel(&x0, t.len(), &residuals, &o)
        });
        assert_eq!(r.x, serial.x, "{threads} threads");
        assert_eq!(r.cost.to_bits(), serial.cost.to_bits());
        assert_eq!(r.jacobian, serial.jacobian);
        assert_eq!(r.residuals, serial.residuals);
        assert_eq!(
            (r.iterations, r.evaluations),
            (serial.iterations, serial.evaluations)
        );
    }
}
