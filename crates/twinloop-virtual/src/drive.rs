//! What a servo's registers mean for the simulated servo: goal, torque on/off,
//! compliance (RX), position gain (MX, X), moving speed and torque limit, turned
//! into the parameters of the simulator's [`DynamixelServo`].

use twinloop_link::ModelTable;
use twinloop_link::servos::LoopFamily;
use twinloop_link::{Item, ServoModel, Unit};
use twinloop_sim::DynamixelServo;

/// The registers that shape one servo's motion, in SI units (servo angles: radians
/// from the servo's centre, counter-clockwise positive). Written by the bus thread,
/// read by the simulator thread.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveRegisters {
    /// Goal Position, rad.
    pub goal: f64,
    pub torque_on: bool,
    /// Compliance margin, clockwise and counter-clockwise, rad (RX only).
    pub margin: Option<[f64; 2]>,
    /// Compliance slope as the error of full torque, clockwise and counter-clockwise,
    /// rad (RX only).
    pub slope: Option<[f64; 2]>,
    /// Position P gain over its factory value (MX on Protocol 1.0, whose e-manual
    /// gives the loop's output no unit; `None` on RX).
    pub p_ratio: Option<f64>,
    /// The error at which the Position P Gain drives full PWM, rad (MX(2.0) and X:
    /// EM-XM430's PWM = P/128 * error in counts, full PWM 885; the catalogue's
    /// `ServoModel::full_output_error`): the loop's stiffness itself, not relative to
    /// the joint's servo.
    pub p_full_error: Option<f64>,
    /// Speed towards the goal, rad/s; 0: as fast as the motor goes (Moving Speed 0 on
    /// RX, Profile Velocity 0 on X).
    pub moving_speed: f64,
    /// Torque Limit (RX) or PWM Limit (X) as a fraction of full torque.
    pub torque_limit: f64,
    /// Profile Acceleration (MX(2.0), X), rad/s^2; 0: none.
    pub profile_acceleration: f64,
    /// Raw Punch (RX), Position I and D Gain (MX, X) as written; `None`: the file's
    /// servo keeps its factory value. Only a full-model servo (a parameter file) has
    /// them.
    pub punch: Option<f64>,
    pub i_gain: Option<f64>,
    pub d_gain: Option<f64>,
}

impl DriveRegisters {
    /// At rest at `goal`, torque off, factory values.
    pub fn new(goal: f64) -> DriveRegisters {
        DriveRegisters {
            goal,
            torque_on: false,
            margin: None,
            slope: None,
            p_ratio: None,
            p_full_error: None,
            moving_speed: 0.0,
            torque_limit: 1.0,
            profile_acceleration: 0.0,
            punch: None,
            i_gain: None,
            d_gain: None,
        }
    }

    /// At rest at `goal`, torque off, the factory values of `model`: an MX or X
    /// servo starts as a PID loop (no dead band) at its factory P gain, on MX(2.0)
    /// and X with that gain's stiffness (800 on an XM430-W350: full PWM at 141.6
    /// counts, 12.4 deg).
    pub fn for_model(goal: f64, model: ServoModel) -> DriveRegisters {
        let mut r = DriveRegisters::new(goal);
        if let (Some(LoopFamily::Pid), Some([p, _, _])) = (model.family(), model.factory_gains()) {
            r.set(model, Item::PositionPGain, p);
        }
        r
    }

