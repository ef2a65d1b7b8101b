//! km20 simulated behind its Protocol 1.0 bus, driven over a real pseudo-terminal
//! by our client: goals move the simulated joints, reads report them, and the
//! robot stands.

use std::time::{Duration, Instant};
use twinloop_link::ModelTable;
use twinloop_link::transport::{self, SerialOptions, Transport};
use twinloop_link::{Client, ClientConfig, Item, Protocol, RobotMapping, ServoModel};
use twinloop_virtual::{PtyServer, Snapshot, VirtualRobot, VirtualRobotOptions};

/// Serve `vr` on a new pty (no wire-time emulation) and open our client on it.
fn serve_on_pty(vr: VirtualRobot) -> (Client<Box<dyn Transport>>, PtyServer) {
    let server = PtyServer::start(vr, None, |_| {}).unwrap();
    let t = transport::open(server.path(), 1_000_000, &SerialOptions::default()).unwrap();
    let c = Client::with_config(
        t,
        ClientConfig {
            latency: Duration::from_millis(200),
            ..ClientConfig::default()
        },
    );
    (c, server)
}

fn km20() -> (twinloop_description::Description, RobotMapping) {
    (
        twinloop_description::builtin::resolve("builtin:km20").unwrap(),
        RobotMapping::builtin("km20").unwrap(),
    )
}

#[test]
fn km20_mapping_names_the_robots_joints_and_servos() {
    let (robot, mapping) = km20();
    assert_eq!(mapping.joints.len(), robot.joints.len());
    for j in &mapping.joints {
        let spec = twinloop_description::builtin::servo_of_joint("km20", &j.name)
            .unwrap_or_else(|| panic!("{} is not a km20 joint", j.name));
        assert_eq!(spec.name, j.model.to_string(), "{}", j.name);
    }
}

/// Trunk tilt from vertical (rad) from the IMU orientation (x, y, z, w).
fn tilt(s: &Snapshot) -> f64 {
    let [x, y, _, _] = s.state.imu.unwrap().orientation.unwrap();
    (1.0 - 2.0 * (x * x + y * y)).clamp(-1.0, 1.0).acos()
}

#[test]
fn knee_goals_over_a_pty_move_the_simulated_knees_and_km20_stands() {
    let (robot, mapping) = km20();
    let vr = VirtualRobot::new(&robot, &mapping, &VirtualRobotOptions::default()).unwrap();
    assert!(vr.unmapped.is_empty());
    let (mut c, server) = serve_on_pty(vr);
    let sim = server.sim();
    let id = |name: &str| mapping.joints.iter().find(|j| j.name == name).unwrap().id;
    let table = ServoModel::Rx64.table();
    let pos = table.item(Item::PresentPosition).unwrap();
    let load = table.item(Item::PresentLoad).unwrap();
    let goal = table.item(Item::GoalPosition).unwrap();
    let unit = 300f64.to_radians() / 1024.0;
    let mut snap = Snapshot::default();
    sim.snapshot(&mut snap);
    let h0 = snap.base_height;
    let sim_joint = {
        let s = twinloop_sim::Simulator::new(&robot, Default::default()).unwrap();
        move |name: &str| s.joint_index(name).unwrap()
    };
    let knee = sim_joint("r_knee");
    // Standing: every joint reads 0 within a unit, torque on.
    let mut b = [0u8; 2];
    c.read(Protocol::V1, id("r_knee"), pos.address, &mut b)
        .unwrap();
    let q_start = snap.state.positions[knee];
    assert!((pos.to_si(pos.decode(&b)) - q_start).abs() < 2.0 * unit);
    let mut on = [0u8; 1];
    c.read(Protocol::V1, id("r_knee"), 24, &mut on).unwrap();
    assert_eq!(on[0], 1, "torque on at start");

    // A shallow squat: hips forward, knees bent, ankles back, feet flat.
    let a = 0.25;
    let targets = [
        ("r_hip_pitch", -a),
        ("l_hip_pitch", -a),
        ("r_knee", 2.0 * a),
        ("l_knee", 2.0 * a),
        ("r_ank_pitch", -a),
        ("l_ank_pitch", -a),
    ];
    let ids: Vec<u8> = targets.iter().map(|(n, _)| id(n)).collect();
    let mut data = Vec::new();
    for (_, q) in targets {
        data.extend_from_slice(&(goal.from_si(q) as u16).to_le_bytes());
    }
    c.sync_write(Protocol::V1, goal.address, 2, &ids, &data)
        .unwrap();

    // While it moves, each read lies between the simulated knee just before and
    // just after it (within one encoder unit).
    let t0 = Instant::now();
    let mut reads = 0;
    let mut moved_during = 0;
    let mut before = Snapshot::default();
    let mut after = Snapshot::default();
    while t0.elapsed() < Duration::from_millis(1500) {
        sim.snapshot(&mut before);
        c.read(Protocol::V1, id("r_knee"), pos.address, &mut b)
            .unwrap();
        sim.snapshot(&mut after);
        let read = pos.to_si(pos.decode(&b));
        let (q0, q1) = (before.state.positions[knee], after.state.positions[knee]);
        assert!(
            read >= q0.min(q1) - unit && read <= q0.max(q1) + unit,
            "read {read} outside the simulated {q0}..{q1}"
        );
        if read > 0.05 && read < 0.4 {
            moved_during += 1;
        }
        reads += 1;
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(reads > 50, "{reads} reads");
    assert!(moved_during > 0, "no read caught the knee moving");
    let status = sim.status();
    assert!(status.error.is_none(), "{status:?}");
    // Real time: about 1.5 s simulated (more only if it could not keep up).
    assert!(status.time > 1.5, "{status:?}");

    // Settled: the knee is near its goal (a compliant servo under load sags a few
    // units), the load register matches the simulated torque, the robot stands.
    sim.snapshot(&mut snap);
    c.read(Protocol::V1, id("r_knee"), pos.address, &mut b)
        .unwrap();
    let read = pos.to_si(pos.decode(&b));
    assert!(
        (read - 2.0 * a).abs() < 0.1,
        "knee at {read}, goal {}",
        2.0 * a
    );
    assert!((read - snap.state.positions[knee]).abs() <= 1.5 * unit);
    let mut lb = [0u8; 2];
    c.read(Protocol::V1, id("r_knee"), load.address, &mut lb)
        .unwrap();
    sim.snapshot(&mut after);
    let ratio = load.to_si(load.decode(&lb));
    let torque = after.state.efforts.as_ref().unwrap()[knee];
    let stall = twinloop_description::builtin::RX64.stall_torque;
    assert!(
        torque.abs() > 0.05 * stall,
        "a bent knee carries the robot: {torque} N m"
    );
    assert!(
        (ratio - torque / stall).abs() < 0.02,
        "load {ratio} vs simulated {}",
        torque / stall
    );
    let mut vt = [0u8; 2];
    c.read(Protocol::V1, id("r_knee"), 42, &mut vt).unwrap();
    assert_eq!(vt[0], 185, "18.5 V");
    assert!((25..=30).contains(&vt[1]), "temperature {} C", vt[1]);
    // Squatting lowers the hips by 2 * 0.1 m * (1 - cos a); the trunk stays upright.
    let sink = 2.0 * 0.1 * (1.0 - a.cos());
    assert!(
        (h0 - after.base_height - sink).abs() < 0.01,
        "base from {h0} to {}, expected a drop of {sink}",
        after.base_height
    );
    assert!(tilt(&after) < 5f64.to_radians(), "tilt {}", tilt(&after));

    drop(c);
    server.stop().unwrap();
}
