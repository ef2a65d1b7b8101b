//! The ANN's training data (seed 000 section V.C): random hardware changes on a robot
//! and, for each, what the tip-over experiment would measure and the three-mass LIPM
//! the change makes.
//!
//! A change is one point mass (uniform in a mass range, 0.05-0.5 kg by default) on a
//! link drawn uniformly from the links that have a collision outline, at a point drawn
//! uniformly inside one of that link's collision shapes (boxes on km20).
//!
//! The fall angles come from the fast route, the static tipping analysis: the changed
//! model in its standing pose gives its CoM, its feet (the part that stays on the
//! ground in the fore/aft lean) and its frontal lever, and
//! [`crate::tipover::tip_angles`] turns them into the four angles at which the CoM
//! crosses the support edge (rigid robot, feet flat). That takes a fraction of a
//! millisecond where the simulated experiment takes seconds;
//! [`check_against_simulation`] runs the full simulated study on a sample of changes
//! to say how far the two differ. A measurement noise (Gaussian, `noise_deg`) is added
//! to the static angles to give the "measured" ones the methods see.
//!
//! The general location of the change (the seed's categorical input `m_p`) is the body
//! part holding the link ([`BodyParts`]). Each sample draws from its own generator
//! (seeded by the run's seed and the sample's index), so the data do not depend on how
//! many threads made them.

use crate::adapt::{ReducedSummary, leg_roots, reduced, standing};
use crate::error::IdentError;
use crate::tipover::{FeetMass, TipAngles, feet_mass, frontal_lever, tip_angles};
use crate::tipover_study::{StudyOptions, ankle_names, hip_roll_names, run_study};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicUsize, Ordering};
use twinloop_description::builtin::FootGeometry;
use twinloop_description::{Description, Geometry, Shape};
use twinloop_random::SplitMix64;

/// One hardware change: `mass` kg at `xyz` (m) in `link`'s frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Change {
    pub link: String,
    pub mass: f64,
    pub xyz: [f64; 3],
}

/// What the static route gives for a model in its standing pose: CoM (standing frame:
/// ankle pitch midpoint, x forward, y left, z up), feet, the four static fall angles
/// and the reduced models.
#[derive(Debug, Clone)]
pub struct StaticTip {
    pub com: [f64; 3],
    pub total_mass: f64,
    pub feet: FeetMass,
    pub angles: TipAngles,
    pub reduced: ReducedSummary,
}

/// The static route (see the module documentation) on `robot` standing on `foot`.
pub fn static_tip(robot: &Description, foot: &FootGeometry) -> Result<StaticTip, IdentError> {
    let frame = standing(robot)?;
    let c = frame.com(robot)?;
    let com = [c.x, c.y, c.z];
    let n = ankle_names(robot)?;
    let h = hip_roll_names(robot)?;
    let (model, q) = (&frame.model, &frame.q);
    let feet = feet_mass(model, q, [&n[0], &n[1]])?;
    let lever = frontal_lever(model, q, [&h[0], &h[1]], [&n[2], &n[3]])?;
    let angles = tip_angles(com, &feet, &lever, foot)?;
    Ok(StaticTip {
        com,
        total_mass: model.total_mass,
        feet,
        angles,
        reduced: reduced(&frame, robot, foot)?,
    })
}

/// The body parts of a robot, the values of the seed's categorical input: the root
/// link's own part, and one part per joint leaving the root link (a leg, an arm, the
/// head on km20), named by that joint's child link.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyParts {
    pub names: Vec<String>,
    /// Which mass of the three-mass LIPM each part belongs to (0 left leg, 1 right
    /// leg, 2 hip).
    pub three_mass_part: Vec<usize>,
    /// `(link, part)` for every link.
    pub link_part: Vec<(String, usize)>,
}

impl BodyParts {
    pub fn of(robot: &Description) -> Result<BodyParts, IdentError> {
        let root = robot
            .root_link()
            .ok_or_else(|| IdentError::new(format!("\"{}\" has no single root link", robot.name)))?
            .to_string();
        let model = twinloop_dynamics::Model::from_description(robot)
            .map_err(|e| IdentError::new(e.to_string()))?;
        let roots = leg_roots(&model, robot)?;
        // The chain of joints from a link up to the root, nearest first.
        let up = |link: &str| {
            let mut chain = vec![];
            let mut l = link.to_string();
            while let Some(j) = robot.parent_joint(&l) {
                chain.push(j.clone());
                l = j.parent.clone();
            }
            chain
        };
        let mut names = vec![root.clone()];
        let mut three_mass_part = vec![2];
        let mut link_part = vec![];
        for link in &robot.links {
            let chain = up(&link.name);
            let part = match chain.last() {
                None => 0,
                Some(top) => match names.iter().position(|n| *n == top.child) {
                    Some(k) => k,
                    None => {
                        names.push(top.child.clone());
                        let leg = |k: usize| up(&top.child).iter().any(|j| j.name == roots[k]);
                        three_mass_part.push(if leg(0) {
                            0
                        } else if leg(1) {
                            1
                        } else {
                            2
                        });
                        names.len() - 1
                    }
                },
            };
            link_part.push((link.name.clone(), part));
        }
        Ok(BodyParts {
            names,
            three_mass_part,
            link_part,
        })
    }

