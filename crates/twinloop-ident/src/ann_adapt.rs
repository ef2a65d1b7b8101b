//! ANN-based model adaptation (seed 000 section V.C): a perceptron ([`crate::ann`])
//! maps the forward and backward fall angles and the general location of the added
//! mass (the body part, one-hot) to the positions of the three masses of the
//! three-mass LIPM (left leg, right leg, hip; standing frame), trained on random
//! changes the simulator's static route gives ([`crate::ann_data`]).
//!
//! The data are split as the seed split its own: a training set (fits the weights), a
//! testing set (chooses the epoch; the seed's Table VI) and a validation set never
//! seen in training (its Table VII). The seed gives no proportions; 70/15/15 is used.
//! On the testing and validation sets three methods give a three-mass model of each
//! change, and each is scored by its position errors and by the fall angles it
//! predicts:
//!
//! - **ANN**: the network's positions;
//! - **exact inversion**: [`crate::adapt::adapt`] with the changed robot's total mass
//!   and the link (`--total-mass`, `--where`) on the four measured angles, its adapted
//!   model's three masses;
//! - **manual** (the seed's human, made a rule): the CoM by the seed's geometric method
//!   (eq. 8-13) from the four angles; the two masses away from the change stay where the
//!   prior model has them and the mass holding the change is placed so that the three
//!   masses' CoM is that CoM, as the seed chose its Table III positions "to keep the
//!   CoM ... reasonably close to the CoM" of Table II. Taken as printed, the seed's
//!   CoM is biased by centimetres on km20 (its L3 is a slanted length, and it reads the
//!   foot's asymmetry as a forward CoM: docs/reduced-models.md), so a second version
//!   takes off the bias it shows on the unchanged robot (the seed's method on the
//!   prior's own fall angles minus the prior's CoM): what a person who had measured the
//!   robot before the change would do. It is the one the ANN has to beat.
//!
//! The masses of each model are the prior's three masses with the added mass (weighed,
//! as the seed knew its battery's 0.2 kg) on the part the location names. A model's fall
//! angles are the static forward and backward angles of its CoM on the changed robot's
//! feet ([`crate::tipover::sagittal_tip_angles`]); the truth's come from the same
//! formula with the true CoM.

use crate::adapt::{AdaptOptions, adapt};
use crate::ann::{Mlp, TrainLog, TrainOptions, train};
use crate::ann_data::{
    BodyParts, DataOptions, Sample, SimCheck, generate, parallel_map, static_tip, training_foot,
};
use crate::error::IdentError;
use crate::tipover::{
    FeetMass, SEED_000_CONSTANTS, SeedAngles, SeedConstants, sagittal_tip_angles, seed_method,
};
use crate::tipover_study::{ComReport, DirectionReport, FootReport, StudyReport};
use serde::{Deserialize, Serialize};
use std::time::Instant;
use twinloop_description::Description;
use twinloop_description::builtin::FootGeometry;

/// The saved network (`adapt train --out net.json`): the perceptron with what its
/// inputs and outputs mean and how it was trained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnnModel {
    pub robot: String,
    /// `forward_deg`, `backward_deg`, `added_kg` (if [`AnnModel::mass_input`]), then one
    /// `part:NAME` per body part (one-hot).
    pub inputs: Vec<String>,
    /// Whether the weighed added mass is an input (see the module documentation).
    pub mass_input: bool,
    /// `left_leg.x` ... `hip.z`, m, standing frame.
    pub outputs: Vec<String>,
    pub parts: BodyParts,
    /// The prior's three masses (left leg, right leg, hip), kg.
    pub prior_masses: [f64; 3],
    pub training: TrainingInfo,
    pub net: Mlp,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainingInfo {
    pub samples: usize,
    pub seed: u64,
    pub mass_range: [f64; 2],
    pub noise_deg: f64,
    /// Training, testing, validation.
    pub split: [usize; 3],
    pub best_epoch: usize,
    pub epochs: usize,
    /// The update rule of the back-propagated gradient.
    pub optimiser: String,
}

const MASS_NAMES: [&str; 3] = ["left_leg", "right_leg", "hip"];

