//! How an experiment makes each servo stiff and puts it back: the registers it
//! writes, their factory values and the value that makes the loop as stiff as an
//! RX at a given compliance slope.
//!
//! The static methods (tip-over, lean) treat the robot as rigid, so every servo
//! holds its pose as stiffly as it can during them; the host reads these registers
//! first and writes back what it found when the experiment ends.

use crate::model::{LoopFamily, ServoModel};

/// One RAM register of the position loop, as the e-manual's control table has it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoopRegister {
    /// The e-manual's name.
    pub name: &'static str,
    pub address: u16,
    /// Bytes.
    pub size: u8,
    /// Initial value (the e-manual's "Initial Value"/"Default").
    pub factory: i32,
    /// Largest value the register takes.
    pub max: i32,
}

// EM-RX28 / EM-RX64 control table, RAM: CW/CCW Compliance Margin 26/27 (initial 1),
// CW/CCW Compliance Slope 28/29 (initial 32), one byte each, 0-255.
const RX: [LoopRegister; 4] = [
    reg("CW Compliance Margin", 26, 1, 1, 255),
    reg("CCW Compliance Margin", 27, 1, 1, 255),
    reg("CW Compliance Slope", 28, 1, 32, 255),
    reg("CCW Compliance Slope", 29, 1, 32, 255),
];
// EM-MX28/MX64/MX106 (Protocol 1.0) control table, RAM: D Gain 26, I Gain 27, P Gain
// 28 (initial 32), one byte, 0-254. Firmware before v30 (0x1E) had them in the order
// P, I, D (the e-manual's note); the layout here is the current one.
const MX_V1: [LoopRegister; 1] = [reg("P Gain", 28, 1, 32, 254)];
// EM-MX28-2 / EM-MX64-2 / EM-MX106-2 and the X series: Position P Gain at 84, two
// bytes, 0-16383; initial 850 (MX(2.0)), 800 (XM430-W350), 640 (XL430-W250).
const MX_V2: [LoopRegister; 1] = [reg("Position P Gain", 84, 2, 850, 16383)];
const XM430: [LoopRegister; 1] = [reg("Position P Gain", 84, 2, 800, 16383)];
const XL430: [LoopRegister; 1] = [reg("Position P Gain", 84, 2, 640, 16383)];

const fn reg(name: &'static str, address: u16, size: u8, factory: i32, max: i32) -> LoopRegister {
    LoopRegister {
        name,
        address,
        size,
        factory,
        max,
    }
}

/// An RX-28's encoder count, rad (the unit of `rx_slope` below).
const RX_COUNT: f64 = 300.0 / 1024.0 * std::f64::consts::PI / 180.0;

impl ServoModel {
    /// The registers the experiment writes to make this servo stiff (and so reads
    /// first and restores afterwards); empty when there is no known way.
    pub const fn loop_registers(self) -> &'static [LoopRegister] {
        match self {
            ServoModel::Rx28 | ServoModel::Rx64 => &RX,
            ServoModel::Mx28 | ServoModel::Mx64 | ServoModel::Mx106 => &MX_V1,
            ServoModel::Mx28V2 | ServoModel::Mx64V2 | ServoModel::Mx106V2 => &MX_V2,
            ServoModel::Xm430W350 => &XM430,
            ServoModel::Xl430W250 => &XL430,
            ServoModel::Cm730 => &[],
        }
    }

    /// The values that make the loop as stiff as an RX at Compliance Slope
    /// `rx_slope` (RX counts to full torque; 2 is the stiffest, 32 the factory's),
    /// in [`ServoModel::loop_registers`]' order; `None` when there is no known way.
    ///
    /// - RX: margin 0 both ways, slope `rx_slope` both ways.
    /// - MX (1.0): P Gain `1024 / rx_slope`, the e-manual's own table of the two
    ///   (EM-MX28 "PID Gain": slope 8/16/32/64/128 is P 128/64/32/16/8).
    /// - MX(2.0), X: the Position P Gain whose loop reaches full PWM at the same
    ///   angle, `885 * 128 / (rx_slope * 0.29 deg / 0.088 deg)` (EM-XM430: PWM =
    ///   P/128 * error in counts); slope 2 asks more than the register's 16383, and
    ///   gets 16383 (full PWM at 6.9 counts, 0.61 deg).
    ///
    /// Each value is kept within 1 and the register's maximum.
    pub fn stiff_values(self, rx_slope: u8) -> Option<Vec<i32>> {
        let regs = self.loop_registers();
        let family = self.family()?;
        if regs.is_empty() {
            return None;
        }
        let slope = rx_slope.max(1);
        let values = match family {
            LoopFamily::Compliance => vec![0, 0, i32::from(slope), i32::from(slope)],
            LoopFamily::Pid if !self.is_v2_firmware() => vec![1024 / i32::from(slope)],
            LoopFamily::Pid => {
                let counts = f64::from(slope) * RX_COUNT / self.resolution();
                let div = self.p_gain_divisor()?;
                vec![(self.full_output() * div / counts).ceil() as i32]
            }
        };
        Some(
            values
                .into_iter()
                .zip(regs)
                .map(|(v, r)| {
                    v.clamp(
                        if family == LoopFamily::Compliance {
                            0
                        } else {
                            1
                        },
                        r.max,
                    )
                })
                .collect(),
        )
    }
}