    /// The part holding `link`.
    pub fn part_of(&self, link: &str) -> Option<usize> {
        self.link_part
            .iter()
            .find(|(l, _)| l == link)
            .map(|(_, p)| *p)
    }
}

/// One training or evaluation example (serialised when it is made elsewhere: on Ray,
/// `python -m twinloop.adapt_train`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Sample {
    pub change: Change,
    /// The body part of the change ([`BodyParts`]).
    pub part: usize,
    /// The changed robot's static fall angles `[forward, backward, left, right]`, deg.
    pub true_deg: [f64; 4],
    /// The same with the measurement noise: what the methods see.
    pub measured_deg: [f64; 4],
    /// The changed robot's CoM (standing frame), m.
    pub com: [f64; 3],
    pub total_mass: f64,
    /// The changed robot's feet (see [`FeetMass`]).
    pub feet: FeetMass,
    /// The changed robot's three-mass LIPM: masses, kg (left leg, right leg, hip) and
    /// positions, m (standing frame).
    pub masses: [f64; 3],
    pub positions: [[f64; 3]; 3],
}

/// Settings of [`generate`].
#[derive(Debug, Clone, PartialEq)]
pub struct DataOptions {
    pub samples: usize,
    pub seed: u64,
    /// Added mass range, kg.
    pub mass_range: (f64, f64),
    /// One-sigma noise on each measured angle, deg.
    pub noise_deg: f64,
    /// Worker threads (0: all cores).
    pub threads: usize,
}

impl Default for DataOptions {
    fn default() -> Self {
        DataOptions {
            samples: 10_000,
            seed: 1,
            mass_range: (0.05, 0.5),
            noise_deg: 0.05,
            threads: 0,
        }
    }
}

/// A point drawn uniformly inside a collision shape (link frame), if the shape is a
/// primitive.
fn point_in(shape: &Shape, rng: &mut SplitMix64) -> Option<[f64; 3]> {
    let local = match shape.geometry {
        Geometry::Box { size } => [0, 1, 2].map(|k| rng.uniform(-0.5 * size[k], 0.5 * size[k])),
        Geometry::Sphere { radius } => loop {
            let p = [0; 3].map(|_| rng.uniform(-radius, radius));
            if p.iter().map(|v| v * v).sum::<f64>() <= radius * radius {
                break p;
            }
        },
        Geometry::Cylinder { radius, length } | Geometry::Capsule { radius, length } => loop {
            let (x, y) = (rng.uniform(-radius, radius), rng.uniform(-radius, radius));
            if x * x + y * y <= radius * radius {
                break [x, y, rng.uniform(-0.5 * length, 0.5 * length)];
            }
        },
        Geometry::Mesh { .. } => return None,
    };
    let r = shape.origin.rotation();
    let o = shape.origin.xyz;
    Some([0, 1, 2].map(|i| o[i] + (0..3).map(|j| r[i][j] * local[j]).sum::<f64>()))
}

/// The links a change can go on: those with a primitive collision outline.
pub fn outlined_links(robot: &Description) -> Vec<usize> {
    (0..robot.links.len())
        .filter(|&i| {
            robot.links[i]
                .collisions
                .iter()
                .any(|s| !matches!(s.geometry, Geometry::Mesh { .. }))
        })
        .collect()
}

/// A random change: a link with an outline, a point inside it, a mass in the range.
pub fn random_change(
    robot: &Description,
    links: &[usize],
    mass_range: (f64, f64),
    rng: &mut SplitMix64,
) -> Change {
    loop {
        let link = &robot.links[links[rng.below(links.len() as u64) as usize]];
        let shapes: Vec<&Shape> = link
            .collisions
            .iter()
            .filter(|s| !matches!(s.geometry, Geometry::Mesh { .. }))
            .collect();
        let shape = shapes[rng.below(shapes.len() as u64) as usize];
        if let Some(xyz) = point_in(shape, rng) {
            return Change {
                link: link.name.clone(),
                mass: rng.uniform(mass_range.0, mass_range.1),
                xyz,
            };
        }
    }
}

/// The robot with `change` merged into its link.
pub fn changed(prior: &Description, change: &Change) -> Result<Description, IdentError> {
    let mut d = prior.clone();
    twinloop_description::builtin::add_point_mass(&mut d, &change.link, change.mass, change.xyz)?;
    Ok(d)
}

/// The foot geometry the training needs: a built-in robot's.
pub fn training_foot(robot: &Description) -> Result<FootGeometry, IdentError> {
    twinloop_description::builtin::foot_geometry(&robot.name).ok_or_else(|| {
        IdentError::new(format!(
            "\"{}\" has no known foot geometry: training runs on a built-in robot (builtin:km20, builtin:lab17)",
            robot.name
        ))
        .option("robot")
    })
}

