//! Butterworth design and zero-phase filtering against SciPy's `butter` + `filtfilt`
//! (tests/data/butterworth.json, written by tools/oracle/butterworth_reference.py).

use serde_json::Value;
use twinloop_ident::filter::butter_lowpass;

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn matches_scipy() {
    let text = include_str!("../data/butterworth.json");
    let refd: Value = serde_json::from_str(text).unwrap();
    for case in refd["cases"].as_array().unwrap() {
        let order = case["order"].as_u64().unwrap() as usize;
        let fc = case["cutoff_hz"].as_f64().unwrap();
        let fs = case["sample_hz"].as_f64().unwrap();
        let f = butter_lowpass(order, fc, fs).unwrap();
        let (b, a) = (nums(&case["b"]), nums(&case["a"]));
        for (x, y) in f.b.iter().zip(&b).chain(f.a.iter().zip(&a)) {
            assert!(
                (x - y).abs() < 1e-13 * (1.0 + y.abs()),
                "order {order} {fc}/{fs}: {x} vs {y}"
            );
        }
        let y = f.filtfilt(&nums(&case["x"])).unwrap();
        let yr = nums(&case["filtfilt"]);
        let err = y
            .iter()
            .zip(&yr)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        // Low cut-offs make the transfer-function form ill-conditioned: the last bits of the
        // coefficients are amplified (1000 Hz sampling, 10 Hz: ~2e-10). A wrong padding or
        // initial state would be off by 1e-3 or more.
        assert!(
            err < 1e-8,
            "order {order} {fc}/{fs}: filtfilt differs by {err:e}"
        );
    }
}
