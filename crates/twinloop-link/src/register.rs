//! One entry of a servo's control table: where it lives, how its bytes encode a
//! number, and what that number means in SI units.

use std::f64::consts::PI;

/// Whether the host may write a register.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    Read,
    ReadWrite,
}

/// EEPROM registers survive power-off and, on Protocol 2.0 servos, can only be
/// written with torque off; RAM registers are reset at power-on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Area {
    Eeprom,
    Ram,
}

/// How a register's little-endian bytes encode a number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    Unsigned,
    /// Two's complement (Protocol 2.0 velocities, currents, positions).
    Signed,
    /// Protocol 1.0 speed and load: bits 0-9 magnitude, bit 10 direction
    /// (1 = clockwise, reported here as negative; counter-clockwise is positive like
    /// increasing position).
    SignMagnitude,
}

/// The physical meaning of one raw unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Unit {
    /// A number without physical unit: ids, modes, flags, gains, counts.
    Raw,
    /// An angle: `(raw - center) * rad_per_unit` radians from the middle of the range.
    Angle { rad_per_unit: f64, center: i32 },
    /// Angular velocity, rad/s per unit.
    AngularVelocity { rad_s_per_unit: f64 },
    /// Load as a fraction of the maximum torque per unit (1.0 = 100 %).
    LoadRatio { per_unit: f64 },
    /// Motor current: `(raw - zero) * amps_per_unit` amperes (zero is 0, except
    /// MX(1.0) Current, which idles at 2048).
    Current { amps_per_unit: f64, zero: i32 },
    /// Volts per unit.
    Voltage { volts_per_unit: f64 },
    /// Degrees Celsius, one per unit (the only non-SI unit: it is what servos report
    /// and what people read; kelvin would help nobody).
    Celsius,
    /// Seconds per unit (Return Delay Time: 2 us; Realtime Tick: 1 ms).
    Duration { seconds_per_unit: f64 },
    /// A gyroscope axis: `(raw - center) * rad_s_per_unit` rad/s (CM-730: 10 bits
    /// centred on 512).
    Gyro { rad_s_per_unit: f64, center: i32 },
    /// An accelerometer axis: `(raw - center) * m_s2_per_unit` m/s^2 of specific
    /// force (CM-730: 10 bits centred on 512).
    Accel { m_s2_per_unit: f64, center: i32 },
}

impl Unit {
    /// How the value of [`Register::to_si`] is written ("" for a raw number).
    pub const fn name(&self) -> &'static str {
        match self {
            Unit::Raw => "",
            Unit::Angle { .. } => "rad",
            Unit::AngularVelocity { .. } | Unit::Gyro { .. } => "rad/s",
            Unit::LoadRatio { .. } => "of max torque",
            Unit::Current { .. } => "A",
            Unit::Voltage { .. } => "V",
            Unit::Celsius => "degC",
            Unit::Duration { .. } => "s",
            Unit::Accel { .. } => "m/s^2",
        }
    }
}

/// One register's value as read: its place in the table, the raw number and the same
/// in SI units (for scripts as JSON: serialised with these field names).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Reading {
    pub address: u16,
    pub name: &'static str,
    pub size: u8,
    /// "R" (read only) or "RW".
    pub access: &'static str,
    pub raw: i32,
    pub value: f64,
    pub unit: &'static str,
}

/// Revolutions per minute to rad/s.
pub const RPM: f64 = 2.0 * PI / 60.0;
/// One degree in radians.
pub const DEGREE: f64 = PI / 180.0;

