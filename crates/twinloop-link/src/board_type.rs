//! IMU board types: what a sub-controller on the servo bus answers as (protocol,
//! Model Number, control table) and where its gyroscope and accelerometer are. The
//! host reads a board through [`BoardType::imu_span`] and [`BoardType::decode_imu`];
//! a virtual bus serves one from [`BoardType::registers`] (the same facts both ways).
//!
//! Three kinds:
//! - [`BoardType::cm730`]: the ROBOTIS CM-730 of Darwin-OP (Protocol 1.0, id 200),
//!   whose table is the servo catalogue's [`ServoModel::Cm730`] (facts in
//!   [`crate::board`]).
//! - [`BoardType::opencr`]: the OpenCR as the ROBOTIS OP3 runs it (Protocol 2.0,
//!   id 200), table below with its sources.
//! - [`BoardType::custom`]: a team's own board, described entirely in a robot
//!   profile (register addresses, size, signedness, scales): [`CustomBoard`].
//!
//! Adding a built-in board type: a constructor here that lists its registers with the
//! source of each fact, a name in [`BoardType::builtin`], a test against the source's
//! numbers (docs/architecture.md, "A new IMU board").

use crate::board::{BoardError, ImuSample, STANDARD_GRAVITY, accel_items, gyro_items};
use crate::control_table::ModelTable;
use crate::protocol::Protocol;
use crate::register::{Access, Area, DEGREE, Encoding, Item, Register, Unit};
use crate::servo_model::ServoModel;
use std::sync::{Mutex, OnceLock};

/// A board type: identity on the bus and control table.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardType {
    /// `CM-730`, `OpenCR` or the profile's `custom` board name.
    pub name: String,
    pub protocol: Protocol,
    /// What PING and address 0 report.
    pub model_number: u16,
    pub firmware: u8,
    /// The servo catalogue model whose table this is (the CM-730), so a bus serves it
    /// as that model; `None` for a table made here.
    pub catalogue: Option<ServoModel>,
    /// Registers in address order: identity (model number, firmware, id, baud,
    /// return delay, status return level) and the six inertial axes.
    pub registers: Vec<Register>,
}

/// One inertial axis of a [`CustomBoard`]: its register address.
pub type AxisAddresses = [u16; 3];

/// A board described in a profile (`model = "custom"`): everything the host needs to
/// read its IMU and a virtual bus needs to serve it.
#[derive(Debug, Clone, PartialEq)]
pub struct CustomBoard {
    pub name: String,
    pub protocol: Protocol,
    pub model_number: u16,
    /// Addresses of gyro X, Y, Z and accelerometer X, Y, Z (board axes).
    pub gyro: AxisAddresses,
    pub accel: AxisAddresses,
    /// Bytes per axis (1, 2 or 4) and two's complement or not.
    pub size: u8,
    pub signed: bool,
    /// Degrees per second and g per count, and the count that reads zero.
    pub gyro_deg_s_per_count: f64,
    pub accel_g_per_count: f64,
    pub center: i32,
}

/// OpenCR facts, as the OP3 firmware and host code have them:
/// - Addresses: `dxl_mem_op3_t` in ROBOTIS-GIT/OpenCR
///   `arduino/opencr_arduino/opencr/libraries/OP3/examples/opencr_op3/dxl_node_op3.h`
///   (Model_Number 0, Firmware_Version 2, ID 3, Baud 4, Return_Delay_Time 5,
///   Status_Return_Level 16, Dynamixel_Power 24, LED 25, LED_RGB 26, Buzzer 28,
///   Button 30, Voltage 31, Gyro_X/Y/Z 32/34/36, Acc_X/Y/Z 38/40/42, Roll/Pitch/Yaw
///   44/46/48, IMU_Control 50, all int16 for the inertial values); the same
///   addresses are ROBOTIS-Framework's `OPEN-CR.device` table.
/// - Identity: `DXL_NODE_OP3_ID` 200, `DXL_NODE_OP3_MODLE_NUMBER` 0x7400, firmware
///   0x02, baud index 3 (1 Mbps in the firmware's {9600, 57600, 115200, 1M, 2M, ...}
///   list), Protocol 2.0 (`dxlInit(&dxl_sp, DXL_PACKET_VER_2_0)`; `OP3.robot` in
///   ROBOTIS-OP3 `op3_manager/config` lists `OPEN-CR` at id 200 on 2.0). Factory
///   Return Delay 0 and Status Return Level 2 (`dxl_node_op3_factory_reset`).
/// - Scales: ROBOTIS-OP3 `open_cr_module.h`: `GYRO_FACTOR = 2000.0 / 32800` deg/s
///   per count, `ACCEL_FACTOR = 2.0 / 32768` g per count, zero at count 0.
/// - Axes: `open_cr_module.cpp` negates gyro and accelerometer X and Y to get the
///   robot's body axes, so the board sits turned half a turn about Z in OP3's body:
///   the built-in `op3` profile says `axes = ["-x", "-y", "z"]`.
pub mod opencr {
    pub const ID: u8 = 200;
    pub const MODEL_NUMBER: u16 = 0x7400;
    pub const FIRMWARE: u8 = 0x02;
    pub const GYRO_ADDRESSES: [u16; 3] = [32, 34, 36];
    pub const ACCEL_ADDRESSES: [u16; 3] = [38, 40, 42];
    pub const GYRO_DEG_S_PER_COUNT: f64 = 2000.0 / 32800.0;
    pub const ACCEL_G_PER_COUNT: f64 = 2.0 / 32768.0;
    /// Baud index 3: 1 Mbps.
    pub const BAUD_INDEX: i32 = 3;
}

