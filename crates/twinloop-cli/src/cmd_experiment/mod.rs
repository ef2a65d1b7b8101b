//! `twinloop experiment ...`: run the experiments whose data the identifications
//! fit: tip-over (seeds 000/001), the virtual force plate and the squat (seed 004),
//! the lab17 walk (seed 003) and the COMAN walk (seed 002).

mod bus;
mod compliant_walk;
mod lean;
mod servo;
mod squat;
mod static_poses;
mod tipover;
mod walk;

use crate::error::{CliError, CliResult};
use clap::Subcommand;
use twinloop_ident::IdentError;

#[derive(Subcommand, Debug)]
pub enum ExperimentCommand {
    /// Ramp both ankles forward, backward, left and right until the robot tips over
    ///
    /// The robot stands on its servos in the simulator (compliance slope 2: stiff). Forward
    /// and backward, both ankle pitches ramp (--ramp deg/s); left and right, both ankle
    /// rolls and both hip rolls turn together, so the legs lean as a parallelogram with the
    /// feet flat and the pelvis level (with the hips held, the two ankle axes would lock the
    /// lean into a closed chain through the ground). Each direction runs twice: a first ramp
    /// finds the tip, a second ramps to 0.5 deg before it and creeps slowly (--slow-ramp) so
    /// the detection lag does not inflate the angle. The tip is where the trunk tilts beyond
    /// what the joints explain. Recorded: the angle commanded and measured at the onset and
    /// the time taken (seed 000 Table IV), beside the model's static tipping angle (CoM over
    /// the support edge, from the joints measured at the onset; `rigid_static_deg` from the
    /// rigid standing pose). From the four angles, the CoM by the seed's geometric method
    /// (seed 000 eq 8-13) and by the exact method, next to the model's true CoM, all relative
    /// to the midpoint of the ankle axes (x forward, y left, z up).
    ///
    /// Example:
    ///   twinloop experiment tipover --robot builtin:km20 --add-mass 0.2@torso:0.05,0,0 --json tip.json
    ///
    /// On a robot over its bus (--port PORT --map MAP): the same protocol through the servos'
    /// registers (stiffened first), the tilt from the mapping's IMU board; between runs it
    /// waits for the robot to be stood up again (`serve --catch-falls` does that for a
    /// simulated one); with all four directions the JSON is the simulator's. On a serial
    /// port it asks first (--yes skips); a servo silent for longer than --silence-window
    /// (a missed read is recorded and read again until then), an overloaded/overheated/
    /// undervolted servo, or Ctrl-C, stops it with the servos holding the standing pose
    /// (exit 2); --record FILE.csv keeps every cycle read; stderr's `bus:` line (and the
    /// JSON's `bus`) counts retries, discarded packets and missed reads. See
    /// docs/adaptation.md and docs/link.md.
    ///   twinloop experiment tipover --port /tmp/km20 --map builtin:km20 --directions forward --record tip.csv
    ///
    /// Output: on stdout the four directions' commanded and measured angles, the model's
    /// static angle and the time taken, then the CoM by each method and its error;
    /// --json FILE (- for stdout) writes the same with full precision.
    #[command(verbatim_doc_comment)]
    Tipover(tipover::TipoverArgs),
    /// Lean over the ankles centre -> forward -> backward -> centre, recording ankle and knee torque
    ///
    /// Seed 001's validation motion (section F, Figs 8-11): both ankle pitches ramp (--ramp
    /// deg/s) to +amplitude (forward), hold (--hold s), ramp to -amplitude, hold, back to
    /// the centre, hold. It does not go to the fall: the amplitude is --fraction (0.3) of
    /// the model's smaller static tip angle (rigid, feet flat), or --amplitude DEG, and is
    /// refused at or beyond that angle. The servos' give leans the trunk further than the
    /// ankles' command (km20 on factory RX settings: 1.6-2.1 times): keep the fraction
    /// well below 1. Should the trunk's pitch move beyond the tip angle anyway, the robot
    /// is falling: the lean stops there (exit 2), the rows so far written.
    ///
    /// In the simulator (--robot) the torque is the servos' applied torque. Over a bus
    /// (--port PORT --map MAP) it is each servo's Present Load (0.1 % of the stall
    /// torque per count) times the datasheet stall torque of its model (RX-28 3.7 N m,
    /// RX-64 5.3 N m at 18.5 V; X series from Present Current by the stall torque over
    /// the stall current): see docs/lean-validation.md for what that conversion is worth.
    /// On a serial port it asks first (--yes skips); a servo silent for longer than
    /// --silence-window, an overloaded, overheated or undervolted servo, or Ctrl-C, stops
    /// it with the servos holding the standing pose (exit 2), and --record keeps every
    /// cycle read, as the tip-over does.
    ///
    /// Example:
    ///   twinloop experiment lean --robot builtin:km20 --out sim.csv --json -
    ///   twinloop experiment lean --port /tmp/km20 --map builtin:km20 --out robot.csv
    ///
    /// Output: OUT.csv, one row per control period (--dt), written as it comes: `t` (s
    /// from the start of the lean), `tilt:pitch` (trunk pitch from the IMU, rad, forward
    /// positive; NaN without one), and for the ankle pitches and knees `goal:<joint>`
    /// (commanded, rad), `q:<joint>` (measured, rad), `tau:<joint>` (N m): the input of
    /// `twinloop validate lean`. stdout: the mean torque and angle in each hold; --json
    /// FILE (- for stdout) writes amplitude_deg, tip_forward_deg, tip_backward_deg,
    /// ramp_deg_per_s, hold_s, rows, duration_s and per joint q_hold, tau_hold
    /// (forward, backward, centre) and tau_min, tau_max.
    #[command(verbatim_doc_comment)]
    Lean(lean::LeanArgs),
    /// Virtual force plate: statically stable poses and the CoP each would give
    ///
    /// Stands the robot (the TRUTH description: the robot as it really is) in
    /// statically stable poses in the six categories of seed 004, section 3.1:
    ///
    ///   arm     double support, feet --gap apart (2 cm), arm joints swept
    ///   left    single support on the left foot, right leg swept
    ///   right   single support on the right foot, left leg swept
    ///   torso   double support, torso (and head) joints swept
    ///   crouch  double support, knees bent, upper body varied
    ///   wide    double support, feet --wide-gap apart (20 cm), upper body random
    ///
    /// Swept joints are set systematically below 10 % and above 90 % of their range,
    /// one at a time, then at random (at least a third of each category's poses, up
    /// to 10). The soles are put flat on the ground (z = 0) by inverse kinematics
    /// over the whole configuration; on one foot the CoM is brought over the sole
    /// centre. A pose is kept only if its ground-projected CoM (GCOM) lies inside
    /// the support polygon, nothing else touches the ground and every joint is in
    /// its limits; otherwise it is drawn again. A category the robot cannot stand in
    /// is skipped (said on stderr) and its share goes to the others.
    ///
    /// Feet are found from the geometry (the lowest primitive shapes on either side);
    /// name them with --feet when that fails. The sole is the lowest face of the
    /// foot's box/cylinder/sphere shapes.
    ///
    /// Example:
    ///   twinloop experiment static-poses --robot models/unitree_h1/h1.urdf --count 172 \
    ///       --cop-noise 0.001 --joint-noise 0.0017 --seed 7 --out poses.csv
    ///
    /// Output: a CSV with one row per pose: `category` (1-6 as above), the
    /// configuration `q:base.x .. q:base.qw`, `q:<joint>` (with --joint-noise added to
    /// the joints) and the plate's centre of pressure `cop.x`, `cop.y` (the truth's
    /// GCOM plus --cop-noise), world frame, metres. stdout gets a summary: poses per
    /// category and how far inside the support polygon the GCOMs lie.
    #[command(verbatim_doc_comment)]
    StaticPoses(static_poses::StaticPosesArgs),
    /// Squat-like validation motion with force-plate readings (seed 004, Fig. 4)
    ///
    /// Makes the validation motion of seed 004, section 3.4 with the TRUTH description:
    /// standing on both feet, the pelvis goes down by --depth and up again (each half a
    /// minimum-jerk move) while the arms swing forward and the CoM stays over the middle
    /// of the feet, between --rest seconds of standing still. Each frame is solved
    /// exactly (feet flat where they stand); the plate readings are what the truth's
    /// inverse dynamics needs from the ground.
    ///
    /// Example:
    ///   twinloop experiment squat --robot models/unitree_h1/h1.urdf --out squat.csv
    ///   twinloop experiment squat --robot truth.urdf --out squat.csv \
    ///       --markers markers.toml --frames-out frames.csv --marker-noise 0.0005
    ///
    /// Output: a CSV with `t`, the configuration `q:*` and the plate: `grf.fx grf.fy
    /// grf.fz` (ground reaction on the robot, world, N), `cop.x cop.y` (m) and `grf.tz`
    /// (free moment, N m). With --markers, --frames-out gets the markers' world positions
    /// `marker:<name>.x .y .z` per frame (plus --marker-noise), input for `twinloop ik`.
    #[command(verbatim_doc_comment)]
    Squat(squat::SquatArgs),
    /// Seed 003's identification dataset: lab17 walking the sequence in the simulator
    ///
    /// The robot stands on two-loop servos (LD-2015 ratings), settles at its trims, then
    /// walks the 13-stage sequence of `twinloop gait sequence`. Every tick it reads an
    /// MPU-6050 gyro on each foot (131 LSB per deg/s, 0.05 deg/s rms noise) and then sets
    /// that tick's goals.
    ///
    /// Example (estimation record; validation record = cycles 11-20, other noise):
    ///   twinloop experiment walk --robot builtin:lab17 --out lab17_walk.csv
    ///   twinloop experiment walk --seed 2 --skip-samples 1000 --out lab17_walk_val.csv
    ///
    /// Output: a CSV with `t` (s), `u:<joint>` (the ten offsets of seed 003 eq 6, servo
    /// degrees) and `gyro:l_foot.roll|pitch|yaw`, `gyro:r_foot.roll|pitch|yaw` (deg/s),
    /// input for `twinloop identify walk`. stderr says whether the robot fell.
    #[command(verbatim_doc_comment)]
    Walk(walk::WalkArgs),
    /// COMAN walking the ZMP gait in the full simulator: seed 002's "real robot" dataset
    ///
    /// Series-elastic knee and ankle pitch joints (eq 1-6, k_j = K_h K_s/(K_h + K_s)),
    /// every other joint a stiff position servo (stiffness K_h); the ZMP/LIPM CoM
    /// reference (eq 12-13) and swing-foot trajectories go through a whole-body IK to the
    /// joints (section 4).
    ///
    /// Example:
    ///   twinloop experiment compliant-walk --robot models/coman/coman.urdf --step-length 0.03 \
    ///       --tss 0.5 --tdb 0.2 --duration 30 --out coman_walk.csv --json summary.json
    ///
    /// Output: OUT.csv with `t, xr, zr, x, z, phase` at 1 kHz: the reference CoM (xr,
    /// zr = Zc) and the simulated robot's true CoM (x, z), world frame (origin on the
    /// ground between the starting feet, x forward, z up), phase 0 single / 1 double
    /// support: input for `twinloop identify compliant`. stdout summarises the tracking;
    /// --json writes it. Exit code 1 if the robot falls.
    #[command(verbatim_doc_comment)]
    CompliantWalk(compliant_walk::CompliantWalkArgs),
    /// One servo (a pendulum bench, or one limb of a held robot) through steps, a chirp, sinusoids at three gains and a slow back-and-forth
    ///
    /// The bench of docs/servo-models.md (after Rhoban's BAM): a mass on an arm on the
    /// servo's horn, hanging at 0, free to swing to the horizontal both ways. The servo
    /// (--id, found on either protocol; RX-28, RX-64, MX-64(2.0), XM430-W350) goes
    /// through about 31 s: steps of 0.15, 0.4 and 0.8 rad, a 0.3-3 Hz chirp, 0.8 Hz
    /// sinusoids at half, the factory and twice the factory loop stiffness (RX
    /// compliance slope, MX/X P gain), and a slow triangle through zero load, all
    /// scaled by --amplitude. Each cycle writes the goal and reads position, speed,
    /// load or current, voltage and temperature in one READ, as fast as the bus
    /// answers. A pendulum heavier than 60 % of the stall torque at the horizontal is
    /// refused; a hardware fault (overload, overheating, voltage), 75 C, a silent
    /// servo or Ctrl-C stops the run with the servo holding where it is (exit 2). On a
    /// serial port it asks first (--yes skips).
    ///
    /// A limb of a held robot instead (--map MAP --joint NAME, the robot's trunk fixed
    /// in a stand, feet off the ground): every other mapped servo is set to hold
    /// where it is (torque on, its loop's registers as they were), their positions
    /// are the held pose, and the load is
    /// the subtree of links beyond the joint computed from the description (--robot,
    /// default the mapping's `urdf`): its inertia about the axis and gravity's torque
    /// A sin q + B cos q, gravity's direction from the mapping's IMU board (averaged
    /// accelerometer), else the trunk taken as upright. The sequence is centred where the joint
    /// is, its 0.8 rad step turned toward the wider side, and scaled down so that it
    /// stays 0.1 rad inside the joint's limits (the description's within the
    /// mapping's) with 20 % overshoot to spare; goals are clamped there, and a
    /// position past the limits stops the run. The log's comment lines record the
    /// robot, joint, gravity and held pose, from which `identify servo` (no --load)
    /// rebuilds the load.
    ///
    /// Example (a simulated bench, `twinloop serve --bench RX-28 --load load.toml --link
    /// /tmp/bench` running):
    ///   twinloop experiment servo --port /tmp/bench --id 1 --load load.toml --out rx28.csv
    /// A limb (`twinloop serve --robot builtin:km20 --held --link /tmp/km20` running):
    ///   twinloop experiment servo --port /tmp/km20 --map builtin:km20 --joint r_hip_pitch --out hip.csv
    ///
    /// Output: LOG.csv, its first line `# twinloop experiment servo: MODEL id N on PORT`
    /// (a limb's log then has `# limb:` lines: robot, joint, gravity, held pose, load),
    /// then `t` (s, the read sent), `goal` (rad), `t_goal` (s, when that goal was sent),
    /// `q` (rad), `v`
    /// (rad/s), `load` (fraction of full, RX; NaN otherwise), `current` (A, MX(2.0)
    /// and X; NaN otherwise), `voltage` (V), `temperature` (C), and the loop's three
    /// registers (`compliance_slope compliance_margin punch` or `p_gain i_gain
    /// d_gain`, raw): the input of `twinloop identify servo`.
    #[command(verbatim_doc_comment)]
    Servo(servo::ServoArgs),
}

pub fn run(cmd: ExperimentCommand) -> CliResult {
    match cmd {
        ExperimentCommand::Tipover(a) => tipover::run(&a),
        ExperimentCommand::Lean(a) => lean::run(&a),
        ExperimentCommand::StaticPoses(a) => static_poses::run(&a),
        ExperimentCommand::Squat(a) => squat::run(&a),
        ExperimentCommand::Walk(a) => walk::run(&a),
        ExperimentCommand::CompliantWalk(a) => compliant_walk::run(&a),
        ExperimentCommand::Servo(a) => servo::run(&a),
    }
}

/// A noise option must be a standard deviation: finite and not negative.
fn check_noise(x: f64, option: &str) -> Result<(), CliError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(
            IdentError::new(format!("{x} is not a standard deviation (finite, >= 0)"))
                .field(option)
                .into(),
        )
    }
}
