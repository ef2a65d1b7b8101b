//! Control tables: every model's registers (e-manual control-table pages), looked up
//! by item, name or address.
//!
//! Sources: EM-RX28/EM-RX64 (RX), e-manual MX-28/64/106 pages (MX 1.0 firmware),
//! MX-28/64/106(2.0) pages, EM-XM (XM430-W350) and the XL430-W250 page, the
//! Protocol 2.0 tables with their Indirect Address / Indirect Data blocks
//! ([`IndirectBlock`]).

use crate::protocol::Protocol;
use crate::register::{Access, Area, DEGREE, Encoding, Item, RPM, Register, Unit};
use crate::servo_model::ServoModel;
use std::sync::OnceLock;

/// A model's control table.
#[derive(Debug)]
pub struct ControlTable {
    pub model: ServoModel,
    /// Registers in address order.
    pub registers: Vec<Register>,
    /// Indirect Address / Indirect Data blocks (none on Protocol 1.0 tables).
    pub indirect: Vec<IndirectBlock>,
}

/// One block of indirect addressing: `count` Indirect Address registers (2 bytes
/// each) from `address`, and the `count` Indirect Data bytes they point from, from
/// `data`. Indirect Data `n` reads and writes the byte whose address Indirect
/// Address `n` holds, with that register's size, range and access (e-manual,
/// "Indirect Address, Indirect Data" of EM-XM, the XL430-W250 and MX(2.0) pages).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IndirectBlock {
    pub address: u16,
    pub data: u16,
    pub count: u16,
}

/// The X series and MX(2.0) blocks: Indirect Address 1..28 at 168..222 with
/// Indirect Data 1..28 at 224..251, and Indirect Address 29..56 at 578..632 with
/// Indirect Data 29..56 at 634..661 (EM-XM, XL430-W250 and MX-28/64/106(2.0)
/// control tables; the second block is out of Protocol 1.0's one-byte reach).
pub const X_INDIRECT: [IndirectBlock; 2] = [
    IndirectBlock {
        address: 168,
        data: 224,
        count: 28,
    },
    IndirectBlock {
        address: 578,
        data: 634,
        count: 28,
    },
];

/// What an Indirect Address may hold: the RAM area, 64..661 ("EEPROM address can't
/// be assigned to Indirect Address", e-manual Indirect Address range).
pub const INDIRECT_TARGETS: std::ops::RangeInclusive<u16> = 64..=661;

impl IndirectBlock {
    /// Which Indirect Data byte of this block `address` is (0-based).
    pub fn data_index(&self, address: u16) -> Option<u16> {
        (address >= self.data && address < self.data + self.count).then(|| address - self.data)
    }

    /// Whether `address` lies in this block's Indirect Address registers.
    pub fn holds_address_register(&self, address: u16) -> bool {
        address >= self.address && address < self.address + 2 * self.count
    }
}

/// The table of a servo model: `model.table()`. A trait because [`ServoModel`] is
/// the catalogue's (`twinloop-servos`), which knows no control tables: the dependency
/// runs one way, tables know servo models, not the reverse. Exported at the crate root.
pub trait ModelTable {
    fn table(self) -> &'static ControlTable;

    /// Whether the servo can be set to talk `protocol`: its own, or either where its
    /// table has a Protocol Type register (X series, MX(2.0): "X-series can switch
    /// Protocol 2.0 into Protocol 1.0", e-manual Protocol Compatibility Table;
    /// Protocol Type(13): 1 = Protocol 1.0, 2 = Protocol 2.0).
    fn speaks(self, protocol: Protocol) -> bool;
}

impl ModelTable for ServoModel {
    fn table(self) -> &'static ControlTable {
        ControlTable::of(self)
    }

    fn speaks(self, protocol: Protocol) -> bool {
        protocol == self.protocol() || self.table().item(Item::ProtocolType).is_some()
    }
}