fn register(
    name: &'static str,
    item: Option<Item>,
    address: u16,
    size: u8,
    writable: bool,
    initial: i32,
    (min, max): (i32, i32),
) -> Register {
    Register {
        name,
        item,
        address,
        size,
        access: if writable {
            Access::ReadWrite
        } else {
            Access::Read
        },
        area: if address < 24 {
            Area::Eeprom
        } else {
            Area::Ram
        },
        initial: Some(initial),
        min,
        max,
        encoding: Encoding::Unsigned,
        unit: Unit::Raw,
    }
}

/// The identity registers every Dynamixel-style board shares (addresses of the
/// Protocol 1.0 layout, which the CM-730 and the OP3's OpenCR both keep).
fn identity(id: u8, baud: i32) -> Vec<Register> {
    let mut delay = register(
        "Return Delay Time",
        Some(Item::ReturnDelayTime),
        5,
        1,
        true,
        0,
        (0, 254),
    );
    delay.unit = Unit::Duration {
        seconds_per_unit: 2e-6,
    };
    vec![
        register(
            "Model Number",
            Some(Item::ModelNumber),
            0,
            2,
            false,
            0,
            (0, 0xFFFF),
        ),
        register(
            "Firmware Version",
            Some(Item::FirmwareVersion),
            2,
            1,
            false,
            0,
            (0, 0xFF),
        ),
        register("ID", Some(Item::Id), 3, 1, true, id as i32, (0, 252)),
        register(
            "Baud Rate",
            Some(Item::BaudRate),
            4,
            1,
            true,
            baud,
            (0, 254),
        ),
        delay,
        register(
            "Status Return Level",
            Some(Item::StatusReturnLevel),
            16,
            1,
            true,
            2,
            (0, 2),
        ),
    ]
}

/// Six inertial registers at `gyro` and `accel` (board X, Y, Z), starting at the
/// values of a board lying level and still (accelerometer Z one g).
fn inertial(
    gyro: AxisAddresses,
    accel: AxisAddresses,
    units: (Unit, Unit),
    size: u8,
    signed: bool,
) -> Vec<Register> {
    const GYRO_NAMES: [&str; 3] = ["Gyro X", "Gyro Y", "Gyro Z"];
    const ACCEL_NAMES: [&str; 3] = ["Accel X", "Accel Y", "Accel Z"];
    let bits = 8 * size as u32;
    let (min, max) = match (signed, bits) {
        (_, 32) => (i32::MIN, i32::MAX),
        (true, b) => (-(1 << (b - 1)), (1 << (b - 1)) - 1),
        (false, b) => (0, (1i64 << b) as i32 - 1),
    };
    let mut out = Vec::with_capacity(6);
    for k in 0..6 {
        let (name, item, address, unit) = if k < 3 {
            (GYRO_NAMES[k], gyro_items()[k], gyro[k], units.0)
        } else {
            (
                ACCEL_NAMES[k - 3],
                accel_items()[k - 3],
                accel[k - 3],
                units.1,
            )
        };
        let mut r = register(name, Some(item), address, size, false, 0, (min, max));
        r.area = Area::Ram;
        r.encoding = if signed {
            Encoding::Signed
        } else {
            Encoding::Unsigned
        };
        r.unit = unit;
        r.initial = Some(r.from_si(if k == 5 { STANDARD_GRAVITY } else { 0.0 }));
        out.push(r);
    }
    out
}

