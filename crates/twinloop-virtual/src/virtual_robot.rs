//! Building the simulated robot behind a bus: the simulator standing on the
//! ground, one simulated Dynamixel servo per joint, the mapping from bus servos to
//! joints, and the thread that runs it.

use crate::backend::SimServoBackend;
use crate::drive::DriveRegisters;
use crate::error::VirtualError;
use crate::runner::{Runner, ServoJoint, SimStatus};
use crate::shared::{Shared, Snapshot};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::thread::JoinHandle;
use twinloop_link::{BoardAxes, BusBoard, BusServo, Item, RobotMapping, VirtualBus};
use twinloop_sim::{Actuator, SimConfig, Simulator};

/// Settings of a virtual robot.
#[derive(Debug, Clone, PartialEq)]
pub struct VirtualRobotOptions {
    /// Simulation time step, s.
    pub dt: f64,
    /// Simulated seconds per wall-clock second (1: real time).
    pub realtime_factor: f64,
    /// Simulated time to stand still before the bus opens, so the robot has
    /// settled into its contacts, s.
    pub settle_s: f64,
    /// Servos start with torque on (as a host would leave them before an
    /// experiment). Off, the servos power on limp as real ones do, and a standing
    /// robot falls.
    pub torque_on: bool,
    /// An operator who catches the robot as it falls and stands it up again, as a
    /// person does between the runs of a tip-over experiment: once the trunk tilts
    /// beyond [`crate::CATCH_DEG`], the robot is placed upright on its feet in the pose its
    /// servos are commanded to. Off, a fall goes on to the floor (whose impacts on
    /// light links the simulator does not resolve well on a stiff floor).
    pub catch_falls: bool,
    /// How far the robot's weight sinks into the ground, m (the floor's stiffness;
    /// `None`: the simulator's default, 1 mm). The tip-over study stands on a
    /// near-rigid floor (1e-5 m), as its static references assume.
    pub ground_sink: Option<f64>,
    /// Hold the simulation while the host has been silent for longer than this,
    /// wall-clock s: a host descheduled on a loaded machine (the simulation and the
    /// host share it) would otherwise find its robot moved on without it, which a
    /// real host on its own computer does not. `None`: the robot never waits.
    pub tether_s: Option<f64>,
    /// The servos' model parameters (docs/servo-models.md): a file for every servo
    /// of its type or one per servo; servos without one keep their datasheet's.
    pub servo_params: twinloop_actuator::params_set::ServoParamsSet,
    /// The robot held in the air: its base (trunk) fixed upright, no ground, as for
    /// `experiment servo --map --joint` (one limb moved, the others holding).
    pub held: bool,
}

impl Default for VirtualRobotOptions {
    fn default() -> Self {
        VirtualRobotOptions {
            dt: 1e-3,
            realtime_factor: 1.0,
            settle_s: 0.5,
            torque_on: true,
            catch_falls: false,
            ground_sink: None,
            tether_s: None,
            servo_params: Default::default(),
            held: false,
        }
    }
}

/// A simulated robot ready to serve.
pub struct VirtualRobot {
    runner: Runner,
    shared: Arc<Shared>,
    servos: Vec<BusServo>,
    /// The protocol each servo talks, as its mapping names it (an X servo may be
    /// set to Protocol 1.0).
    protocols: Vec<twinloop_link::Protocol>,
    /// Sub-controller boards after the servos (the trunk IMU's CM-730).
    boards: Vec<(BusBoard, BoardAxes)>,
    torque_on: bool,
    /// Joints the mapping leaves off the bus (they hold their standing pose).
    pub unmapped: Vec<String>,
}

impl VirtualRobot {
    /// `robot` standing upright on the ground (or held, [`VirtualRobotOptions::held`])
    /// with every joint at 0 (or the nearest limit), each joint driven by its servo
    /// ([`twinloop_sim::servo_for_joint`]); the servos of `mapping` are the
    /// bus's, tied to joints by name.
    pub fn new(
        robot: &twinloop_description::Description,
        mapping: &RobotMapping,
        options: &VirtualRobotOptions,
    ) -> Result<VirtualRobot, VirtualError> {
        let mut sim = simulator(robot, options)?;
        let nb = sim.model.nbodies;
        let (servos, on_bus) = bus_servos(&mut sim, robot, mapping, options)?;
        let boards = place_boards(&mut sim, robot, mapping)?;
        if !options.held {
            // A robot served "standing" on nothing would answer with zero load: refused
            // with the words `simulate` uses.
            sim.check_can_stand()?;
        }
        let standing = twinloop_sim::standing_pose(&sim.model);
        sim.place_on_ground(&standing)?;
        sim.run(options.settle_s.max(0.0))
            .map_err(|e| VirtualError::from(e).context("the robot does not stand"))?;
        let unmapped = (0..nb)
            .filter(|&i| !on_bus[i])
            .map(|i| sim.model.joint_names[i].clone())
            .collect();
        // `servos` is in the mapping's joint order.
        let registers: Vec<DriveRegisters> = servos
            .iter()
            .zip(&mapping.joints)
            .map(|(s, j)| {
                let q = sim.q[sim.model.q_offset + s.joint];
                DriveRegisters::for_model(s.zero + s.direction * q, j.model)
            })
            .collect();
        let shared = Arc::new(Shared::new(registers));
        let mut runner = Runner::new(sim, servos, shared.clone(), options.realtime_factor);
        runner.catch_falls = options.catch_falls;
        runner.tether_s = options.tether_s;
        runner.imu_on_bus = !mapping.boards.is_empty();
        runner.publish();
        Ok(VirtualRobot {
            runner,
            shared,
            servos: mapping
                .joints
                .iter()
                .map(|j| BusServo {
                    id: j.id,
                    model: j.model,
                })
                .collect(),
            protocols: mapping.joints.iter().map(|j| j.protocol).collect(),
            boards,
            torque_on: options.torque_on,
            unmapped,
        })
    }