impl ControlTable {
    /// The table of `model` (built once, then shared).
    pub fn of(model: ServoModel) -> &'static ControlTable {
        static TABLES: OnceLock<Vec<ControlTable>> = OnceLock::new();
        let tables = TABLES.get_or_init(|| ServoModel::ALL.iter().map(|&m| build(m)).collect());
        let k = ServoModel::ALL
            .iter()
            .position(|&m| m == model)
            .unwrap_or(0);
        &tables[k]
    }

    pub fn protocol(&self) -> Protocol {
        self.model.protocol()
    }

    /// The register playing `item`, if this model has one.
    pub fn item(&self, item: Item) -> Option<&Register> {
        self.registers.iter().find(|r| r.item == Some(item))
    }

    /// A register by its e-manual name, ignoring case and spaces.
    pub fn by_name(&self, name: &str) -> Option<&Register> {
        let key = |s: &str| -> String {
            s.chars()
                .filter(|c| c.is_ascii_alphanumeric())
                .map(|c| c.to_ascii_lowercase())
                .collect()
        };
        let k = key(name);
        self.registers.iter().find(|r| key(r.name) == k)
    }

    /// The register starting at `address`.
    pub fn at(&self, address: u16) -> Option<&Register> {
        self.registers.iter().find(|r| r.address == address)
    }

    /// The register holding byte `address` (registers are in address order and do
    /// not overlap: a binary search).
    pub fn containing(&self, address: u16) -> Option<&Register> {
        let k = self.registers.partition_point(|r| r.end() <= address);
        self.registers.get(k).filter(|r| r.address <= address)
    }

    /// The Indirect Address register that redirects Indirect Data byte `address`,
    /// if `address` is one.
    pub fn indirect_pointer(&self, address: u16) -> Option<u16> {
        self.indirect
            .iter()
            .find_map(|b| b.data_index(address).map(|i| b.address + 2 * i))
    }

    /// Whether `address` lies in an Indirect Address register.
    pub fn is_indirect_address(&self, address: u16) -> bool {
        self.indirect
            .iter()
            .any(|b| b.holds_address_register(address))
    }

    /// Bytes of memory the table spans (one past its last register).
    pub fn len(&self) -> usize {
        self.registers
            .iter()
            .map(|r| r.end() as usize)
            .max()
            .unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.registers.is_empty()
    }

    /// The factory memory image of a servo with this table and `id`: initial values
    /// where the e-manual gives them, the model number, 0 elsewhere.
    pub fn factory_memory(&self, id: u8, firmware: u8) -> Vec<u8> {
        let mut mem = vec![0u8; self.len()];
        for r in &self.registers {
            let a = r.address as usize;
            let bytes = &mut mem[a..a + r.size as usize];
            match r.item {
                Some(Item::ModelNumber) => r.encode(self.model.model_number() as i32, bytes),
                Some(Item::FirmwareVersion) => r.encode(firmware as i32, bytes),
                Some(Item::Id) => r.encode(id as i32, bytes),
                _ => {
                    if let Some(v) = r.initial {
                        r.encode(v, bytes);
                    }
                }
            }
        }
        // Torque Limit starts at Max Torque (EM-RX28).
        if let (Some(limit), Some(max)) = (self.item(Item::TorqueLimit), self.item(Item::MaxTorque))
            && self.protocol() == Protocol::V1
        {
            let v = max.decode(&mem[max.address as usize..max.end() as usize]);
            let a = limit.address as usize;
            limit.encode(v, &mut mem[a..a + limit.size as usize]);
        }
        mem
    }
}

/// One register, all fields given.
#[allow(clippy::too_many_arguments)]
const fn reg(
    name: &'static str,
    item: Option<Item>,
    address: u16,
    size: u8,
    access: Access,
    area: Area,
    initial: Option<i32>,
    min: i32,
    max: i32,
    encoding: Encoding,
    unit: Unit,
) -> Register {
    Register {
        name,
        item,
        address,
        size,
        access,
        area,
        initial,
        min,
        max,
        encoding,
        unit,
    }
}

fn unsigned_max(size: u8) -> i32 {
    match size {
        1 => 0xFF,
        2 => 0xFFFF,
        _ => i32::MAX,
    }
}

/// A read-only register of unsigned raw value.
fn ro(name: &'static str, item: Option<Item>, address: u16, size: u8, area: Area) -> Register {
    reg(
        name,
        item,
        address,
        size,
        Access::Read,
        area,
        None,
        0,
        unsigned_max(size),
        Encoding::Unsigned,
        Unit::Raw,
    )
}

/// A read-write register of unsigned raw value in `min..=max`.
#[allow(clippy::too_many_arguments)]
fn rw(
    name: &'static str,
    item: Option<Item>,
    address: u16,
    size: u8,
    area: Area,
    initial: Option<i32>,
    min: i32,
    max: i32,
) -> Register {
    reg(
        name,
        item,
        address,
        size,
        Access::ReadWrite,
        area,
        initial,
        min,
        max,
        Encoding::Unsigned,
        Unit::Raw,
    )
}

fn with(mut r: Register, encoding: Encoding, unit: Unit) -> Register {
    r.encoding = encoding;
    r.unit = unit;
    r
}

use Area::{Eeprom as E, Ram as R};