impl AnnModel {
    /// The network's input for angles `forward`, `backward` (deg), the added mass
    /// (kg; not used without [`AnnModel::mass_input`]) and body `part`.
    pub fn input(&self, forward: f64, backward: f64, added: f64, part: usize) -> Vec<f64> {
        let mut x = vec![forward, backward];
        if self.mass_input {
            x.push(added);
        }
        x.extend((0..self.parts.names.len()).map(|k| if k == part { 1.0 } else { 0.0 }));
        x
    }

    /// The three positions the network gives, m.
    pub fn positions(&self, forward: f64, backward: f64, added: f64, part: usize) -> [[f64; 3]; 3] {
        let y = self
            .net
            .predict(&self.input(forward, backward, added, part));
        [0, 1, 2].map(|i| [y[3 * i], y[3 * i + 1], y[3 * i + 2]])
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    pub fn from_json(text: &str) -> Result<AnnModel, IdentError> {
        let m: AnnModel = serde_json::from_str(text).map_err(|e| IdentError::new(e.to_string()))?;
        m.net.check()?;
        let k = m.parts.names.len();
        let n_in = 2 + usize::from(m.mass_input) + k;
        if m.net.n_inputs() != n_in || m.net.n_outputs() != 9 || m.parts.three_mass_part.len() != k
        {
            return Err(IdentError::new(format!(
                "a network of {} inputs and {} outputs does not fit {n_in} inputs ({k} parts) and 9 positions",
                m.net.n_inputs(),
                m.net.n_outputs()
            ))
            .field("net"));
        }
        Ok(m)
    }
}

/// A three-mass model: masses (kg) and positions (m) of left leg, right leg, hip.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ThreeMassModel {
    pub masses: [f64; 3],
    pub positions: [[f64; 3]; 3],
}

impl ThreeMassModel {
    /// The CoM of the three points (the seed's vCoM).
    pub fn com(&self) -> [f64; 3] {
        let m: f64 = self.masses.iter().sum();
        [0, 1, 2].map(|k| {
            (0..3)
                .map(|i| self.masses[i] * self.positions[i][k])
                .sum::<f64>()
                / m
        })
    }

    /// Static forward and backward fall angles, deg, of this CoM on `feet_kg` (the feet's
    /// mass, kg, and CoM x, z) standing on `foot`.
    pub fn fall_deg(
        &self,
        feet_kg: (f64, f64, f64),
        foot: &FootGeometry,
    ) -> Result<[f64; 2], IdentError> {
        let c = self.com();
        let m: f64 = self.masses.iter().sum();
        let feet = FeetMass {
            fraction: feet_kg.0 / m,
            x: feet_kg.1,
            z: feet_kg.2,
        };
        let (f, b) = sagittal_tip_angles(c[0], c[2], &feet, foot)?;
        Ok([f.to_degrees(), b.to_degrees()])
    }
}

/// The masses every method uses: the prior's, with `added` kg on `part`'s mass.
fn known_masses(prior: [f64; 3], parts: &BodyParts, part: usize, added: f64) -> [f64; 3] {
    let mut m = prior;
    m[parts.three_mass_part[part]] += added;
    m
}

/// The seed's geometric CoM (seed 000 eq. 8-13) from `[forward, backward, left,
/// right]`, deg.
fn seed_com(angles_deg: [f64; 4], constants: &SeedConstants) -> Result<[f64; 3], IdentError> {
    let a = SeedAngles {
        alpha1: angles_deg[0],
        beta1: angles_deg[1],
        alpha2: angles_deg[2],
        beta2: angles_deg[3],
    };
    Ok(seed_method(&a, constants)?.com)
}

