//! The servo types the models know, with the e-manual facts the models need:
//! encoder resolution, the firmware's loop family and factory gains, whether the
//! servo senses its current, and the datasheet ratings.

/// How the firmware closes the position loop (the catalogue's).
pub use twinloop_servos::LoopFamily;
use twinloop_servos::ServoModel;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServoType {
    Rx28,
    Rx64,
    Mx64V2,
    Xm430W350,
    /// XL330-M288-T (X series, Protocol 2.0): BAM's XL330 pendulum logs.
    Xl330M288,
}

/// Datasheet ratings (e-manual specification tables) at `voltage`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rating {
    /// N m.
    pub stall_torque: f64,
    /// A.
    pub stall_current: f64,
    /// rad/s.
    pub no_load_speed: f64,
    /// V.
    pub voltage: f64,
    pub gear_ratio: f64,
}

use twinloop_servos::RPM;

impl ServoType {
    pub const ALL: [ServoType; 5] = [
        ServoType::Rx28,
        ServoType::Rx64,
        ServoType::Mx64V2,
        ServoType::Xm430W350,
        ServoType::Xl330M288,
    ];

    /// The e-manual name (as twinloop-link's `ServoModel::name`).
    pub fn name(self) -> &'static str {
        self.model().map_or("XL330-M288-T", ServoModel::name)
    }

    /// The name, case and punctuation aside ("rx28", "MX-64(2.0)", "xm430").
    pub fn parse(text: &str) -> Option<ServoType> {
        let key: String = text
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .collect::<String>()
            .to_ascii_lowercase();
        match key.as_str() {
            "rx28" => Some(ServoType::Rx28),
            "rx64" => Some(ServoType::Rx64),
            "mx6420" | "mx64v2" | "mx642" => Some(ServoType::Mx64V2),
            "xm430w350" | "xm430" => Some(ServoType::Xm430W350),
            "xl330m288t" | "xl330m288" | "xl330" => Some(ServoType::Xl330M288),
            _ => None,
        }
    }

    pub fn known_names() -> String {
        Self::ALL.map(ServoType::name).join(", ")
    }

    /// The catalogue's entry for this servo (`None`: the XL330, which twinloop does
    /// not drive over a bus and so has no catalogue entry yet).
    pub fn model(self) -> Option<ServoModel> {
        match self {
            ServoType::Rx28 => Some(ServoModel::Rx28),
            ServoType::Rx64 => Some(ServoModel::Rx64),
            ServoType::Mx64V2 => Some(ServoModel::Mx64V2),
            ServoType::Xm430W350 => Some(ServoModel::Xm430W350),
            ServoType::Xl330M288 => None,
        }
    }

    pub fn family(self) -> LoopFamily {
        self.model()
            .and_then(ServoModel::family)
            .unwrap_or(LoopFamily::Pid)
    }

    /// One encoder count, rad: 300 deg / 1024 (RX), 360 deg / 4096 (MX(2.0), X;
    /// EM-XL330 likewise).
    pub fn resolution(self) -> f64 {
        self.model()
            .map_or(std::f64::consts::TAU / 4096.0, ServoModel::resolution)
    }

    /// The divisor of the Position P Gain register: the loop's PWM per count of
    /// error is `P / divisor`. 128 for MX(2.0) and XM430 (EM-XM430 "Position PID
    /// Gain": K_P = P/128). 256 for the XL330, measured: in BAM's XL330 logs the
    /// Present PWM the servo reports is `P/256` times the count error (entries 6 and
    /// 10 of the kp 100 sin_sin log: 12 and 21 against 12.1 and 21.9; at three
    /// points under load in two logs the ratio to `P/128` is 0.51, 0.50, 0.50).
    pub fn p_gain_divisor(self) -> f64 {
        match self.model() {
            Some(m) => m.p_gain_divisor().unwrap_or(128.0),
            None => 256.0,
        }
    }

    /// Full PWM in the firmware's units: 1023 (RX Torque Limit), 885 (PWM Limit).
    pub fn pwm_max(self) -> f64 {
        self.model().map_or(885.0, ServoModel::full_output)
    }

    /// Present Current's unit, A (`None`: the servo senses no current; RX reports
    /// its PWM as Present Load).
    pub fn current_unit(self) -> Option<f64> {
        match self {
            ServoType::Rx28 | ServoType::Rx64 => None,
            ServoType::Mx64V2 => Some(0.00336),
            ServoType::Xm430W350 => Some(0.00269),
            ServoType::Xl330M288 => Some(0.001),
        }
    }

    /// Factory values of the three firmware registers the loop uses: RX compliance
    /// slope, margin and punch (32, 1, 32); MX/X Position P, I, D gain (850 or 800,
    /// 0, 0; XL330: 400, 0, 0, the P gain BAM's XL330 model starts from).
    pub fn factory_firmware(self) -> [f64; 3] {
        match self.model().and_then(ServoModel::factory_gains) {
            Some(g) => g.map(f64::from),
            None => [400.0, 0.0, 0.0],
        }
    }

    /// The log columns of the three firmware registers.
    pub fn firmware_columns(self) -> [&'static str; 3] {
        match self.family() {
            LoopFamily::Compliance => ["compliance_slope", "compliance_margin", "punch"],
            LoopFamily::Pid => ["p_gain", "i_gain", "d_gain"],
        }
    }

    /// e-manual ratings: the catalogue's datasheet ([`ServoModel::spec`]), the XL330's
    /// here.
    pub fn rating(self) -> Rating {
        match self.model() {
            Some(m) => {
                let s = m.spec();
                Rating {
                    stall_torque: s.stall_torque,
                    stall_current: s.stall_current.unwrap_or(0.0),
                    no_load_speed: s.no_load_speed,
                    voltage: s.voltage,
                    gear_ratio: s.gear_ratio,
                }
            }
            // EM-XL330-M288-T at its recommended 5.0 V (BAM ran it at 7.4 V, above
            // the rated 6.0 V; the fit takes the measured voltage).
            None => Rating {
                stall_torque: 0.52,
                stall_current: 1.47,
                no_load_speed: 103.0 * RPM,
                voltage: 5.0,
                gear_ratio: 288.4,
            },
        }
    }
}

impl std::fmt::Display for ServoType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