/// Well-known items, so code asks a table for "present position" rather than an
/// address that differs between models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Item {
    ModelNumber,
    FirmwareVersion,
    Id,
    BaudRate,
    ReturnDelayTime,
    OperatingMode,
    ProtocolType,
    HomingOffset,
    /// CW Angle Limit in 1.0, Min Position Limit in 2.0.
    MinPositionLimit,
    /// CCW Angle Limit in 1.0, Max Position Limit in 2.0.
    MaxPositionLimit,
    TemperatureLimit,
    MinVoltageLimit,
    MaxVoltageLimit,
    /// Max Torque (1.0) or PWM Limit (2.0).
    MaxTorque,
    CurrentLimit,
    VelocityLimit,
    StatusReturnLevel,
    Shutdown,
    TorqueEnable,
    Led,
    GoalPosition,
    /// Moving Speed (1.0, joint mode: speed towards the goal) or Profile Velocity
    /// (2.0).
    MovingSpeed,
    /// Profile Acceleration (2.0).
    ProfileAcceleration,
    GoalVelocity,
    GoalCurrent,
    /// Torque Limit (1.0, RAM).
    TorqueLimit,
    PresentPosition,
    PresentVelocity,
    PresentLoad,
    PresentCurrent,
    PresentVoltage,
    PresentTemperature,
    Registered,
    Moving,
    /// The speed above which Moving reads 1 (2.0: Moving Threshold(24)).
    MovingThreshold,
    Lock,
    HardwareErrorStatus,
    RealtimeTick,
    /// 1.0 RX compliance: the dead band and the error of full torque, per direction.
    CwComplianceMargin,
    CcwComplianceMargin,
    CwComplianceSlope,
    CcwComplianceSlope,
    /// Position loop gains (MX "P/I/D Gain" in 1.0, "Position P/I/D Gain" in 2.0).
    PositionPGain,
    PositionIGain,
    PositionDGain,
    /// Minimum drive current (1.0).
    Punch,
    /// A sub-controller's gyroscope (angular rate about the board's X, Y, Z axes)
    /// and accelerometer (specific force along them).
    GyroX,
    GyroY,
    GyroZ,
    AccelX,
    AccelY,
    AccelZ,
}

/// One control-table register.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Register {
    pub name: &'static str,
    pub item: Option<Item>,
    pub address: u16,
    /// Bytes: 1, 2 or 4.
    pub size: u8,
    pub access: Access,
    pub area: Area,
    /// Factory value, where the e-manual gives one.
    pub initial: Option<i32>,
    /// Valid range of the (decoded) value; a write outside it is a range error.
    pub min: i32,
    pub max: i32,
    pub encoding: Encoding,
    pub unit: Unit,
}

impl Register {
    /// Address one past the last byte.
    pub const fn end(&self) -> u16 {
        self.address + self.size as u16
    }

    /// Decode the register's bytes (exactly `size` of them, little-endian).
    pub fn decode(&self, bytes: &[u8]) -> i32 {
        let mut u: u32 = 0;
        for (k, &b) in bytes.iter().take(self.size as usize).enumerate() {
            u |= (b as u32) << (8 * k);
        }
        match self.encoding {
            Encoding::Unsigned => u as i32,
            Encoding::Signed => match self.size {
                1 => u as u8 as i8 as i32,
                2 => u as u16 as i16 as i32,
                _ => u as i32,
            },
            Encoding::SignMagnitude => {
                let magnitude = (u & 0x3FF) as i32;
                if u & 0x400 != 0 {
                    -magnitude
                } else {
                    magnitude
                }
            }
        }
    }

    /// Encode `value` into `out` (`size` bytes, little-endian).
    pub fn encode(&self, value: i32, out: &mut [u8]) {
        let u: u32 = match self.encoding {
            Encoding::Unsigned | Encoding::Signed => value as u32,
            Encoding::SignMagnitude => {
                let m = value.unsigned_abs().min(0x3FF);
                if value < 0 { 0x400 | m } else { m }
            }
        };
        for (k, b) in out.iter_mut().take(self.size as usize).enumerate() {
            *b = (u >> (8 * k)) as u8;
        }
    }

    /// Whether bytes on the wire can be this register's value: the raw bits of a
    /// sign-magnitude or unsigned register above its range cannot come from a
    /// healthy servo.
    pub fn plausible(&self, bytes: &[u8]) -> bool {
        if self.encoding == Encoding::SignMagnitude {
            let mut u: u32 = 0;
            for (k, &b) in bytes.iter().take(self.size as usize).enumerate() {
                u |= (b as u32) << (8 * k);
            }
            if u > 0x7FF {
                return false;
            }
        }
        let v = self.decode(bytes);
        v >= self.min && v <= self.max
    }