fn build(model: ServoModel) -> ControlTable {
    let registers = match model {
        ServoModel::Rx28 | ServoModel::Rx64 => table_rx(),
        ServoModel::Mx28 | ServoModel::Mx64 | ServoModel::Mx106 => table_mx_v1(model),
        ServoModel::Cm730 => table_cm730(),
        _ => table_v2(model),
    };
    let mut registers = registers;
    let indirect = if model.protocol() == Protocol::V2 {
        X_INDIRECT.to_vec()
    } else {
        Vec::new()
    };
    for b in &indirect {
        registers.extend(indirect_registers(b));
    }
    registers.sort_by_key(|r| r.address);
    ControlTable {
        model,
        registers,
        indirect,
    }
}

/// The names "Indirect Address 1..56" and "Indirect Data 1..56", made once and
/// shared by every table.
fn indirect_names() -> &'static [(String, String)] {
    static NAMES: OnceLock<Vec<(String, String)>> = OnceLock::new();
    NAMES.get_or_init(|| {
        (1..=56)
            .map(|n| {
                (
                    format!("Indirect Address {n}"),
                    format!("Indirect Data {n}"),
                )
            })
            .collect()
    })
}

/// One block's registers: each Indirect Address (2 bytes, RAM, 64..661, initially
/// the address of its own Indirect Data byte) and Indirect Data (1 byte, RAM,
/// initially 0), as the e-manual's RAM tables list them.
fn indirect_registers(b: &IndirectBlock) -> Vec<Register> {
    // Numbering: the first block is 1..28, the second 29..56.
    let first = if b.address == X_INDIRECT[0].address {
        0
    } else {
        X_INDIRECT[0].count
    };
    let names = indirect_names();
    let mut v = Vec::with_capacity(2 * b.count as usize);
    for i in 0..b.count {
        let (address_name, data_name) = &names[(first + i) as usize];
        v.push(rw(
            address_name.as_str(),
            None,
            b.address + 2 * i,
            2,
            R,
            Some((b.data + i) as i32),
            *INDIRECT_TARGETS.start() as i32,
            *INDIRECT_TARGETS.end() as i32,
        ));
        v.push(rw(
            data_name.as_str(),
            None,
            b.data + i,
            1,
            R,
            Some(0),
            0,
            255,
        ));
    }
    v
}

/// The CM-730 sub-controller, Protocol 1.0: addresses from the DARwIn-OP framework's
/// `CM730.h`, ranges from the board firmware's parameter table, scales as the
/// ROBOTIS-OP ROS interface converts them (sources in [`crate::board`]). The
/// inertial registers start at the values of a board lying level and still (gyro
/// 512, accelerometer X and Y 512, Z 512 + 1 g).
fn table_cm730() -> Vec<Register> {
    use crate::board::{
        CM730_ACCEL_M_S2_PER_COUNT, CM730_CENTER, CM730_GYRO_RAD_S_PER_COUNT, CM730_ID,
    };
    let gyro = Unit::Gyro {
        rad_s_per_unit: CM730_GYRO_RAD_S_PER_COUNT,
        center: CM730_CENTER,
    };
    let accel = Unit::Accel {
        m_s2_per_unit: CM730_ACCEL_M_S2_PER_COUNT,
        center: CM730_CENTER,
    };
    let one_g = (crate::board::STANDARD_GRAVITY / CM730_ACCEL_M_S2_PER_COUNT).round() as i32;
    let sensor = |name, item, address, initial, unit| {
        let mut r = with(
            ro(name, Some(item), address, 2, R),
            Encoding::Unsigned,
            unit,
        );
        r.max = 1023;
        r.initial = Some(initial);
        r
    };
    let mut v = vec![
        ro("Model Number", Some(Item::ModelNumber), 0, 2, E),
        ro("Firmware Version", Some(Item::FirmwareVersion), 2, 1, E),
        rw("ID", Some(Item::Id), 3, 1, E, Some(CM730_ID as i32), 0, 253),
        rw("Baud Rate", Some(Item::BaudRate), 4, 1, E, Some(1), 1, 254),
        with(
            rw(
                "Return Delay Time",
                Some(Item::ReturnDelayTime),
                5,
                1,
                E,
                Some(0),
                0,
                254,
            ),
            Encoding::Unsigned,
            Unit::Duration {
                seconds_per_unit: 2e-6,
            },
        ),
        rw(
            "Status Return Level",
            Some(Item::StatusReturnLevel),
            16,
            1,
            E,
            Some(2),
            0,
            2,
        ),
        rw("Dynamixel Power", None, 24, 1, R, Some(0), 0, 1),
        rw("LED Panel", Some(Item::Led), 25, 1, R, Some(0), 0, 7),
        rw("LED Head", None, 26, 2, R, Some(0), 0, 0x7FFF),
        rw("LED Eye", None, 28, 2, R, Some(0), 0, 0x7FFF),
        ro("Button", None, 30, 1, R),
        sensor("Gyro Z", Item::GyroZ, 38, CM730_CENTER, gyro),
        sensor("Gyro Y", Item::GyroY, 40, CM730_CENTER, gyro),
        sensor("Gyro X", Item::GyroX, 42, CM730_CENTER, gyro),
        sensor("Accel X", Item::AccelX, 44, CM730_CENTER, accel),
        sensor("Accel Y", Item::AccelY, 46, CM730_CENTER, accel),
        sensor("Accel Z", Item::AccelZ, 48, CM730_CENTER + one_g, accel),
        with(
            ro("Present Voltage", Some(Item::PresentVoltage), 50, 1, R),
            Encoding::Unsigned,
            Unit::Voltage {
                volts_per_unit: 0.1,
            },
        ),
    ];
    // A 12 V supply (0.1 V per unit).
    if let Some(r) = v.iter_mut().find(|r| r.item == Some(Item::PresentVoltage)) {
        r.initial = Some(120);
    }
    // Microphones and ADC channels 51..80 (2 bytes each): read as raw counts.
    const ADC: [&str; 15] = [
        "Left Mic",
        "ADC 2",
        "ADC 3",
        "ADC 4",
        "ADC 5",
        "ADC 6",
        "ADC 7",
        "ADC 8",
        "Right Mic",
        "ADC 10",
        "ADC 11",
        "ADC 12",
        "ADC 13",
        "ADC 14",
        "ADC 15",
    ];
    for (k, name) in ADC.iter().enumerate() {
        v.push(ro(name, None, 51 + 2 * k as u16, 2, R));
    }
    v
}