/// The seed's manual method (see the module documentation): the seed's geometric CoM
/// from the four angles (deg) on `constants`, the mass of the changed `part` placed to
/// give it, the other two at `prior_positions`.
pub fn manual_method(
    angles_deg: [f64; 4],
    masses: [f64; 3],
    prior_positions: [[f64; 3]; 3],
    changed_mass: usize,
    constants: &SeedConstants,
) -> Result<ThreeMassModel, IdentError> {
    let seed = seed_com(angles_deg, constants)?;
    let total: f64 = masses.iter().sum();
    let mut positions = prior_positions;
    positions[changed_mass] = [0, 1, 2].map(|k| {
        let others: f64 = (0..3)
            .filter(|&i| i != changed_mass)
            .map(|i| masses[i] * prior_positions[i][k])
            .sum();
        (total * seed[k] - others) / masses[changed_mass]
    });
    Ok(ThreeMassModel { masses, positions })
}

/// A tip-over study report carrying only the four measured angles (feet flat), for
/// [`adapt`].
fn measured_report(robot: &str, deg: [f64; 4], foot: &FootGeometry) -> StudyReport {
    let dir = |a: f64| DirectionReport {
        commanded_deg: a,
        measured_deg: a,
        time_s: 0.0,
        static_deg: a,
        static_note: None,
        excess_deg: 0.0,
        rigid_static_deg: a,
        rigid_static_note: None,
        lean_deg: a,
        onset_positions: Default::default(),
    };
    StudyReport {
        robot: robot.into(),
        forward: dir(deg[0]),
        backward: dir(deg[1]),
        left: dir(deg[2]),
        right: dir(deg[3]),
        com: ComReport {
            truth: [f64::NAN; 3],
            seed_method: [f64::NAN; 3],
            exact_method: [f64::NAN; 3],
            seed_error: f64::NAN,
            exact_error: f64::NAN,
            frontal_lever_true: f64::NAN,
            frontal_lever_exact: f64::NAN,
        },
        seed_constants: String::new(),
        foot: FootReport {
            front: foot.front,
            back: foot.back,
            ankle_height: foot.ankle_height,
            roll_axis_height: foot.roll_axis_height,
            ankle_half_spacing: foot.ankle_half_spacing,
            outer: foot.outer,
            inner: foot.inner,
            feet_mass_fraction: f64::NAN,
            feet_com: [f64::NAN; 2],
        },
        protocol: None,
        bus: None,
    }
}

/// The exact inversion's three-mass model of a sample: [`adapt`] with the total mass
/// and the link.
fn exact_model(
    prior: &Description,
    s: &Sample,
    foot: &FootGeometry,
) -> Result<ThreeMassModel, IdentError> {
    let tip = measured_report(&prior.name, s.measured_deg, foot);
    let opts = AdaptOptions {
        total_mass: Some(s.total_mass),
        host: Some(s.change.link.clone()),
        merge: true,
        angle_resolution_deg: None,
        protocol_bias_deg: None,
    };
    let a = adapt(prior, &tip, &opts)?;
    let r = a
        .report
        .adapted_reduced
        .ok_or_else(|| IdentError::new("the exact inversion placed no mass"))?;
    let t = r.three_masses;
    Ok(ThreeMassModel {
        masses: [t[0].0, t[1].0, t[2].0],
        positions: [t[0].1, t[1].1, t[2].1],
    })
}

/// Errors of one method over a set of changes.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct MethodErrors {
    pub method: String,
    pub n: usize,
    /// Changes the method gave no model for.
    pub failed: usize,
    /// Mean over the three masses of |position - truth|, mm: mean, 95th percentile and
    /// largest over the set.
    pub position_mm: [f64; 3],
    /// The hip mass alone, mm (mean, 95th percentile, largest).
    pub hip_mm: [f64; 3],
    /// |vCoM - CoM|, mm (mean, 95th percentile, largest).
    pub com_mm: [f64; 3],
    /// |fall angle - truth|, deg, forward and backward together (mean, 95th percentile,
    /// largest).
    pub fall_deg: [f64; 3],
}