/// Interned board types: a profile's custom board lives as long as the program, like
/// the catalogue's tables, so mappings and buses hold `&'static` references.
fn intern(board: BoardType) -> &'static BoardType {
    static ALL: OnceLock<Mutex<Vec<&'static BoardType>>> = OnceLock::new();
    let mut all = ALL
        .get_or_init(|| Mutex::new(Vec::new()))
        .lock()
        .unwrap_or_else(|p| p.into_inner());
    if let Some(b) = all.iter().find(|b| ***b == board) {
        return b;
    }
    let b: &'static BoardType = Box::leak(Box::new(board));
    all.push(b);
    b
}

impl BoardType {
    /// Names [`BoardType::builtin`] knows, for messages.
    pub const BUILTIN: [&'static str; 2] = ["CM-730", "OpenCR"];

    /// The CM-730: the catalogue's table ([`ServoModel::Cm730`]).
    pub fn cm730() -> &'static BoardType {
        static B: OnceLock<&'static BoardType> = OnceLock::new();
        B.get_or_init(|| {
            let m = ServoModel::Cm730;
            intern(BoardType {
                name: m.name().into(),
                protocol: m.protocol(),
                model_number: m.model_number(),
                // No source gives one; a virtual bus serves the catalogue model with
                // its own firmware number.
                firmware: 0,
                catalogue: Some(m),
                registers: m.table().registers.clone(),
            })
        })
    }