    /// The bus: one virtual servo per mapped joint, answering from the simulation,
    /// then the mapping's boards, whose gyro and accelerometer read the simulated
    /// IMU; torque on if the options say so.
    pub fn bus(&self) -> VirtualBus<SimServoBackend> {
        let backend = SimServoBackend {
            shared: self.shared.clone(),
            models: self.servos.iter().map(|s| s.model).collect(),
            boards: self.boards.iter().map(|b| b.1).collect(),
        };
        let boards: Vec<BusBoard> = self.boards.iter().map(|b| b.0).collect();
        let mut bus = VirtualBus::with_boards(&self.servos, &boards, backend);
        for (k, &protocol) in self.protocols.iter().enumerate() {
            // The mapping only names protocols its servos speak (checked on load).
            let _ = bus.set_protocol(k, protocol);
        }
        if self.torque_on {
            for k in 0..self.servos.len() {
                // Torque Enable 1 is within every table's range: cannot fail.
                let _ = bus.host_write(k, Item::TorqueEnable, 1);
            }
        }
        bus
    }

    /// The simulator itself (before it runs on its thread).
    pub fn simulator(&mut self) -> &mut Simulator {
        &mut self.runner.sim
    }

    /// Advance `seconds` of simulated time on the caller's thread, with the
    /// registers as the bus left them (tests; [`VirtualRobot::spawn`] runs it in
    /// real time).
    pub fn step_for(&mut self, seconds: f64) -> Result<(), VirtualError> {
        self.runner.take_registers();
        let n = (seconds / self.runner.sim.dt()).round() as u64;
        for _ in 0..n {
            self.runner.step()?;
            self.runner.operator()?;
        }
        self.runner.publish();
        Ok(())
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.runner.sim.time
    }

    /// Times the operator caught the robot (see [`VirtualRobotOptions::catch_falls`]).
    pub fn pick_ups(&self) -> u64 {
        self.runner.pick_ups
    }

    /// The latest snapshot.
    pub fn snapshot(&self, out: &mut Snapshot) {
        out.copy_from(
            &self
                .shared
                .snapshot
                .lock()
                .unwrap_or_else(|e| e.into_inner()),
        );
    }

    /// Run the simulation on its own thread, in real time.
    pub fn spawn(self) -> SimHandle {
        let shared = self.shared.clone();
        let runner = self.runner;
        let thread = std::thread::Builder::new()
            .name("twinloop-sim".into())
            .spawn(move || runner.run())
            .ok();
        SimHandle { shared, thread }
    }
}

/// The simulator `robot` is served from: standing on the ground (the contact's
/// sink from the options) or held, each joint driven by its servo.
fn simulator(
    robot: &twinloop_description::Description,
    options: &VirtualRobotOptions,
) -> Result<Simulator, VirtualError> {
    // Four corners per sole, two soles: the weight shares eight points.
    let contact = options
        .ground_sink
        .map(|sink| twinloop_sim::ContactParams::for_robot(robot.total_mass(), 8, sink));
    let config = SimConfig {
        dt: options.dt,
        contact,
        ground: !options.held,
        ..SimConfig::default()
    };
    let mut sim = if options.held {
        // The trunk welded upright where the description puts it (base frame =
        // world frame); with no ground nothing else touches the robot.
        let model = twinloop_dynamics::Model::from_description_with_base(
            robot,
            twinloop_dynamics::BaseKind::Fixed,
        )?;
        Simulator::from_model(robot, model, config)
    } else {
        Simulator::new(robot, config)
    }?;
    for i in 0..sim.model.nbodies {
        let s = twinloop_sim::servo_for_joint(&robot.name, &sim.model, i);
        sim.actuators[i] = Actuator::Dynamixel(s);
    }
    Ok(sim)
}