/// RX-28 / RX-64, Protocol 1.0 (EM-RX28, EM-RX64; e-manual control table). Position
/// 0..1023 over 300 degrees (0.29 deg/unit, 512 = centre), speed about 0.111 rpm/unit,
/// load 0.1 %/unit with bit 10 the direction.
fn table_rx() -> Vec<Register> {
    let angle = Unit::Angle {
        rad_per_unit: 300.0 / 1024.0 * DEGREE,
        center: 512,
    };
    let speed = Unit::AngularVelocity {
        rad_s_per_unit: 0.111 * RPM,
    };
    let load = Unit::LoadRatio { per_unit: 0.001 };
    let mut v = common_v1_head(angle, 1023, 190);
    v.extend([
        rw(
            "CW Compliance Margin",
            Some(Item::CwComplianceMargin),
            26,
            1,
            R,
            Some(1),
            0,
            255,
        ),
        rw(
            "CCW Compliance Margin",
            Some(Item::CcwComplianceMargin),
            27,
            1,
            R,
            Some(1),
            0,
            255,
        ),
        rw(
            "CW Compliance Slope",
            Some(Item::CwComplianceSlope),
            28,
            1,
            R,
            Some(32),
            0,
            255,
        ),
        rw(
            "CCW Compliance Slope",
            Some(Item::CcwComplianceSlope),
            29,
            1,
            R,
            Some(32),
            0,
            255,
        ),
        with(
            rw(
                "Goal Position",
                Some(Item::GoalPosition),
                30,
                2,
                R,
                None,
                0,
                1023,
            ),
            Encoding::Unsigned,
            angle,
        ),
        with(
            rw(
                "Moving Speed",
                Some(Item::MovingSpeed),
                32,
                2,
                R,
                Some(0),
                0,
                1023,
            ),
            Encoding::Unsigned,
            speed,
        ),
        with(
            rw(
                "Torque Limit",
                Some(Item::TorqueLimit),
                34,
                2,
                R,
                None,
                0,
                1023,
            ),
            Encoding::Unsigned,
            load,
        ),
        present_position_v1(angle, 0, 1023, Encoding::Unsigned),
    ]);
    v.extend(common_v1_tail(speed, load, 32));
    v
}