    /// The OpenCR with the OP3 firmware (facts in [`opencr`]).
    pub fn opencr() -> &'static BoardType {
        static B: OnceLock<&'static BoardType> = OnceLock::new();
        B.get_or_init(|| {
            let gyro = Unit::Gyro {
                rad_s_per_unit: opencr::GYRO_DEG_S_PER_COUNT * DEGREE,
                center: 0,
            };
            let accel = Unit::Accel {
                m_s2_per_unit: opencr::ACCEL_G_PER_COUNT * STANDARD_GRAVITY,
                center: 0,
            };
            let mut registers = identity(opencr::ID, opencr::BAUD_INDEX);
            registers.push(register("Dynamixel Power", None, 24, 1, true, 0, (0, 1)));
            registers.push(register("LED", Some(Item::Led), 25, 1, true, 0, (0, 7)));
            registers.push(register("LED RGB", None, 26, 2, true, 0, (0, 0x7FFF)));
            registers.push(register("Buzzer", None, 28, 2, true, 0, (0, 0xFFFF)));
            registers.push(register("Button", None, 30, 1, false, 0, (0, 15)));
            let mut volts = register(
                "Present Voltage",
                Some(Item::PresentVoltage),
                31,
                1,
                false,
                120,
                (0, 255),
            );
            volts.unit = Unit::Voltage {
                volts_per_unit: 0.1,
            };
            registers.push(volts);
            registers.extend(inertial(
                opencr::GYRO_ADDRESSES,
                opencr::ACCEL_ADDRESSES,
                (gyro, accel),
                2,
                true,
            ));
            registers.sort_by_key(|r| r.address);
            intern(BoardType {
                name: "OpenCR".into(),
                protocol: Protocol::V2,
                model_number: opencr::MODEL_NUMBER,
                firmware: opencr::FIRMWARE,
                catalogue: None,
                registers,
            })
        })
    }

    /// A built-in board type by name (`CM-730`, `cm730`, `OpenCR`, `open-cr`).
    pub fn builtin(name: &str) -> Option<&'static BoardType> {
        let norm: String = name
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .map(|c| c.to_ascii_lowercase())
            .collect();
        match norm.as_str() {
            "cm730" => Some(BoardType::cm730()),
            "opencr" => Some(BoardType::opencr()),
            _ => None,
        }
    }

    /// A profile's own board. `Err` says which field is wrong.
    pub fn custom(c: &CustomBoard) -> Result<&'static BoardType, BoardError> {
        if ![1, 2, 4].contains(&c.size) {
            return Err(BoardError(format!(
                "size: {} bytes; a register has 1, 2 or 4",
                c.size
            )));
        }
        for (what, v) in [
            ("gyro_deg_s_per_count", c.gyro_deg_s_per_count),
            ("accel_g_per_count", c.accel_g_per_count),
        ] {
            if !(v.is_finite() && v != 0.0) {
                return Err(BoardError(format!("{what}: {v} is not a non-zero number")));
            }
        }
        let mut registers = identity(0, 1);
        let axes: Vec<u16> = c.gyro.iter().chain(&c.accel).copied().collect();
        for (k, &a) in axes.iter().enumerate() {
            let end = a as u32 + c.size as u32;
            let clash = registers
                .iter()
                .find(|r| (r.address as u32) < end && a < r.end())
                .map(|r| r.name.to_string())
                .or_else(|| {
                    axes[..k]
                        .iter()
                        .find(|&&b| (b as u32) < end && a < b + c.size as u16)
                        .map(|b| format!("the axis at {b}"))
                });
            if let Some(other) = clash {
                return Err(BoardError(format!(
                    "the axis at address {a} ({} bytes) overlaps {other}",
                    c.size
                )));
            }
        }
        let gyro = Unit::Gyro {
            rad_s_per_unit: c.gyro_deg_s_per_count * DEGREE,
            center: c.center,
        };
        let accel = Unit::Accel {
            m_s2_per_unit: c.accel_g_per_count * STANDARD_GRAVITY,
            center: c.center,
        };
        registers.extend(inertial(c.gyro, c.accel, (gyro, accel), c.size, c.signed));
        registers.sort_by_key(|r| r.address);
        Ok(intern(BoardType {
            name: c.name.clone(),
            protocol: c.protocol,
            model_number: c.model_number,
            firmware: 1,
            catalogue: None,
            registers,
        }))
    }

    /// The register playing `item`.
    pub fn register(&self, item: Item) -> Option<&Register> {
        self.registers.iter().find(|r| r.item == Some(item))
    }

    /// The address range holding all six inertial registers: (first address, bytes),
    /// what one READ fetches.
    pub fn imu_span(&self) -> (u16, u16) {
        let regs = || {
            gyro_items()
                .into_iter()
                .chain(accel_items())
                .filter_map(|i| self.register(i))
        };
        let start = regs().map(|r| r.address).min().unwrap_or(0);
        let end = regs().map(|r| r.end()).max().unwrap_or(0);
        (start, end - start)
    }

    /// Decode the inertial block read from `base` into SI units along the board's
    /// axes. `None` if a value is outside its register's range (a damaged reply) or
    /// the block is short.
    pub fn decode_imu(&self, base: u16, block: &[u8]) -> Option<ImuSample> {
        let mut out = ImuSample::default();
        for (k, item) in gyro_items().into_iter().chain(accel_items()).enumerate() {
            let r = self.register(item)?;
            let o = r.address.checked_sub(base)? as usize;
            let bytes = block.get(o..o + r.size as usize)?;
            if !r.plausible(bytes) {
                return None;
            }
            let v = r.to_si(r.decode(bytes));
            if k < 3 {
                out.gyro[k] = v;
            } else {
                out.accel[k - 3] = v;
            }
        }
        Some(out)
    }

    /// Bytes of memory the table spans.
    pub fn memory_len(&self) -> usize {
        self.registers
            .iter()
            .map(|r| r.end() as usize)
            .max()
            .unwrap_or(0)
    }

    /// The board's memory at power-on with `id`: initial values, its model number and
    /// firmware.
    pub fn factory_memory(&self, id: u8) -> Vec<u8> {
        let mut mem = vec![0u8; self.memory_len()];
        for r in &self.registers {
            let bytes = &mut mem[r.address as usize..r.end() as usize];
            let v = match r.item {
                Some(Item::ModelNumber) => Some(self.model_number as i32),
                Some(Item::FirmwareVersion) => Some(self.firmware as i32),
                Some(Item::Id) => Some(id as i32),
                _ => r.initial,
            };
            if let Some(v) = v {
                r.encode(v, bytes);
            }
        }
        mem
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cm730_type_is_the_catalogue_table() {
        let b = BoardType::cm730();
        assert_eq!(b.protocol, Protocol::V1);
        assert_eq!(b.model_number, 0x7300);
        assert_eq!(b.imu_span(), crate::board::CM730_IMU_BLOCK);
        assert!(std::ptr::eq(b, BoardType::builtin("cm730").unwrap()));
    }

    #[test]
    fn a_custom_board_refuses_overlapping_axes() {
        let c = CustomBoard {
            name: "mine".into(),
            protocol: Protocol::V2,
            model_number: 0x1234,
            gyro: [40, 42, 44],
            accel: [46, 48, 49],
            size: 2,
            signed: true,
            gyro_deg_s_per_count: 0.1,
            accel_g_per_count: 0.001,
            center: 0,
        };
        let e = BoardType::custom(&c).unwrap_err();
        assert!(e.0.contains("overlaps"), "{e}");
        let ok = CustomBoard {
            accel: [46, 48, 50],
            ..c
        };
        let b = BoardType::custom(&ok).unwrap();
        assert_eq!(b.imu_span(), (40, 12));
        // Interned: the same description is the same type.
        assert!(std::ptr::eq(b, BoardType::custom(&ok).unwrap()));
    }
}