fn summary(mut v: Vec<f64>) -> [f64; 3] {
    if v.is_empty() {
        return [f64::NAN; 3];
    }
    v.sort_by(f64::total_cmp);
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let p95 = v[((v.len() as f64 * 0.95).ceil() as usize).clamp(1, v.len()) - 1];
    [mean, p95, v[v.len() - 1]]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// One row of the seed's Tables VI-VII: a change, what each method made of it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TableRow {
    pub change: crate::ann_data::Change,
    pub part: String,
    /// Measured forward and backward angles, deg.
    pub measured_deg: [f64; 2],
    /// The changed robot's static forward and backward angles, deg.
    pub true_deg: [f64; 2],
    /// CoM, mm: truth, then each method of [`METHOD_NAMES`].
    pub com_mm: [[f64; 3]; 5],
    /// Fall angles (forward, backward), deg, of each method's model.
    pub fall_deg: [[f64; 2]; 4],
}

/// The methods compared, in the order of [`SetEvaluation::methods`] (which adds the
/// exact inversion on the changes above the ankles).
pub const METHOD_NAMES: [&str; 4] = [
    "manual, seed CoM as printed",
    "manual, seed CoM less its bias on the prior",
    "ANN 5-10-5",
    "exact inversion",
];

/// A set's evaluation: errors per method ([`METHOD_NAMES`], then the exact inversion
/// on the changes above the ankles alone) and the first rows.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SetEvaluation {
    pub set: String,
    pub methods: Vec<MethodErrors>,
    pub rows: Vec<TableRow>,
}

type Scored = Option<(ThreeMassModel, [f64; 2])>;

/// The three methods on `samples`; the exact inversion runs on `threads` threads.
pub fn evaluate(
    set: &str,
    prior: &Description,
    model: &AnnModel,
    samples: &[Sample],
    threads: usize,
) -> Result<SetEvaluation, IdentError> {
    let foot = training_foot(prior)?;
    let constants = if prior.name == twinloop_description::builtin::km20::NAME {
        SEED_000_CONSTANTS
    } else {
        SeedConstants::from_foot(&foot)
    };
    let prior_tip = static_tip(prior, &foot)?;
    let prior_three = prior_tip.reduced.three_masses;
    let prior_pos = [prior_three[0].1, prior_three[1].1, prior_three[2].1];
    // What the seed's method says of the unchanged robot: its bias, which a person
    // who knows the prior model takes off.
    let seed_bias = {
        let c = seed_com(prior_tip.angles.to_degrees(), &constants)?;
        [0, 1, 2].map(|k| c[k] - prior_tip.com[k])
    };
    let score = |s: &Sample, m: Result<ThreeMassModel, IdentError>| -> Scored {
        let m = m.ok()?;
        let feet_kg = (s.feet.fraction * s.total_mass, s.feet.x, s.feet.z);
        let f = m.fall_deg(feet_kg, &foot).ok()?;
        Some((m, f))
    };
    let scored: Vec<[Scored; 4]> = parallel_map(samples.len(), threads, &|_| {}, &|i| {
        let s = &samples[i];
        let masses = known_masses(model.prior_masses, &model.parts, s.part, s.change.mass);
        let k = model.parts.three_mass_part[s.part];
        let manual = manual_method(s.measured_deg, masses, prior_pos, k, &constants);
        let calibrated = manual.clone().map(|m| calibrated_manual(m, k, seed_bias));
        let ann = Ok(ThreeMassModel {
            masses,
            positions: model.positions(s.measured_deg[0], s.measured_deg[1], s.change.mass, s.part),
        });
        let exact = exact_model(prior, s, &foot);
        Ok([
            score(s, manual),
            score(s, calibrated),
            score(s, ann),
            score(s, exact),
        ])
    })?;
    let feet_links = below_ankles(prior)?;
    let on_feet = |s: &Sample| feet_links.contains(&s.change.link);
    let mut methods = vec![];
    for (k, name) in METHOD_NAMES.iter().enumerate() {
        methods.push(method_errors(name, samples, &scored, k, &foot, &|_| true)?);
    }
    methods.push(method_errors(
        "exact inversion, changes above the ankles",
        samples,
        &scored,
        3,
        &foot,
        &|s| !on_feet(s),
    )?);
    let rows = samples
        .iter()
        .zip(&scored)
        .take(6)
        .map(|(s, sc)| {
            let mm = |c: [f64; 3]| c.map(|v| v * 1e3);
            let com = |k: usize| sc[k].as_ref().map_or([f64::NAN; 3], |(m, _)| mm(m.com()));
            let fall = |k: usize| sc[k].as_ref().map_or([f64::NAN; 2], |(_, f)| *f);
            TableRow {
                change: s.change.clone(),
                part: model.parts.names[s.part].clone(),
                measured_deg: [s.measured_deg[0], s.measured_deg[1]],
                true_deg: [s.true_deg[0], s.true_deg[1]],
                com_mm: [mm(s.com), com(0), com(1), com(2), com(3)],
                fall_deg: [fall(0), fall(1), fall(2), fall(3)],
            }
        })
        .collect();
    Ok(SetEvaluation {
        set: set.into(),
        methods,
        rows,
    })
}

