//! The simulator step on OP3 (`models/op3/mjcf/op3.xml`) standing on its datasheet
//! servos (as `twinloop bench sim --servo auto`) or following a goal trajectory (the
//! walking case of `bench/mujoco/compare_sim.py`), for callgrind's instruction counts
//! and for checking that a change keeps the results: after the run it prints a hash
//! of the state's bits (q, v, the applied torques, every contact force).
//!
//! `cargo bench --profile ci -p twinloop-sim --bench step -- [--dt S] [--steps N]
//! [--walk FILE.csv]`; the walk's CSV is `bench/mujoco/walk_trajectory.py --out`'s
//! (`t`, `q:<joint>`, goals interpolated linearly as `bench sim --trajectory` does).
//! Settles 0.5 s first, as `bench sim` does.

use std::time::Instant;
use twinloop_sim::{SimConfig, Simulator};

struct Walk {
    t: Vec<f64>,
    /// Per row, per model joint: the goal (NaN where the file has no column).
    rows: Vec<Vec<f64>>,
}

fn read_walk(path: &str, sim: &Simulator) -> Walk {
    let text = std::fs::read_to_string(path).expect("the walk's CSV");
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let cols: Vec<Option<usize>> = sim
        .model
        .joint_names
        .iter()
        .map(|n| head.iter().position(|h| *h == format!("q:{n}")))
        .collect();
    let (mut t, mut rows) = (Vec::new(), Vec::new());
    for l in lines.filter(|l| !l.trim().is_empty()) {
        let x: Vec<f64> = l.split(',').map(|s| s.trim().parse().unwrap()).collect();
        t.push(x[0]);
        rows.push(cols.iter().map(|c| c.map_or(f64::NAN, |c| x[c])).collect());
    }
    Walk { t, rows }
}

impl Walk {
    fn at(&self, time: f64, hold: &[f64], out: &mut [f64]) {
        let k = self.t.partition_point(|&x| x <= time);
        let (i0, i1, w) = if k == 0 {
            (0, 0, 0.0)
        } else if k >= self.t.len() {
            (self.t.len() - 1, self.t.len() - 1, 0.0)
        } else {
            let (a, b) = (self.t[k - 1], self.t[k]);
            (k - 1, k, (time - a) / (b - a))
        };
        for (j, o) in out.iter_mut().enumerate() {
            let (a, b) = (self.rows[i0][j], self.rows[i1][j]);
            *o = if a.is_nan() {
                hold[j]
            } else {
                a * (1.0 - w) + b * w
            };
        }
    }
}

/// FNV-1a over the bits of the state and the step's outputs.
fn state_hash(sim: &Simulator) -> u64 {
    let mut h = 0xcbf29ce484222325u64;
    let mut eat = |x: f64| {
        h ^= x.to_bits();
        h = h.wrapping_mul(0x100000001b3);
    };
    sim.q
        .iter()
        .chain(&sim.v)
        .chain(&sim.applied)
        .for_each(|&x| eat(x));
    for c in sim.contact_states() {
        c.force
            .iter()
            .chain(c.position.iter())
            .for_each(|&x| eat(x));
    }
    h
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let opt = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .map(|k| args[k + 1].clone())
    };
    let dt: f64 = opt("--dt").map_or(2e-3, |s| s.parse().unwrap());
    let steps: usize = opt("--steps").map_or(2000, |s| s.parse().unwrap());
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/op3/mjcf/op3.xml");
    let robot = twinloop_description::load(root).expect("OP3's MJCF");
    let cfg = SimConfig {
        dt,
        ..Default::default()
    };
    let (mut sim, _) = Simulator::standing_on_datasheet_servos(&robot, cfg).unwrap();
    sim.run(0.5).unwrap();
    let walk = opt("--walk").map(|p| read_walk(&p, &sim));
    let hold = sim.goals.clone();
    let mut goals = hold.clone();
    let t = Instant::now();
    for k in 0..steps {
        if let Some(w) = &walk {
            w.at(k as f64 * dt, &hold, &mut goals);
            sim.goals.copy_from_slice(&goals);
        }
        sim.step().unwrap();
    }
    let us = t.elapsed().as_secs_f64() * 1e6 / steps as f64;
    println!(
        "{} dt {dt}: {steps} steps, {us:.2} us/step, state hash {:016x}",
        if walk.is_some() {
            "walking"
        } else {
            "standing"
        },
        state_hash(&sim)
    );
}
