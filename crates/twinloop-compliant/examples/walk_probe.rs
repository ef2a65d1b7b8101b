use twinloop_compliant::walking::{ComanWalker, WalkingConfig, write_csv};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let robot = twinloop_model::load(std::path::Path::new("models/coman/coman.urdf")).unwrap();
    let mut c = WalkingConfig::default();
    c.duration = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(5.0);
    if let Some(k) = args.get(2) { c.k_series = k.parse().unwrap(); }
    if let Some(k) = args.get(3) { c.step_length = k.parse().unwrap(); }
    if let Some(k) = args.get(4) { c.t_single = k.parse().unwrap(); }
    if let Some(k) = args.get(5) { c.spring_damping = k.parse().unwrap(); }
    if let Some(k) = args.get(6) { c.substeps = k.parse().unwrap(); }
    if let Ok(k) = std::env::var("SINK") { c.contact_sink = k.parse().unwrap(); }
    if let Ok(k) = std::env::var("LIFT") { c.swing_height = k.parse().unwrap(); }
    if let Ok(k) = std::env::var("BEND") { c.knee_bend = k.parse().unwrap(); }
    if let Ok(k) = std::env::var("KP") { let v: Vec<f64> = k.split(',').map(|x| x.parse().unwrap()).collect(); c.balance_kp = [v[0], v[1]]; }
    if let Ok(k) = std::env::var("KD") { let v: Vec<f64> = k.split(',').map(|x| x.parse().unwrap()).collect(); c.balance_kd = [v[0], v[1]]; }
    let t0 = std::time::Instant::now();
    let mut w = ComanWalker::new(&robot, &c).unwrap();
    let t1 = t0.elapsed();
    let r = w.run(|_, _| {});
    println!("ik {:?} total {:?}", t1, t0.elapsed());
    match r {
        Ok(d) => { println!("{:#?}", d.summary); write_csv(std::path::Path::new("/tmp/walk_probe.csv"), &d.rows).unwrap(); }
        Err(e) => println!("ERR {e}"),
    }
}