    /// Take a register's raw value (see
    /// [`VirtualServoBackend::register_written`](twinloop_link::VirtualServoBackend::register_written)).
    pub fn set(&mut self, model: ServoModel, item: Item, raw: i32) {
        let table = model.table();
        let Some(r) = table.item(item) else { return };
        // Compliance is in position units of this model.
        let unit = match table.item(Item::GoalPosition).map(|g| g.unit) {
            Some(Unit::Angle { rad_per_unit, .. }) => rad_per_unit,
            _ => 0.0,
        };
        match item {
            Item::CwComplianceMargin | Item::CcwComplianceMargin => {
                let m = self.margin.get_or_insert([unit; 2]);
                m[usize::from(item == Item::CcwComplianceMargin)] = raw.max(0) as f64 * unit;
            }
            Item::CwComplianceSlope | Item::CcwComplianceSlope => {
                let s = self.slope.get_or_insert([32.0 * unit; 2]);
                s[usize::from(item == Item::CcwComplianceSlope)] = rx_slope_units(raw) * unit;
            }
            Item::PositionPGain => match model.full_output_error(raw) {
                Some(e) => self.p_full_error = Some(e),
                None => {
                    let factory = r.initial.unwrap_or(raw).max(1) as f64;
                    self.p_ratio = Some(raw.max(0) as f64 / factory);
                }
            },
            Item::ProfileAcceleration => {
                let mut p = twinloop_actuator::profile::Profile::default();
                p.set_acceleration_register(raw as f64);
                self.profile_acceleration = p.acceleration;
            }
            Item::Punch => self.punch = Some(raw.max(0) as f64),
            Item::PositionIGain => self.i_gain = Some(raw.max(0) as f64),
            Item::PositionDGain => self.d_gain = Some(raw.max(0) as f64),
            Item::MovingSpeed => {
                self.moving_speed = match r.unit {
                    Unit::AngularVelocity { rad_s_per_unit } => raw.max(0) as f64 * rad_s_per_unit,
                    _ => 0.0,
                };
            }
            // RX has Torque Limit (RAM, starts at Max Torque); X has only PWM Limit
            // (the MaxTorque item), which then is the limit.
            Item::TorqueLimit => self.torque_limit = fraction(raw, r.max),
            Item::MaxTorque if table.item(Item::TorqueLimit).is_none() => {
                self.torque_limit = fraction(raw, r.max)
            }
            _ => {}
        }
    }
}

fn fraction(raw: i32, full: i32) -> f64 {
    (raw.max(0) as f64 / full.max(1) as f64).clamp(0.0, 1.0)
}

/// The slope an RX applies for a Compliance Slope register value: only seven steps
/// exist, 2, 4, ..., 128 units, each register value using the power of two at or
/// below it (0-3 -> 2, 4-7 -> 4, ..., 128-254 -> 128; EM-RX28 "Compliance Slope").
pub fn rx_slope_units(raw: i32) -> f64 {
    let v = raw.clamp(2, 255) as u32;
    let step = 1u32 << (31 - v.leading_zeros());
    step.min(128) as f64
}