/// Method `k`'s errors over the samples `keep` accepts.
fn method_errors(
    name: &str,
    samples: &[Sample],
    scored: &[[Scored; 4]],
    k: usize,
    foot: &FootGeometry,
    keep: &dyn Fn(&Sample) -> bool,
) -> Result<MethodErrors, IdentError> {
    let (mut pos, mut hip, mut com, mut fall, mut failed, mut n) =
        (vec![], vec![], vec![], vec![], 0, 0);
    for (s, sc) in samples.iter().zip(scored).filter(|(s, _)| keep(s)) {
        n += 1;
        let Some((m, f)) = &sc[k] else {
            failed += 1;
            continue;
        };
        pos.push(
            (0..3)
                .map(|i| dist(m.positions[i], s.positions[i]))
                .sum::<f64>()
                / 3.0
                * 1e3,
        );
        hip.push(dist(m.positions[2], s.positions[2]) * 1e3);
        com.push(dist(m.com(), s.com) * 1e3);
        let t = true_fall(s, foot)?;
        fall.push((f[0] - t[0]).abs());
        fall.push((f[1] - t[1]).abs());
    }
    Ok(MethodErrors {
        method: name.to_string(),
        n,
        failed,
        position_mm: summary(pos),
        hip_mm: summary(hip),
        com_mm: summary(com),
        fall_deg: summary(fall),
    })
}

/// The manual model with the seed method's bias on the prior (`bias`, m, its CoM
/// minus the prior's true CoM) taken off the changed mass's position.
fn calibrated_manual(mut m: ThreeMassModel, changed_mass: usize, bias: [f64; 3]) -> ThreeMassModel {
    let total: f64 = m.masses.iter().sum();
    let mass = m.masses[changed_mass];
    for (p, b) in m.positions[changed_mass].iter_mut().zip(bias) {
        *p -= total * b / mass;
    }
    m
}

/// The links below the ankle pitch joints (the feet, which stay on the ground in the
/// fore/aft lean).
fn below_ankles(robot: &Description) -> Result<Vec<String>, IdentError> {
    let n = crate::tipover_study::ankle_names(robot)?;
    Ok(robot
        .links
        .iter()
        .filter(|l| {
            let mut link = l.name.clone();
            while let Some(j) = robot.parent_joint(&link) {
                if j.name == n[0] || j.name == n[1] {
                    return true;
                }
                link = j.parent.clone();
            }
            false
        })
        .map(|l| l.name.clone())
        .collect())
}

/// The ANN's mean fall-angle error (forward and backward, deg) on `samples`.
fn ann_fall_error(
    model: &AnnModel,
    samples: &[Sample],
    foot: &FootGeometry,
) -> Result<f64, IdentError> {
    let mut sum = 0.0;
    for s in samples {
        let m = ThreeMassModel {
            masses: known_masses(model.prior_masses, &model.parts, s.part, s.change.mass),
            positions: model.positions(s.measured_deg[0], s.measured_deg[1], s.change.mass, s.part),
        };
        let feet_kg = (s.feet.fraction * s.total_mass, s.feet.x, s.feet.z);
        let (f, t) = (m.fall_deg(feet_kg, foot)?, true_fall(s, foot)?);
        sum += (f[0] - t[0]).abs() + (f[1] - t[1]).abs();
    }
    Ok(sum / (2 * samples.len().max(1)) as f64)
}