    /// The value in SI units (radians, rad/s, load ratio, amperes, volts, degrees
    /// Celsius, seconds); raw for [`Unit::Raw`].
    pub fn to_si(&self, value: i32) -> f64 {
        match self.unit {
            Unit::Raw | Unit::Celsius => value as f64,
            Unit::Angle {
                rad_per_unit,
                center,
            } => (value - center) as f64 * rad_per_unit,
            Unit::AngularVelocity { rad_s_per_unit } => value as f64 * rad_s_per_unit,
            Unit::LoadRatio { per_unit } => value as f64 * per_unit,
            Unit::Current {
                amps_per_unit,
                zero,
            } => (value - zero) as f64 * amps_per_unit,
            Unit::Voltage { volts_per_unit } => value as f64 * volts_per_unit,
            Unit::Duration { seconds_per_unit } => value as f64 * seconds_per_unit,
            Unit::Gyro {
                rad_s_per_unit,
                center,
            } => (value - center) as f64 * rad_s_per_unit,
            Unit::Accel {
                m_s2_per_unit,
                center,
            } => (value - center) as f64 * m_s2_per_unit,
        }
    }

    /// This register read out of a servo's control table memory (`memory` from
    /// address 0): what `link read` prints and returns, one row per register.
    pub fn reading(&self, memory: &[u8]) -> Reading {
        let raw = self.decode(&memory[self.address as usize..self.end() as usize]);
        Reading {
            address: self.address,
            name: self.name,
            size: self.size,
            access: match self.access {
                Access::Read => "R",
                Access::ReadWrite => "RW",
            },
            raw,
            value: self.to_si(raw),
            unit: self.unit.name(),
        }
    }

    /// The nearest raw value to an SI value, clamped to the register's range
    /// (NaN gives the range's lower end).
    pub fn from_si(&self, si: f64) -> i32 {
        self.nearest(self.raw_exact(si))
    }

    /// [`Register::from_si`] with the part of a unit that rounding drops carried in
    /// `residual` to the next call (first-order sigma-delta modulation): called
    /// again and again with one value, the raw values sent average to it.
    pub fn from_si_carrying(&self, si: f64, residual: &mut f64) -> i32 {
        let want = self.raw_exact(si) + *residual;
        let raw = self.nearest(want);
        // A value pinned at the register's end must not wind the residual up.
        *residual = if want.is_nan() {
            0.0
        } else {
            (want - raw as f64).clamp(-1.0, 1.0)
        };
        raw
    }

    /// The nearest raw value in the register's range (NaN: the lower end).
    fn nearest(&self, raw: f64) -> i32 {
        let r = raw.round();
        if r.is_nan() {
            return self.min;
        }
        r.clamp(self.min as f64, self.max as f64) as i32
    }

    /// The raw value of an SI value before rounding (what [`Register::from_si`]
    /// rounds), unclamped.
    fn raw_exact(&self, si: f64) -> f64 {
        match self.unit {
            Unit::Raw | Unit::Celsius => si,
            Unit::Angle {
                rad_per_unit,
                center,
            } => si / rad_per_unit + center as f64,
            Unit::AngularVelocity { rad_s_per_unit } => si / rad_s_per_unit,
            Unit::LoadRatio { per_unit } => si / per_unit,
            Unit::Current {
                amps_per_unit,
                zero,
            } => si / amps_per_unit + zero as f64,
            Unit::Voltage { volts_per_unit } => si / volts_per_unit,
            Unit::Duration { seconds_per_unit } => si / seconds_per_unit,
            Unit::Gyro {
                rad_s_per_unit,
                center,
            } => si / rad_s_per_unit + center as f64,
            Unit::Accel {
                m_s2_per_unit,
                center,
            } => si / m_s2_per_unit + center as f64,
        }
    }
}