/// MX-28 / MX-64 / MX-106 with Protocol 1.0 firmware (e-manual MX pages). Position
/// 0..4095 over 360 degrees (0.088 deg/unit, 2048 = centre; multi-turn -28672..28672),
/// speed 0.114 rpm/unit, load 0.1 %/unit.
fn table_mx_v1(model: ServoModel) -> Vec<Register> {
    let angle = Unit::Angle {
        rad_per_unit: 360.0 / 4096.0 * DEGREE,
        center: 2048,
    };
    let speed = Unit::AngularVelocity {
        rad_s_per_unit: 0.114 * RPM,
    };
    let load = Unit::LoadRatio { per_unit: 0.001 };
    let mut v = common_v1_head(angle, 4095, 160);
    v.extend([
        with(
            rw("Multi Turn Offset", None, 20, 2, E, Some(0), -24576, 24576),
            Encoding::Signed,
            Unit::Raw,
        ),
        rw("Resolution Divider", None, 22, 1, E, Some(1), 1, 4),
        rw(
            "D Gain",
            Some(Item::PositionDGain),
            26,
            1,
            R,
            Some(0),
            0,
            254,
        ),
        rw(
            "I Gain",
            Some(Item::PositionIGain),
            27,
            1,
            R,
            Some(0),
            0,
            254,
        ),
        rw(
            "P Gain",
            Some(Item::PositionPGain),
            28,
            1,
            R,
            Some(32),
            0,
            254,
        ),
        with(
            rw(
                "Goal Position",
                Some(Item::GoalPosition),
                30,
                2,
                R,
                None,
                -28672,
                28672,
            ),
            Encoding::Signed,
            angle,
        ),
        with(
            rw(
                "Moving Speed",
                Some(Item::MovingSpeed),
                32,
                2,
                R,
                Some(0),
                0,
                1023,
            ),
            Encoding::Unsigned,
            speed,
        ),
        with(
            rw(
                "Torque Limit",
                Some(Item::TorqueLimit),
                34,
                2,
                R,
                None,
                0,
                1023,
            ),
            Encoding::Unsigned,
            load,
        ),
        present_position_v1(angle, -28672, 28672, Encoding::Signed),
        rw("Goal Acceleration", None, 73, 1, R, Some(0), 0, 254),
    ]);
    v.extend(common_v1_tail(speed, load, 0));
    if matches!(model, ServoModel::Mx64 | ServoModel::Mx106) {
        let current = Unit::Current {
            amps_per_unit: 0.0045,
            zero: 2048,
        };
        v.extend([
            with(
                ro("Realtime Tick", Some(Item::RealtimeTick), 50, 2, R),
                Encoding::Unsigned,
                Unit::Duration {
                    seconds_per_unit: 0.001,
                },
            ),
            with(
                rw(
                    "Current",
                    Some(Item::PresentCurrent),
                    68,
                    2,
                    R,
                    Some(2048),
                    0,
                    4095,
                ),
                Encoding::Unsigned,
                current,
            ),
            rw("Torque Ctrl Mode Enable", None, 70, 1, R, Some(0), 0, 1),
            with(
                rw(
                    "Goal Torque",
                    Some(Item::GoalCurrent),
                    71,
                    2,
                    R,
                    Some(0),
                    -1023,
                    1023,
                ),
                Encoding::SignMagnitude,
                Unit::Current {
                    amps_per_unit: 0.0045,
                    zero: 0,
                },
            ),
        ]);
    }
    if model == ServoModel::Mx106 {
        v.push(rw("Drive Mode", None, 10, 1, E, Some(0), 0, 3));
    }
    v
}

/// Registers 0..18 and 24..25 shared by RX and MX(1.0).
fn common_v1_head(angle: Unit, position_max: i32, max_voltage: i32) -> Vec<Register> {
    vec![
        ro("Model Number", Some(Item::ModelNumber), 0, 2, E),
        ro("Firmware Version", Some(Item::FirmwareVersion), 2, 1, E),
        rw("ID", Some(Item::Id), 3, 1, E, Some(1), 0, 253),
        rw("Baud Rate", Some(Item::BaudRate), 4, 1, E, Some(34), 0, 254),
        with(
            rw(
                "Return Delay Time",
                Some(Item::ReturnDelayTime),
                5,
                1,
                E,
                Some(250),
                0,
                254,
            ),
            Encoding::Unsigned,
            Unit::Duration {
                seconds_per_unit: 2e-6,
            },
        ),
        with(
            rw(
                "CW Angle Limit",
                Some(Item::MinPositionLimit),
                6,
                2,
                E,
                Some(0),
                0,
                position_max,
            ),
            Encoding::Unsigned,
            angle,
        ),
        with(
            rw(
                "CCW Angle Limit",
                Some(Item::MaxPositionLimit),
                8,
                2,
                E,
                Some(position_max),
                0,
                position_max,
            ),
            Encoding::Unsigned,
            angle,
        ),
        with(
            rw(
                "Temperature Limit",
                Some(Item::TemperatureLimit),
                11,
                1,
                E,
                Some(80),
                10,
                99,
            ),
            Encoding::Unsigned,
            Unit::Celsius,
        ),
        with(
            rw(
                "Min Voltage Limit",
                Some(Item::MinVoltageLimit),
                12,
                1,
                E,
                Some(60),
                50,
                250,
            ),
            Encoding::Unsigned,
            Unit::Voltage {
                volts_per_unit: 0.1,
            },
        ),
        with(
            rw(
                "Max Voltage Limit",
                Some(Item::MaxVoltageLimit),
                13,
                1,
                E,
                Some(max_voltage),
                50,
                250,
            ),
            Encoding::Unsigned,
            Unit::Voltage {
                volts_per_unit: 0.1,
            },
        ),
        with(
            rw(
                "Max Torque",
                Some(Item::MaxTorque),
                14,
                2,
                E,
                Some(1023),
                0,
                1023,
            ),
            Encoding::Unsigned,
            Unit::LoadRatio { per_unit: 0.001 },
        ),
        rw(
            "Status Return Level",
            Some(Item::StatusReturnLevel),
            16,
            1,
            E,
            Some(2),
            0,
            2,
        ),
        rw("Alarm LED", None, 17, 1, E, Some(36), 0, 127),
        rw("Shutdown", Some(Item::Shutdown), 18, 1, E, Some(36), 0, 127),
        rw(
            "Torque Enable",
            Some(Item::TorqueEnable),
            24,
            1,
            R,
            Some(0),
            0,
            1,
        ),
        rw("LED", Some(Item::Led), 25, 1, R, Some(0), 0, 1),
    ]
}