/// The truth's forward and backward angles by the same formula as the models'.
fn true_fall(s: &Sample, foot: &FootGeometry) -> Result<[f64; 2], IdentError> {
    ThreeMassModel {
        masses: s.masses,
        positions: s.positions,
    }
    .fall_deg((s.feet.fraction * s.total_mass, s.feet.x, s.feet.z), foot)
}

/// Settings of [`train_ann`].
#[derive(Debug, Clone, PartialEq)]
pub struct AnnTrainOptions {
    pub data: DataOptions,
    pub train: TrainOptions,
    /// Give the network the weighed added mass as an input besides the seed's three.
    pub mass_input: bool,
    /// Trainings from different initial weights; the one with the smallest fall-angle
    /// error on the testing set is kept.
    pub restarts: usize,
}

impl Default for AnnTrainOptions {
    fn default() -> Self {
        AnnTrainOptions {
            data: DataOptions::default(),
            train: TrainOptions::default(),
            mass_input: true,
            restarts: 4,
        }
    }
}

/// What `adapt train` reports.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrainReport {
    pub robot: String,
    pub samples: usize,
    pub seed: u64,
    pub threads: usize,
    pub noise_deg: f64,
    pub mass_range: [f64; 2],
    /// Training, testing, validation.
    pub split: [usize; 3],
    pub parts: Vec<String>,
    pub layout: Vec<usize>,
    pub optimiser: String,
    /// The kept training's learning curve.
    pub log: TrainLog,
    /// Each restart's mean fall-angle error on the testing set, deg, and the one kept.
    pub restart_fall_deg: Vec<f64>,
    pub restart_kept: usize,
    /// Wall time, s: making the data, training, evaluating.
    pub seconds: [f64; 3],
    pub testing: SetEvaluation,
    pub validation: SetEvaluation,
    /// The static route against the full simulated tip-over (`--check-sim`).
    pub sim_check: Vec<SimCheck>,
    pub files: Vec<String>,
}

/// The network's description before training (a placeholder net).
fn untrained_model(
    prior: &Description,
    parts: &BodyParts,
    opts: &AnnTrainOptions,
    split: [usize; 3],
    prior_three: [(f64, [f64; 3]); 3],
) -> AnnModel {
    AnnModel {
        robot: prior.name.clone(),
        inputs: ["forward_deg", "backward_deg", "added_kg"]
            .into_iter()
            .filter(|n| opts.mass_input || *n != "added_kg")
            .map(String::from)
            .chain(parts.names.iter().map(|p| format!("part:{p}")))
            .collect(),
        outputs: MASS_NAMES
            .iter()
            .flat_map(|m| ["x", "y", "z"].map(|a| format!("{m}.{a}")))
            .collect(),
        parts: parts.clone(),
        mass_input: opts.mass_input,
        prior_masses: [prior_three[0].0, prior_three[1].0, prior_three[2].0],
        training: TrainingInfo {
            samples: split.iter().sum(),
            seed: opts.data.seed,
            mass_range: [opts.data.mass_range.0, opts.data.mass_range.1],
            noise_deg: opts.data.noise_deg,
            split,
            best_epoch: 0,
            epochs: 0,
            optimiser: format!(
                "Adam (beta1 0.9, beta2 0.999), rate {}, mini-batch {}",
                opts.train.learning_rate, opts.train.batch
            ),
        },
        net: Mlp::new(&[1, 1], &mut twinloop_random::SplitMix64(0)),
    }
}