/// One sample: draws changes until the changed robot can stand (at most 100 draws).
fn sample(
    prior: &Description,
    parts: &BodyParts,
    links: &[usize],
    foot: &FootGeometry,
    opts: &DataOptions,
    index: usize,
) -> Result<Sample, IdentError> {
    let mut rng = SplitMix64(opts.seed ^ (index as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
    rng.next_u64();
    let mut last = IdentError::new("no draw");
    for _ in 0..100 {
        let change = random_change(prior, links, opts.mass_range, &mut rng);
        let tip = match changed(prior, &change).and_then(|d| static_tip(&d, foot)) {
            Ok(t) => t,
            Err(e) => {
                last = e;
                continue;
            }
        };
        let true_deg = tip.angles.to_degrees();
        let measured_deg = true_deg.map(|a| a + opts.noise_deg * rng.normal());
        let r = &tip.reduced.three_masses;
        return Ok(Sample {
            part: parts.part_of(&change.link).unwrap_or(0),
            change,
            true_deg,
            measured_deg,
            com: tip.com,
            total_mass: tip.total_mass,
            feet: tip.feet,
            masses: [r[0].0, r[1].0, r[2].0],
            positions: [r[0].1, r[1].1, r[2].1],
        });
    }
    Err(last)
}

/// The number of worker threads: `threads`, or all cores when 0.
pub fn worker_threads(threads: usize) -> usize {
    twinloop_optim::parallel::worker_threads(threads)
}

/// `f(i)` for `i` in `0..n` on rayon's pool with `threads` workers
/// ([`twinloop_optim::parallel::on_threads`]), results in index order; `progress` is
/// called with the number done so far after each. Every index runs; the error
/// returned is the lowest failing index's, whatever the thread count.
pub(crate) fn parallel_map<T: Send>(
    n: usize,
    threads: usize,
    progress: &(dyn Fn(usize) + Sync),
    f: &(dyn Fn(usize) -> Result<T, IdentError> + Sync),
) -> Result<Vec<T>, IdentError> {
    let done = AtomicUsize::new(0);
    let results: Vec<Result<T, IdentError>> = twinloop_optim::parallel::on_threads(threads, || {
        (0..n)
            .into_par_iter()
            .map(|i| {
                let r = f(i);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                r
            })
            .collect()
    });
    results.into_iter().collect()
}

/// `opts.samples` random changes of `prior` and their static tip-overs, on all cores;
/// `progress(done)` after each sample.
pub fn generate(
    prior: &Description,
    opts: &DataOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(BodyParts, Vec<Sample>), IdentError> {
    generate_range(prior, opts, 0..opts.samples, progress)
}

/// The samples of indices `range` of [`generate`]'s (the same draws).
pub fn generate_range(
    prior: &Description,
    opts: &DataOptions,
    range: std::ops::Range<usize>,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(BodyParts, Vec<Sample>), IdentError> {
    let (lo, hi) = opts.mass_range;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo) {
        return Err(
            IdentError::new(format!("needs 0 < low <= high, got {lo}..{hi} kg"))
                .option("mass_range"),
        );
    }
    if !(opts.noise_deg.is_finite() && opts.noise_deg >= 0.0) {
        return Err(
            IdentError::new(format!("must be >= 0, got {}", opts.noise_deg)).option("noise_deg"),
        );
    }
    let foot = training_foot(prior)?;
    let parts = BodyParts::of(prior)?;
    let links = outlined_links(prior);
    if links.is_empty() {
        return Err(IdentError::new(format!(
            "\"{}\" has no link with a collision outline to put a change in",
            prior.name
        ))
        .option("robot"));
    }
    let samples = parallel_map(range.len(), opts.threads, progress, &|i| {
        sample(prior, &parts, &links, &foot, opts, range.start + i)
    })?;
    Ok((parts, samples))
}

/// A change's fall angles by the static route and by the full simulated tip-over
/// study (`measured_deg` of each direction), `[forward, backward, left, right]`, deg.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SimCheck {
    pub change: Change,
    pub static_deg: [f64; 4],
    pub simulated_deg: [f64; 4],
}

impl SimCheck {
    /// The largest |simulated - static| over forward and backward, and over left and
    /// right, deg.
    pub fn max_difference(&self) -> [f64; 2] {
        let d = |k: usize| (self.simulated_deg[k] - self.static_deg[k]).abs();
        [d(0).max(d(1)), d(2).max(d(3))]
    }
}

/// The static route against the full simulated tip-over study on `changes`, in
/// parallel; `progress(done)` after each.
pub fn check_against_simulation(
    prior: &Description,
    changes: &[Change],
    study: &StudyOptions,
    threads: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<SimCheck>, IdentError> {
    let foot = training_foot(prior)?;
    parallel_map(changes.len(), threads, progress, &|i| {
        let d = changed(prior, &changes[i])?;
        let s = static_tip(&d, &foot)?;
        let r = run_study(&d, study)?;
        Ok(SimCheck {
            change: changes[i].clone(),
            static_deg: s.angles.to_degrees(),
            simulated_deg: [
                r.forward.measured_deg,
                r.backward.measured_deg,
                r.left.measured_deg,
                r.right.measured_deg,
            ],
        })
    })
}
