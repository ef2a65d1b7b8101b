//! The ANN's training loop alone (issue 32 item 5: `adapt train` spends 90 % of its
//! time there), on made-up rows of `adapt train`'s shape (9 inputs, 9 outputs, the
//! 5-10-5 network, mini-batches of 32), small enough for callgrind.
//!
//! `cargo run --profile ci -p twinloop-ident --example ann_train_speed -- [ROWS]
//! [EPOCHS]`: prints the CPU time and a hash of the trained weights' bits (the same
//! hash before and after a change of the loop means the same network).

use twinloop_ident::ann::{TrainOptions, train};
use twinloop_random::SplitMix64;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rows: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(2000);
    let epochs: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(5);
    let mut rng = SplitMix64(7);
    // A smooth map with some noise: what the network learns need not be the robot's.
    let mut row = |_| -> (Vec<f64>, Vec<f64>) {
        let x: Vec<f64> = (0..9).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let y = (0..9)
            .map(|k| (x[k] + 0.5 * x[(k + 1) % 9]).sin() + 0.01 * rng.uniform(-1.0, 1.0))
            .collect();
        (x, y)
    };
    let (tx, ty): (Vec<_>, Vec<_>) = (0..rows).map(&mut row).unzip();
    let (sx, sy): (Vec<_>, Vec<_>) = (0..rows / 5).map(&mut row).unzip();
    let opts = TrainOptions {
        max_epochs: epochs,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let (net, log) = train(&tx, &ty, &sx, &sy, &opts).expect("training runs");
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for l in &net.layers {
        for v in l.weights.iter().chain(&l.biases) {
            hash = (hash ^ v.to_bits()).wrapping_mul(0x100_0000_01b3);
        }
    }
    println!(
        "{rows} rows, {} epochs (best {}): {:.3} s, weights' hash {hash:016x}",
        log.train_mse.len(),
        log.best_epoch,
        t0.elapsed().as_secs_f64()
    );
}