/// Trainings from `opts.restarts` initial weights, in parallel; the one whose models
/// fall at the testing set's angles best is kept (the seed's criterion for its
/// network). `xy`: training inputs and outputs, testing inputs and outputs. Returns the
/// network, its log, every restart's testing fall-angle error and the one kept.
fn best_restart(
    model: &AnnModel,
    xy: [&[Vec<f64>]; 4],
    testing: &[Sample],
    foot: &FootGeometry,
    opts: &AnnTrainOptions,
) -> Result<(Mlp, TrainLog, Vec<f64>, usize), IdentError> {
    let restarts = parallel_map(opts.restarts.max(1), opts.data.threads, &|_| {}, &|r| {
        let o = TrainOptions {
            seed: opts.train.seed.wrapping_add(r as u64 * 0x9E37_79B9),
            ..opts.train.clone()
        };
        let (net, log) = train(xy[0], xy[1], xy[2], xy[3], &o)?;
        let mut m = model.clone();
        m.net = net;
        let fall = ann_fall_error(&m, testing, foot)?;
        Ok((m.net, log, fall))
    })?;
    let pick = (0..restarts.len())
        .min_by(|&a, &b| restarts[a].2.total_cmp(&restarts[b].2))
        .unwrap_or(0);
    let falls: Vec<f64> = restarts.iter().map(|r| r.2).collect();
    let (net, log, _) = restarts
        .into_iter()
        .nth(pick)
        .ok_or_else(|| IdentError::new("no network trained"))?;
    Ok((net, log, falls, pick))
}

/// Make the data, split them, train the network, evaluate the three methods on the
/// testing and validation sets; `progress(done)` during the data generation.
pub fn train_ann(
    prior: &Description,
    opts: &AnnTrainOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(AnnModel, TrainReport), IdentError> {
    if opts.data.samples < 20 {
        return Err(IdentError::new(format!(
            "needs at least 20 changes to split into three sets, got {}",
            opts.data.samples
        ))
        .option("samples"));
    }
    let t0 = Instant::now();
    let (_, samples) = generate(prior, &opts.data, progress)?;
    train_ann_on(prior, opts, samples, t0.elapsed().as_secs_f64())
}

/// [`train_ann`] on samples made elsewhere (`adapt train --ray`: as Ray tasks by
/// `python -m twinloop.adapt_train`): `samples` must be [`generate`]'s for
/// `opts.data`, in index order; `data_seconds` is the time they took.
pub fn train_ann_on(
    prior: &Description,
    opts: &AnnTrainOptions,
    samples: Vec<Sample>,
    data_seconds: f64,
) -> Result<(AnnModel, TrainReport), IdentError> {
    if samples.len() != opts.data.samples || samples.len() < 20 {
        return Err(IdentError::new(format!(
            "needs the {} changes asked for (at least 20), got {}",
            opts.data.samples,
            samples.len()
        ))
        .option("samples"));
    }
    let parts = BodyParts::of(prior)?;
    if let Some(s) = samples.iter().find(|s| s.part >= parts.names.len()) {
        return Err(IdentError::new(format!(
            "a change on \"{}\" names body part {} of {}'s {}",
            s.change.link,
            s.part,
            prior.name,
            parts.names.len()
        ))
        .option("samples"));
    }
    let t1 = Instant::now();
    let n = samples.len();
    let (n_train, n_test) = (n * 70 / 100, n * 15 / 100);
    let (training, rest) = samples.split_at(n_train);
    let (testing, validation) = rest.split_at(n_test);
    let foot = training_foot(prior)?;
    let prior_three = static_tip(prior, &foot)?.reduced.three_masses;
    let split = [training.len(), testing.len(), validation.len()];
    let mut model = untrained_model(prior, &parts, opts, split, prior_three);
    let xy = |set: &[Sample]| -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        set.iter()
            .map(|s| {
                (
                    model.input(s.measured_deg[0], s.measured_deg[1], s.change.mass, s.part),
                    s.positions.iter().flatten().copied().collect(),
                )
            })
            .unzip()
    };
    let (tx, ty) = xy(training);
    let (sx, sy) = xy(testing);
    let (net, log, fall_by_restart, pick) =
        best_restart(&model, [&tx, &ty, &sx, &sy], testing, &foot, opts)?;
    model.net = net;
    model.training.best_epoch = log.best_epoch;
    model.training.epochs = log.train_mse.len();
    let t2 = Instant::now();
    let threads = crate::ann_data::worker_threads(opts.data.threads);
    let testing_eval = evaluate("testing", prior, &model, testing, threads)?;
    let validation_eval = evaluate("validation", prior, &model, validation, threads)?;
    let t3 = Instant::now();
    let report = TrainReport {
        robot: prior.name.clone(),
        samples: n,
        seed: opts.data.seed,
        threads,
        noise_deg: opts.data.noise_deg,
        mass_range: model.training.mass_range,
        split: model.training.split,
        parts: parts.names.clone(),
        layout: model.net.sizes(),
        optimiser: model.training.optimiser.clone(),
        log,
        restart_fall_deg: fall_by_restart,
        restart_kept: pick,
        seconds: [
            data_seconds,
            (t2 - t1).as_secs_f64(),
            (t3 - t2).as_secs_f64(),
        ],
        testing: testing_eval,
        validation: validation_eval,
        sim_check: vec![],
        files: vec![],
    };
    Ok((model, report))
}