/// The simulator's servo for one moment: `base` (the joint's servo, from its
/// datasheet) with the registers applied. `ccw` says which way the servo turns to
/// reach its goal: RX compliance differs per direction. A P gain scales the slope
/// (full torque at an error `p_ratio` times smaller). The datasheet servo has one
/// proportional loop: I and D gains, Punch and Profile Acceleration are kept in the
/// table only; a servo from a parameter file (`--servo-params`, the full model) takes
/// them, and its firmware runs the profile.
pub fn servo_with_registers(
    base: &DynamixelServo,
    regs: &DriveRegisters,
    ccw: bool,
) -> DynamixelServo {
    let mut s = *base;
    let side = usize::from(ccw);
    if let Some(m) = regs.margin {
        s.compliance_margin = m[side];
    }
    if let Some(sl) = regs.slope {
        s.compliance_slope = sl[side].max(1e-6);
    }
    if let Some(e) = regs.p_full_error {
        // A PID loop has no dead band; P = 0 never reaches full PWM.
        s.compliance_margin = 0.0;
        s.compliance_slope = if e.is_finite() { e.max(1e-6) } else { f64::MAX };
    }
    if let Some(p) = regs.p_ratio {
        s.compliance_margin = 0.0;
        // P = 0: no position control at all (full torque at an error never reached).
        s.compliance_slope = if p > 0.0 {
            base.compliance_slope / p
        } else {
            f64::MAX
        };
    }
    s.torque_limit = regs.torque_limit;
    // A full-model servo runs its own profile, punch and I and D terms.
    if let Some(full) = &mut s.full {
        full.profile_velocity = regs.moving_speed;
        full.profile_acceleration = regs.profile_acceleration;
        if let Some(p) = regs.punch {
            full.punch = p;
        }
        if let Some(i) = regs.i_gain {
            full.i_gain = i;
        }
        if let Some(d) = regs.d_gain {
            full.d_gain = d;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rx_slope_steps() {
        let want = [
            (0, 2.0),
            (3, 2.0),
            (4, 4.0),
            (31, 16.0),
            (32, 32.0),
            (127, 64.0),
            (128, 128.0),
            (254, 128.0),
        ];
        for (raw, units) in want {
            assert_eq!(rx_slope_units(raw), units, "raw {raw}");
        }
    }

    #[test]
    fn registers_become_servo_parameters() {
        let unit = (300.0f64 / 1024.0).to_radians();
        let mut r = DriveRegisters::new(0.0);
        r.set(ServoModel::Rx28, Item::CwComplianceSlope, 8);
        r.set(ServoModel::Rx28, Item::CcwComplianceSlope, 64);
        r.set(ServoModel::Rx28, Item::CwComplianceMargin, 0);
        r.set(ServoModel::Rx28, Item::CcwComplianceMargin, 3);
        r.set(ServoModel::Rx28, Item::TorqueLimit, 512);
        r.set(ServoModel::Rx28, Item::MovingSpeed, 100);
        let base = DynamixelServo::rx28();
        let cw = servo_with_registers(&base, &r, false);
        let ccw = servo_with_registers(&base, &r, true);
        assert!((cw.compliance_slope - 8.0 * unit).abs() < 1e-4 * unit);
        assert!((ccw.compliance_slope - 64.0 * unit).abs() < 1e-4 * unit);
        assert_eq!(cw.compliance_margin, 0.0);
        assert!((ccw.compliance_margin - 3.0 * unit).abs() < 1e-4 * unit);
        assert!((cw.torque_limit - 512.0 / 1023.0).abs() < 1e-12);
        // 100 units of 0.111 rpm.
        assert!((r.moving_speed - 100.0 * 0.111 * std::f64::consts::TAU / 60.0).abs() < 1e-9);
        // X-series: the P gain is the loop's stiffness as EM-XM430 states it, PWM =
        // P/128 * error (counts), full PWM 885: P 1600 reaches it at 70.8 counts; no
        // dead band. PWM Limit is the torque limit.
        let count = std::f64::consts::TAU / 4096.0;
        let mut x = DriveRegisters::for_model(0.0, ServoModel::Xm430W350);
        // Factory P 800: 141.6 counts.
        let s = servo_with_registers(&base, &x, true);
        assert!((s.compliance_slope - 141.6 * count).abs() < 1e-9);
        x.set(ServoModel::Xm430W350, Item::PositionPGain, 1600);
        x.set(ServoModel::Xm430W350, Item::MaxTorque, 885 / 5);
        let s = servo_with_registers(&base, &x, true);
        assert!((s.compliance_slope - 70.8 * count).abs() < 1e-9);
        assert_eq!(s.compliance_margin, 0.0);
        assert!((s.torque_limit - 177.0 / 885.0).abs() < 1e-12);
        // MX (1.0): relative to the factory P 32.
        let mut m = DriveRegisters::for_model(0.0, ServoModel::Mx28);
        assert_eq!((m.p_full_error, m.p_ratio), (None, Some(1.0)));
        m.set(ServoModel::Mx28, Item::PositionPGain, 64);
        let s = servo_with_registers(&base, &m, true);
        assert!((s.compliance_slope - base.compliance_slope / 2.0).abs() < 1e-12);
    }
}

#[cfg(test)]
mod full_model_tests {
    use super::*;
    use twinloop_actuator::datasheet::defaults;
    use twinloop_actuator::{ModelLevel, ServoType};

    #[test]
    fn a_parameter_files_servo_takes_gains_punch_and_profile() {
        let x = twinloop_sim::servo_from_params(&defaults(ServoType::Xm430W350, ModelLevel::M1));
        let mut r = DriveRegisters::new(0.0);
        r.set(ServoModel::Xm430W350, Item::PositionIGain, 300);
        r.set(ServoModel::Xm430W350, Item::PositionDGain, 1200);
        r.set(ServoModel::Xm430W350, Item::MovingSpeed, 100);
        r.set(ServoModel::Xm430W350, Item::ProfileAcceleration, 10);
        let s = servo_with_registers(&x, &r, true);
        let f = s.full.unwrap();
        assert_eq!((f.i_gain, f.d_gain), (300.0, 1200.0));
        // EM-XM430: 0.229 rpm and 214.577 rev/min^2 per unit.
        assert!((f.profile_velocity - 22.9 * std::f64::consts::TAU / 60.0).abs() < 1e-9);
        assert!((f.profile_acceleration - 2145.77 * std::f64::consts::TAU / 3600.0).abs() < 1e-9);
        let rx = twinloop_sim::servo_from_params(&defaults(ServoType::Rx28, ModelLevel::M1));
        let mut r = DriveRegisters::new(0.0);
        r.set(ServoModel::Rx28, Item::Punch, 100);
        assert_eq!(
            servo_with_registers(&rx, &r, true).full.unwrap().punch,
            100.0
        );
    }
}