fn present_position_v1(angle: Unit, min: i32, max: i32, encoding: Encoding) -> Register {
    reg(
        "Present Position",
        Some(Item::PresentPosition),
        36,
        2,
        Access::Read,
        R,
        None,
        min,
        max,
        encoding,
        angle,
    )
}

/// Registers 38..48 shared by RX and MX(1.0).
fn common_v1_tail(speed: Unit, load: Unit, punch: i32) -> Vec<Register> {
    vec![
        reg(
            "Present Speed",
            Some(Item::PresentVelocity),
            38,
            2,
            Access::Read,
            R,
            None,
            -1023,
            1023,
            Encoding::SignMagnitude,
            speed,
        ),
        reg(
            "Present Load",
            Some(Item::PresentLoad),
            40,
            2,
            Access::Read,
            R,
            None,
            -1023,
            1023,
            Encoding::SignMagnitude,
            load,
        ),
        with(
            ro("Present Voltage", Some(Item::PresentVoltage), 42, 1, R),
            Encoding::Unsigned,
            Unit::Voltage {
                volts_per_unit: 0.1,
            },
        ),
        with(
            ro(
                "Present Temperature",
                Some(Item::PresentTemperature),
                43,
                1,
                R,
            ),
            Encoding::Unsigned,
            Unit::Celsius,
        ),
        ro("Registered", Some(Item::Registered), 44, 1, R),
        ro("Moving", Some(Item::Moving), 46, 1, R),
        rw("Lock", Some(Item::Lock), 47, 1, R, Some(0), 0, 1),
        rw("Punch", Some(Item::Punch), 48, 2, R, Some(punch), 0, 1023),
    ]
}