/// What `adapt --method ann` reports.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AnnAdaptReport {
    pub robot: String,
    pub method: String,
    /// Forward and backward measured angles, deg (the network's inputs).
    pub measured_deg: [f64; 2],
    pub host: String,
    pub part: String,
    /// The added mass (total mass minus the prior's), kg, if the total mass was given.
    pub added_mass: Option<f64>,
    pub prior: ThreeMassModel,
    pub adapted: ThreeMassModel,
    /// The adapted three masses' CoM (vCoM), m.
    pub adapted_com: [f64; 3],
    /// Static forward and backward fall angles of the adapted three-mass model on the
    /// prior's feet, deg.
    pub adapted_fall_deg: [f64; 2],
    pub notes: Vec<String>,
    pub files: Vec<String>,
}

/// `adapt --method ann`: the three-mass LIPM from the network, the measured forward
/// and backward angles of `tip` and the link `host` the mass went on.
pub fn adapt_ann(
    prior: &Description,
    tip: &StudyReport,
    model: &AnnModel,
    host: &str,
    total_mass: Option<f64>,
) -> Result<AnnAdaptReport, IdentError> {
    if model.robot != prior.name {
        return Err(IdentError::new(format!(
            "the network was trained on \"{}\", the robot is \"{}\"",
            model.robot, prior.name
        ))
        .option("net"));
    }
    let part = model.parts.part_of(host).ok_or_else(|| {
        IdentError::new(format!("no link \"{host}\" in \"{}\"", prior.name)).option("host")
    })?;
    let foot = training_foot(prior)?;
    let st = static_tip(prior, &foot)?;
    let r = st.reduced.three_masses;
    let prior3 = ThreeMassModel {
        masses: [r[0].0, r[1].0, r[2].0],
        positions: [r[0].1, r[1].1, r[2].1],
    };
    let added = match total_mass {
        Some(m) if !(m.is_finite() && m > st.total_mass) => {
            return Err(IdentError::new(format!(
                "{m} kg must exceed the prior's {:.4} kg (an added mass)",
                st.total_mass
            ))
            .option("total_mass"));
        }
        Some(m) => Some(m - st.total_mass),
        None => None,
    };
    if model.mass_input && added.is_none() {
        return Err(IdentError::new(
            "this network takes the added mass as an input: give the total mass",
        )
        .option("total_mass"));
    }
    let (f, b) = (tip.forward.measured_deg, tip.backward.measured_deg);
    let adapted = ThreeMassModel {
        masses: known_masses(prior3.masses, &model.parts, part, added.unwrap_or(0.0)),
        positions: model.positions(f, b, added.unwrap_or(0.0), part),
    };
    let feet_kg = (st.feet.fraction * st.total_mass, st.feet.x, st.feet.z);
    let mut notes = vec![format!(
        "inputs: forward {f:.3} deg, backward {b:.3} deg, part \"{}\" (the left and right angles are not the network's inputs)",
        model.parts.names[part]
    )];
    if added.is_none() {
        notes.push(
            "no total mass given: the masses are the prior's (the network gives positions only)"
                .into(),
        );
    }
    Ok(AnnAdaptReport {
        robot: prior.name.clone(),
        method: "ann".into(),
        measured_deg: [f, b],
        host: host.into(),
        part: model.parts.names[part].clone(),
        added_mass: added,
        prior: prior3,
        adapted_com: adapted.com(),
        adapted_fall_deg: adapted.fall_deg(feet_kg, &foot)?,
        adapted,
        notes,
        files: vec![],
    })
}
