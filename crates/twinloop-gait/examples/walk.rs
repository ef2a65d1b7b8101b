//! Record the walk and print how the robot fared: `cargo run --example walk -- [amplitude] [kp]`.
use twinloop_gait::*;
fn main() {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let robot = twinloop_robots::resolve("builtin:lab17").unwrap();
    let mut o = DatasetOptions::default();
    if let Some(&x) = a.first() {
        o.sequence.amplitude = x;
    }
    if let Some(&x) = a.get(1) {
        o.kp_position = x;
    }
    let t = std::time::Instant::now();
    let d = record_walk(&robot, &o).unwrap();
    println!(
        "{:.1} s: max tilt {:.1} deg, fell {:?}, travel {:?}, yaw {:.1}",
        t.elapsed().as_secs_f64(),
        d.max_tilt_deg,
        d.fell_at,
        d.travel,
        d.yaw_deg
    );
    for c in 11..17 {
        let v: Vec<f64> = d.rows.iter().map(|r| r[c]).collect();
        let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        println!("{} rms {:.2} deg/s", d.columns[c], rms);
    }
}