/// Protocol 2.0 tables: X series (EM-XM, XL430-W250 page) and MX(2.0) (MX-28/64/106
/// (2.0) pages). Position 0.088 deg/unit (4096 per turn, 2048 = centre), velocity
/// 0.229 rpm/unit, current 2.69 mA/unit (XM430) or 3.36 mA/unit (MX-64/106), load
/// 0.1 %/unit where the model senses no current (XL430, MX-28).
fn table_v2(model: ServoModel) -> Vec<Register> {
    let angle = Unit::Angle {
        rad_per_unit: 360.0 / 4096.0 * DEGREE,
        center: 2048,
    };
    let velocity = Unit::AngularVelocity {
        rad_s_per_unit: 0.229 * RPM,
    };
    // (Current Limit initial, A per unit) for models that sense current.
    let current = match model {
        ServoModel::Xm430W350 => Some((1193, 0.00269)),
        ServoModel::Mx64V2 => Some((1941, 0.00336)),
        ServoModel::Mx106V2 => Some((2047, 0.00336)),
        _ => None,
    };
    let velocity_limit = match model {
        ServoModel::Xm430W350 => 350,
        ServoModel::Xl430W250 => 265,
        ServoModel::Mx28V2 => 380,
        ServoModel::Mx64V2 => 435,
        ServoModel::Mx106V2 => 210,
        _ => 1023,
    };
    let (max_volt, min_volt, volt_lo, volt_hi) = match model {
        ServoModel::Xl430W250 => (140, 60, 60, 140),
        _ => (160, 95, 95, 160),
    };
    let position_p = match model {
        ServoModel::Xm430W350 => 800,
        ServoModel::Xl430W250 => 640,
        _ => 850,
    };
    let velocity_i = if model == ServoModel::Xl430W250 {
        1000
    } else {
        1920
    };
    let volts = Unit::Voltage {
        volts_per_unit: 0.1,
    };
    let signed = |name, item, address, size, access, min, max, unit| {
        reg(
            name,
            item,
            address,
            size,
            access,
            R,
            None,
            min,
            max,
            Encoding::Signed,
            unit,
        )
    };
    let mut v = vec![
        ro("Model Number", Some(Item::ModelNumber), 0, 2, E),
        ro("Model Information", None, 2, 4, E),
        ro("Firmware Version", Some(Item::FirmwareVersion), 6, 1, E),
        rw("ID", Some(Item::Id), 7, 1, E, Some(1), 0, 252),
        rw("Baud Rate", Some(Item::BaudRate), 8, 1, E, Some(1), 0, 7),
        with(
            rw(
                "Return Delay Time",
                Some(Item::ReturnDelayTime),
                9,
                1,
                E,
                Some(250),
                0,
                254,
            ),
            Encoding::Unsigned,
            Unit::Duration {
                seconds_per_unit: 2e-6,
            },
        ),
        rw("Drive Mode", None, 10, 1, E, Some(0), 0, 255),
        rw(
            "Operating Mode",
            Some(Item::OperatingMode),
            11,
            1,
            E,
            Some(3),
            0,
            16,
        ),
        rw("Secondary ID", None, 12, 1, E, Some(255), 0, 255),
        rw(
            "Protocol Type",
            Some(Item::ProtocolType),
            13,
            1,
            E,
            Some(2),
            1,
            2,
        ),
        with(
            rw(
                "Homing Offset",
                Some(Item::HomingOffset),
                20,
                4,
                E,
                Some(0),
                -1_044_479,
                1_044_479,
            ),
            Encoding::Signed,
            Unit::Angle {
                rad_per_unit: 360.0 / 4096.0 * DEGREE,
                center: 0,
            },
        ),
        with(
            rw(
                "Moving Threshold",
                Some(Item::MovingThreshold),
                24,
                4,
                E,
                Some(10),
                0,
                1023,
            ),
            Encoding::Unsigned,
            velocity,
        ),
        with(
            rw(
                "Temperature Limit",
                Some(Item::TemperatureLimit),
                31,
                1,
                E,
                Some(80),
                0,
                100,
            ),
            Encoding::Unsigned,
            Unit::Celsius,
        ),
        with(
            rw(
                "Max Voltage Limit",
                Some(Item::MaxVoltageLimit),
                32,
                2,
                E,
                Some(max_volt),
                volt_lo,
                volt_hi,
            ),
            Encoding::Unsigned,
            volts,
        ),
        with(
            rw(
                "Min Voltage Limit",
                Some(Item::MinVoltageLimit),
                34,
                2,
                E,
                Some(min_volt),
                volt_lo,
                volt_hi,
            ),
            Encoding::Unsigned,
            volts,
        ),
        rw(
            "PWM Limit",
            Some(Item::MaxTorque),
            36,
            2,
            E,
            Some(885),
            0,
            885,
        ),
        with(
            rw(
                "Velocity Limit",
                Some(Item::VelocityLimit),
                44,
                4,
                E,
                Some(velocity_limit),
                0,
                1023,
            ),
            Encoding::Unsigned,
            velocity,
        ),
        with(
            rw(
                "Max Position Limit",
                Some(Item::MaxPositionLimit),
                48,
                4,
                E,
                Some(4095),
                0,
                4095,
            ),
            Encoding::Unsigned,
            angle,
        ),
        with(
            rw(
                "Min Position Limit",
                Some(Item::MinPositionLimit),
                52,
                4,
                E,
                Some(0),
                0,
                4095,
            ),
            Encoding::Unsigned,
            angle,
        ),
        rw("Shutdown", Some(Item::Shutdown), 63, 1, E, Some(52), 0, 255),
        rw(
            "Torque Enable",
            Some(Item::TorqueEnable),
            64,
            1,
            R,
            Some(0),
            0,
            1,
        ),
        rw("LED", Some(Item::Led), 65, 1, R, Some(0), 0, 1),
        rw(
            "Status Return Level",
            Some(Item::StatusReturnLevel),
            68,
            1,
            R,
            Some(2),
            0,
            2,
        ),
        ro("Registered Instruction", Some(Item::Registered), 69, 1, R),
        ro(
            "Hardware Error Status",
            Some(Item::HardwareErrorStatus),
            70,
            1,
            R,
        ),
        rw(
            "Velocity I Gain",
            None,
            76,
            2,
            R,
            Some(velocity_i),
            0,
            16383,
        ),
        rw("Velocity P Gain", None, 78, 2, R, Some(100), 0, 16383),
        rw(
            "Position D Gain",
            Some(Item::PositionDGain),
            80,
            2,
            R,
            Some(0),
            0,
            16383,
        ),
        rw(
            "Position I Gain",
            Some(Item::PositionIGain),
            82,
            2,
            R,
            Some(0),
            0,
            16383,
        ),
        rw(
            "Position P Gain",
            Some(Item::PositionPGain),
            84,
            2,
            R,
            Some(position_p),
            0,
            16383,
        ),
        rw("Feedforward 2nd Gain", None, 88, 2, R, Some(0), 0, 16383),
        rw("Feedforward 1st Gain", None, 90, 2, R, Some(0), 0, 16383),
        rw("Bus Watchdog", None, 98, 1, R, Some(0), 0, 127),
        signed(
            "Goal PWM",
            None,
            100,
            2,
            Access::ReadWrite,
            -885,
            885,
            Unit::Raw,
        ),
        signed(
            "Goal Velocity",
            Some(Item::GoalVelocity),
            104,
            4,
            Access::ReadWrite,
            -1023,
            1023,
            velocity,
        ),
        rw(
            "Profile Acceleration",
            Some(Item::ProfileAcceleration),
            108,
            4,
            R,
            Some(0),
            0,
            32767,
        ),
        with(
            rw(
                "Profile Velocity",
                Some(Item::MovingSpeed),
                112,
                4,
                R,
                Some(0),
                0,
                32767,
            ),
            Encoding::Unsigned,
            velocity,
        ),
        signed(
            "Goal Position",
            Some(Item::GoalPosition),
            116,
            4,
            Access::ReadWrite,
            -1_048_575,
            1_048_575,
            angle,
        ),
        with(
            ro("Realtime Tick", Some(Item::RealtimeTick), 120, 2, R),
            Encoding::Unsigned,
            Unit::Duration {
                seconds_per_unit: 0.001,
            },
        ),
        ro("Moving", Some(Item::Moving), 122, 1, R),
        ro("Moving Status", None, 123, 1, R),
        signed(
            "Present PWM",
            None,
            124,
            2,
            Access::Read,
            -885,
            885,
            Unit::Raw,
        ),
        signed(
            "Present Velocity",
            Some(Item::PresentVelocity),
            128,
            4,
            Access::Read,
            -1_000_000,
            1_000_000,
            velocity,
        ),
        signed(
            "Present Position",
            Some(Item::PresentPosition),
            132,
            4,
            Access::Read,
            i32::MIN,
            i32::MAX,
            angle,
        ),
        signed(
            "Velocity Trajectory",
            None,
            136,
            4,
            Access::Read,
            i32::MIN,
            i32::MAX,
            velocity,
        ),
        signed(
            "Position Trajectory",
            None,
            140,
            4,
            Access::Read,
            i32::MIN,
            i32::MAX,
            angle,
        ),
        with(
            ro(
                "Present Input Voltage",
                Some(Item::PresentVoltage),
                144,
                2,
                R,
            ),
            Encoding::Unsigned,
            volts,
        ),
        with(
            ro(
                "Present Temperature",
                Some(Item::PresentTemperature),
                146,
                1,
                R,
            ),
            Encoding::Unsigned,
            Unit::Celsius,
        ),
    ];
    match current {
        Some((limit, amps)) => {
            let unit = Unit::Current {
                amps_per_unit: amps,
                zero: 0,
            };
            v.push(with(
                rw(
                    "Current Limit",
                    Some(Item::CurrentLimit),
                    38,
                    2,
                    E,
                    Some(limit),
                    0,
                    limit,
                ),
                Encoding::Unsigned,
                unit,
            ));
            v.push(signed(
                "Goal Current",
                Some(Item::GoalCurrent),
                102,
                2,
                Access::ReadWrite,
                -limit,
                limit,
                unit,
            ));
            v.push(signed(
                "Present Current",
                Some(Item::PresentCurrent),
                126,
                2,
                Access::Read,
                -32768,
                32767,
                unit,
            ));
        }
        None => v.push(signed(
            "Present Load",
            Some(Item::PresentLoad),
            126,
            2,
            Access::Read,
            -1000,
            1000,
            Unit::LoadRatio { per_unit: 0.001 },
        )),
    }
    if matches!(
        model,
        ServoModel::Mx28V2 | ServoModel::Mx64V2 | ServoModel::Mx106V2
    ) {
        v.push(rw(
            "Acceleration Limit",
            None,
            40,
            4,
            E,
            Some(32767),
            0,
            32767,
        ));
    }
    v
}