/// The bus's servos, in the mapping's joint order, tied to `sim`'s joints by name
/// (with their parameters from the options' `--servo-params`), and which joints
/// are on the bus.
fn bus_servos(
    sim: &mut Simulator,
    robot: &twinloop_description::Description,
    mapping: &RobotMapping,
    options: &VirtualRobotOptions,
) -> Result<(Vec<ServoJoint>, Vec<bool>), VirtualError> {
    let nb = sim.model.nbodies;
    let mut servos = Vec::with_capacity(mapping.joints.len());
    let mut on_bus = vec![false; nb];
    let mut slots = Vec::with_capacity(mapping.joints.len());
    for j in &mapping.joints {
        let at = if j.line > 0 {
            format!("{}:{}", mapping.source, j.line)
        } else {
            mapping.source.clone()
        };
        let Some(i) = sim.joint_index(&j.name) else {
            return Err(VirtualError::new(format!(
                "{at}: joint \"{}\" (id {}) is not a joint of robot \"{}\" (its joints: {})",
                j.name,
                j.id,
                robot.name,
                sim.model.joint_names.join(", ")
            )));
        };
        if on_bus[i] {
            return Err(VirtualError::new(format!(
                "{at}: joint \"{}\" is mapped to two servos",
                j.name
            )));
        }
        on_bus[i] = true;
        let slot = twinloop_actuator::params_set::ServoSlot {
            id: Some(j.id),
            joint: &j.name,
            servo: twinloop_actuator::ServoType::parse(j.model.name()),
        };
        if let Some(p) = options.servo_params.for_servo(slot, "--servo-params")? {
            sim.set_servo_params(i, p);
        }
        slots.push(slot);
        let Actuator::Dynamixel(base) = sim.actuators[i] else {
            // `simulator` gives every joint a servo; a caller's own simulator may not.
            return Err(VirtualError::new(format!(
                "{at}: joint \"{}\" has no servo in the simulation",
                j.name
            )));
        };
        let spec = j.model.spec();
        servos.push(ServoJoint {
            joint: i,
            zero: j.zero,
            direction: j.direction,
            base,
            torque_scale: spec.stall_torque / base.stall_torque,
            voltage: spec.voltage,
        });
    }
    options.servo_params.check_used(&slots, "--servo-params")?;
    Ok((servos, on_bus))
}

/// Put the simulator's IMU on the link of the mapping's boards (one IMU: every
/// board must be on the same link) and return the boards with their axes.
fn place_boards(
    sim: &mut Simulator,
    robot: &twinloop_description::Description,
    mapping: &RobotMapping,
) -> Result<Vec<(BusBoard, BoardAxes)>, VirtualError> {
    let mut imu_link: Option<(usize, &str)> = None;
    let mut out = Vec::with_capacity(mapping.boards.len());
    for b in &mapping.boards {
        let at = if b.line > 0 {
            format!("{}:{}", mapping.source, b.line)
        } else {
            mapping.source.clone()
        };
        let Some(link) = sim.model.links.iter().position(|l| l.name == b.link) else {
            let names: Vec<&str> = sim.model.links.iter().map(|l| l.name.as_str()).collect();
            return Err(VirtualError::new(format!(
                "{at}: board \"{}\": link \"{}\" is not a link of robot \"{}\" (its links: {})",
                b.name,
                b.link,
                robot.name,
                names.join(", ")
            )));
        };
        if let Some((other, name)) = imu_link
            && other != link
        {
            return Err(VirtualError::new(format!(
                "{at}: board \"{}\" is on link \"{}\", board \"{name}\" on another: the simulated robot has one IMU",
                b.name, b.link
            )));
        }
        imu_link = Some((link, &b.name));
        sim.sensors_mut().imu_link = link;
        out.push((
            BusBoard {
                id: b.id,
                board: b.kind,
            },
            b.axes,
        ));
    }
    Ok(out)
}

/// The running simulation. Dropping it stops the thread.
pub struct SimHandle {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<Simulator>>,
}

impl SimHandle {
    /// Copy the latest snapshot into `out` (no allocation once `out` is sized).
    pub fn snapshot(&self, out: &mut Snapshot) {
        out.copy_from(
            &self
                .shared
                .snapshot
                .lock()
                .unwrap_or_else(|e| e.into_inner()),
        );
    }

    pub fn status(&self) -> SimStatus {
        let s = self
            .shared
            .snapshot
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        SimStatus {
            time: s.time,
            steps: s.steps,
            behind_s: s.behind_s,
            error: s.error.clone(),
        }
    }

    /// Whether the thread is running (it could not be started, or it panicked).
    pub fn is_running(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// Stop the simulation and hand back the simulator.
    pub fn stop(mut self) -> Option<Simulator> {
        self.shared.stop.store(true, Ordering::Relaxed);
        self.thread.take().and_then(|t| t.join().ok())
    }
}

impl Drop for SimHandle {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
