//! IK marker fitting (seed 004, section 3.2, eq 7): the configuration of each
//! motion-capture frame, floating base included, that brings the model's virtual
//! markers closest to the measured ones,
//!
//! ```text
//! min_q  sum_m | r_m^V(q) - r_m^C |^2
//! ```
//!
//! by Levenberg-Marquardt ([`twinloop_gait::ik`]) with frame Jacobians, the base moving on
//! SE(3) and joints kept in their limits. As the seed does, the first frame starts
//! from the pelvis pose estimated from the pelvis markers alone (a rigid fit by SVD,
//! Kabsch's method), so the solver does not wander into joint angles beyond a full
//! turn; every later frame starts from the previous solution.
//!
//! Marker sets are TOML:
//!
//! ```toml
//! [[marker]]
//! name = "pelvis_front_left"
//! link = "pelvis"
//! position = [0.10, 0.08, 0.00]   # in the link frame, m
//! ```
//!
//! and marker frames are CSV with `t` and `marker:<name>.x .y .z` (world, m); a NaN
//! cell means the marker was not seen in that frame.

use crate::anatomy::link_placement;
use crate::error::IdentError;
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use std::path::Path;
use twinloop_dynamics::{BASE, Data, Model};
use twinloop_gait::ik::{Ik, IkOptions, Task};
use twinloop_io::Table;

/// A virtual marker: a point fixed in a link.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    pub name: String,
    /// Description link index.
    pub link: usize,
    /// Position in the link frame, m.
    pub position: Vector3<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MarkerFile {
    marker: Vec<MarkerEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MarkerEntry {
    name: String,
    link: String,
    position: Vec<f64>,
}

/// The furthest, m, a marker may sit from its link's frame: 3 m, past the longest
/// limb of the tallest robot here; a set written in millimetres is 1000x that.
pub const MAX_MARKER_OFFSET_M: f64 = 3.0;

/// Parse a marker set for `model` from TOML text. Errors name the marker and field.
pub fn parse_markers(text: &str, model: &Model) -> Result<Vec<Marker>, IdentError> {
    let file: MarkerFile = toml::from_str(text).map_err(|e| {
        let mut msg = e.message().to_string();
        if let Some(span) = e.span() {
            let line = text[..span.start.min(text.len())].lines().count().max(1);
            msg = format!("line {line}: {msg}");
        }
        IdentError::new(msg)
    })?;
    let mut out: Vec<Marker> = Vec::new();
    for (i, m) in file.marker.into_iter().enumerate() {
        let at = |f: &str| format!("marker[{i}] \"{}\".{f}", m.name);
        if m.name.is_empty() || m.name.contains(',') {
            return Err(
                IdentError::new("a marker name must be non-empty and without commas")
                    .field(at("name")),
            );
        }
        if out.iter().any(|o| o.name == m.name) {
            return Err(IdentError::new("two markers have this name").field(at("name")));
        }
        let link = model
            .links
            .iter()
            .position(|l| l.name == m.link)
            .ok_or_else(|| {
                IdentError::new(format!(
                    "no link \"{}\" in the model \"{}\"",
                    m.link, model.name
                ))
                .field(at("link"))
            })?;
        if m.position.len() != 3 || !m.position.iter().all(|x| x.is_finite()) {
            return Err(IdentError::new(format!(
                "{:?} is not a position: three finite numbers (x, y, z in the link frame, m)",
                m.position
            ))
            .field(at("position")));
        }
        let far = m.position.iter().map(|x| x * x).sum::<f64>().sqrt();
        if far > MAX_MARKER_OFFSET_M {
            let written: Vec<String> = m
                .position
                .iter()
                .map(|&x| twinloop_report::number(x))
                .collect();
            return Err(IdentError::new(format!(
                "[{}] is {} m from its link's frame, further than any marker sits on a \
                 robot ({MAX_MARKER_OFFSET_M} m); positions are metres: are they in \
                 millimetres? (that would be {} m)",
                written.join(", "),
                twinloop_report::number(far),
                twinloop_report::number(far / 1000.0)
            ))
            .field(at("position")));
        }
        out.push(Marker {
            name: m.name,
            link,
            position: Vector3::new(m.position[0], m.position[1], m.position[2]),
        });
    }
    if out.len() < 3 {
        return Err(IdentError::new(format!(
            "{} markers: at least 3 are needed",
            out.len()
        )));
    }
    Ok(out)
}

/// Read a marker set file.
pub fn read_markers(path: &Path, model: &Model) -> Result<Vec<Marker>, IdentError> {
    let text = twinloop_io::input::read_to_string(path)
        .map_err(|e| IdentError::new(format!("cannot read: {e}")).in_file(path))?;
    parse_markers(&text, model).map_err(|e| e.in_file(path))
}

/// Write a marker set as TOML.
pub fn markers_to_toml(model: &Model, markers: &[Marker]) -> String {
    let mut s = String::from(
        "# Virtual markers: a point fixed in a link, position in the link frame (m).\n",
    );
    for m in markers {
        s.push_str(&format!(
            "\n[[marker]]\nname = \"{}\"\nlink = \"{}\"\nposition = [{:?}, {:?}, {:?}]\n",
            m.name, model.links[m.link].name, m.position.x, m.position.y, m.position.z
        ));
    }
    s
}

/// World positions of the markers at the last forward kinematics in `data`.
pub fn marker_positions(model: &Model, data: &Data, markers: &[Marker]) -> Vec<Vector3<f64>> {
    markers
        .iter()
        .map(|m| link_placement(model, data, m.link).act_point(&m.position))
        .collect()
}

/// Marker frames: time and per marker a world position, `None` where not seen.
#[derive(Debug, Clone, Default)]
pub struct MarkerFrames {
    pub t: Vec<f64>,
    pub positions: Vec<Vec<Option<Vector3<f64>>>>,
}

/// Column names of marker frames.
pub fn frame_columns(markers: &[Marker]) -> Vec<String> {
    let mut cols = vec!["t".to_string()];
    for m in markers {
        for a in ["x", "y", "z"] {
            cols.push(format!("marker:{}.{a}", m.name));
        }
    }
    cols
}

/// Read marker frames; every marker of the set needs its three columns.
pub fn read_frames(path: &Path, markers: &[Marker]) -> Result<MarkerFrames, IdentError> {
    let table = Table::read(path)?;
    frames_from_table(&table, markers).map_err(|e| e.in_file(path))
}

/// [`read_frames`] of a table read already (a log through twinloop-logs: the
/// `marker:` columns of a Float64MultiArray); errors name the table's file.
pub fn frames_from_table(table: &Table, markers: &[Marker]) -> Result<MarkerFrames, IdentError> {
    let at = |e: IdentError| match &table.path {
        Some(p) => e.in_file(p),
        None => e,
    };
    let tc = table
        .column_index("t")
        .ok_or_else(|| at(IdentError::new("a time column is needed (seconds)").field("t")))?;
    let mut idx = Vec::with_capacity(markers.len());
    for m in markers {
        let mut c = [0usize; 3];
        for (k, a) in ["x", "y", "z"].iter().enumerate() {
            let name = format!("marker:{}.{a}", m.name);
            c[k] = table.column_index(&name).ok_or_else(|| {
                at(
                    IdentError::new("the marker set has this marker but the frames do not")
                        .field(name),
                )
            })?;
        }
        idx.push(c);
    }
    let mut f = MarkerFrames::default();
    for (r, row) in table.rows.iter().enumerate() {
        let t = row[tc];
        if !t.is_finite() || f.t.last().is_some_and(|&p| t <= p) {
            return Err(at(IdentError::new(format!(
                "time {t} is not finite and increasing"
            ))
            .at_row(r)
            .field("t")));
        }
        f.t.push(t);
        f.positions.push(
            idx.iter()
                .map(|c| {
                    let p = Vector3::new(row[c[0]], row[c[1]], row[c[2]]);
                    p.iter().all(|x| x.is_finite()).then_some(p)
                })
                .collect(),
        );
    }
    if f.t.is_empty() {
        return Err(at(IdentError::new("no frames")));
    }
    check_frame_units(&f, markers).map_err(at)?;
    Ok(f)
}

/// Frames in the marker set's unit, metres: two markers on one link are as far apart
/// in every frame as the set places them (a rigid link). Frames in millimetres make
/// those distances 1000 times the set's, and the fit would put the base hundreds of
/// metres up (issue 29, class 3); the median ratio over every such pair (1 cm apart
/// or more in the set) and every frame that sees both must be within 2x of 1.
pub fn check_frame_units(frames: &MarkerFrames, markers: &[Marker]) -> Result<(), IdentError> {
    let mut ratios = Vec::new();
    let mut named = None;
    for (i, a) in markers.iter().enumerate() {
        for (j, b) in markers.iter().enumerate().skip(i + 1) {
            let set = (a.position - b.position).norm();
            if a.link != b.link || set < 0.01 {
                continue;
            }
            named.get_or_insert(j);
            for p in &frames.positions {
                if let (Some(pa), Some(pb)) = (p[i], p[j]) {
                    ratios.push((pa - pb).norm() / set);
                }
            }
        }
    }
    if ratios.is_empty() {
        return Ok(());
    }
    ratios.sort_by(f64::total_cmp);
    let r = ratios[ratios.len() / 2];
    if (0.5..=2.0).contains(&r) {
        return Ok(());
    }
    let unit = [
        (1000.0, "millimetres"),
        (100.0, "centimetres"),
        (39.37, "inches"),
    ]
    .iter()
    .find(|(k, _)| (r / k - 1.0).abs() < 0.25)
    .map(|(_, u)| format!(": the frames look like {u}, the set is in metres"));
    // Frames smaller than the set: the set is the one in another unit.
    let set_unit = [(1000.0, "millimetres"), (100.0, "centimetres")]
        .iter()
        .find(|(k, _)| (r * k - 1.0).abs() < 0.25)
        .map(|(_, u)| format!(": the marker set looks like {u}, the frames metres"));
    let unit = unit.or(set_unit).unwrap_or_default();
    let name = &markers[named.unwrap_or(0)].name;
    Err(IdentError::new(format!(
        "markers on one link are {r:.4} times as far apart as the marker set places them \
         (the median of {} distances){unit}; give both in metres",
        ratios.len()
    ))
    .field(format!("marker:{name}.x")))
}

/// Rigid transform (rotation, translation) that best maps points `a` onto `b` in the
/// least-squares sense (Kabsch: SVD of the cross-covariance, reflection removed).
pub fn kabsch(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    if a.len() < 3 || a.len() != b.len() {
        return None;
    }
    let n = a.len() as f64;
    let ca = a.iter().sum::<Vector3<f64>>() / n;
    let cb = b.iter().sum::<Vector3<f64>>() / n;
    let mut h = Matrix3::zeros();
    for (p, q) in a.iter().zip(b) {
        h += (p - ca) * (q - cb).transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    // Non-collinear points give a cross-covariance of rank 2 at least.
    let mut sv = svd.singular_values;
    sv.as_mut_slice().sort_by(|x, y| y.total_cmp(x));
    if sv[1] <= 1e-12 * sv[0].max(1e-300) {
        return None;
    }
    let v = vt.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    Some((r, cb - r * ca))
}

/// The marker distance, m, past which a frame's fit is poor: 20 mm RMS. Optical
/// motion capture places a marker within a millimetre or two and a marker set on a
/// rigid robot link is known to a few; a fit 20 mm off means the marker set does not
/// match the robot or the frames (swapped or mislabelled markers, another robot), and
/// the joint angles it gives are not the robot's.
pub const POOR_FIT_RMS_M: f64 = 0.02;

/// The fit of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameFit {
    /// Root-mean-square marker distance after the fit, m.
    pub rms: f64,
    pub max: f64,
    pub iterations: usize,
}

/// Fits marker frames to a model, frame by frame.
pub struct MarkerIk<'a> {
    model: &'a Model,
    markers: Vec<Marker>,
    ik: Ik,
    data: Data,
    options: IkOptions,
    /// The last solution (the next frame's start once `started`).
    q: Vec<f64>,
    started: bool,
    /// A frame whose worst marker stays farther than this (m) after the warm-started
    /// fit is fitted again from its own pelvis pose (frames far apart, e.g. separate
    /// static poses, can leave the previous solution in the wrong basin).
    pub restart_distance: f64,
}

impl<'a> MarkerIk<'a> {
    pub fn new(model: &'a Model, markers: Vec<Marker>) -> Result<Self, IdentError> {
        if !model.is_floating() {
            return Err(IdentError::new(
                "marker fitting needs a floating-base model",
            ));
        }
        let frame_of = |l: usize| crate::anatomy::link_frame(model, l);
        let tasks = markers
            .iter()
            .map(|m| Task::Point {
                frame: frame_of(m.link),
                point: m.position,
                target: Vector3::zeros(),
                weight: Vector3::repeat(1.0),
            })
            .collect();
        Ok(MarkerIk {
            model,
            ik: Ik::new(model, tasks),
            markers,
            data: Data::new(model),
            options: IkOptions {
                max_iterations: 100,
                cost_tolerance: 1e-20,
                ..IkOptions::default()
            },
            q: model.neutral_configuration(),
            started: false,
            restart_distance: 0.02,
        })
    }

    /// The pelvis (base body) pose from its visible markers (Kabsch), joints neutral.
    fn initial_guess(&self, seen: &[Option<Vector3<f64>>]) -> Result<Vec<f64>, IdentError> {
        let model = self.model;
        let mut local = Vec::new();
        let mut world = Vec::new();
        for (m, p) in self.markers.iter().zip(seen) {
            let info = &model.links[m.link];
            if let (BASE, Some(p)) = (info.body, p) {
                local.push(info.placement.act_point(&m.position));
                world.push(*p);
            }
        }
        let (r, p) = kabsch(&local, &world).ok_or_else(|| {
            IdentError::new(format!(
                "the first frame shows {} markers on the base body ({}): 3 non-collinear ones are \
                 needed to estimate its pose (seed 004, section 3.2)",
                local.len(),
                model.base_link
            ))
            .at_row(0)
        })?;
        let mut q = model.neutral_configuration();
        q[0..3].copy_from_slice(p.as_slice());
        let quat = twinloop_spatial::matrix_to_quaternion_xyzw(&r);
        q[3..7].copy_from_slice(&quat);
        twinloop_gait::ik::clamp_to_limits(model, &mut q);
        Ok(q)
    }

    /// Turn each joint, parents first, to best align the visible markers of its subtree
    /// with their targets (a closed-form rotation about the joint axis), from `self.q`.
    fn align_chain(&mut self, seen: &[Option<Vector3<f64>>]) {
        let model = self.model;
        for b in 0..model.nbodies {
            twinloop_dynamics::forward_kinematics(model, &mut self.data, &self.q);
            let x = self.data.o_m_i[b];
            let u = x.rotation * model.axes[b];
            let o = x.translation;
            let (mut s, mut c, mut shift, mut count) = (0.0, 0.0, 0.0, 0usize);
            for (m, target) in self.markers.iter().zip(seen) {
                let Some(t) = target else { continue };
                let mb = model.links[m.link].body;
                if mb == BASE || !model.ancestors(mb).any(|a| a == b) {
                    continue;
                }
                let p = link_placement(model, &self.data, m.link).act_point(&m.position);
                let (pr, tr) = (p - o, t - o);
                let pp = pr - u * u.dot(&pr);
                let tp = tr - u * u.dot(&tr);
                s += u.dot(&pp.cross(&tp));
                c += pp.dot(&tp);
                shift += u.dot(&(t - p));
                count += 1;
            }
            if count == 0 {
                continue;
            }
            let i = model.q_offset + b;
            if model.joint_types[b].is_revolute() {
                if s.abs() + c.abs() > 1e-12 {
                    self.q[i] += s.atan2(c);
                }
            } else {
                self.q[i] += shift / count as f64;
            }
            let (lo, hi) = (model.lower_limits[b], model.upper_limits[b]);
            if lo <= hi {
                self.q[i] = self.q[i].clamp(lo, hi);
            }
        }
    }

    /// Largest marker distance of the last evaluation.
    fn worst(&self, seen: &[Option<Vector3<f64>>]) -> f64 {
        let r = self.ik.residual();
        let mut max: f64 = 0.0;
        for (k, p) in seen.iter().enumerate() {
            if p.is_some() {
                max = max.max(Vector3::new(r[3 * k], r[3 * k + 1], r[3 * k + 2]).norm());
            }
        }
        max
    }

    /// Fit one frame (seed 004, eq 7); `row` names the frame in errors. Returns the
    /// configuration (valid until the next call). After the first frame nothing is
    /// allocated.
    pub fn fit(
        &mut self,
        seen: &[Option<Vector3<f64>>],
        row: usize,
    ) -> Result<(&[f64], FrameFit), IdentError> {
        let visible = seen.iter().filter(|p| p.is_some()).count();
        if visible < 3 {
            return Err(
                IdentError::new(format!("{visible} markers seen: at least 3 are needed"))
                    .at_row(row),
            );
        }
        if seen.len() != self.markers.len() {
            return Err(IdentError::new(format!(
                "{} marker positions for {} markers",
                seen.len(),
                self.markers.len()
            ))
            .at_row(row));
        }
        if !self.started {
            self.q = self.initial_guess(seen)?;
            self.started = true;
        }
        for (t, p) in self.ik.tasks.iter_mut().zip(seen) {
            if let Task::Point { target, weight, .. } = t {
                match p {
                    Some(p) => {
                        *target = *p;
                        *weight = Vector3::repeat(1.0);
                    }
                    None => *weight = Vector3::zeros(),
                }
            }
        }
        let mut rep = self
            .ik
            .solve(self.model, &mut self.data, &mut self.q, &self.options);
        if self.worst(seen) > self.restart_distance
            && let Ok(q0) = self.initial_guess(seen)
        {
            // Other starts: joint by joint from the pelvis outwards, each turned to best
            // align the markers below it; then the pelvis pose with the joints at zero.
            let mut best = std::mem::take(&mut self.q);
            let mut best_cost = rep.cost;
            for chain in [true, false] {
                self.q = q0.clone();
                if chain {
                    self.align_chain(seen);
                }
                let again = self
                    .ik
                    .solve(self.model, &mut self.data, &mut self.q, &self.options);
                if again.cost < best_cost {
                    best_cost = again.cost;
                    std::mem::swap(&mut best, &mut self.q);
                }
                if self.worst(seen) <= self.restart_distance {
                    break;
                }
            }
            self.q = best;
            rep = self
                .ik
                .solve(self.model, &mut self.data, &mut self.q, &self.options);
        }
        let r = self.ik.residual();
        let mut max: f64 = 0.0;
        let mut sum = 0.0;
        for (k, p) in seen.iter().enumerate() {
            if p.is_some() {
                let d = Vector3::new(r[3 * k], r[3 * k + 1], r[3 * k + 2]).norm();
                max = max.max(d);
                sum += d * d;
            }
        }
        Ok((
            &self.q,
            FrameFit {
                rms: (sum / visible as f64).sqrt(),
                max,
                iterations: rep.iterations,
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three markers 5 cm apart on one link (and one on another, not compared).
    fn set() -> Vec<Marker> {
        let m = |name: &str, link, p: [f64; 3]| Marker {
            name: name.into(),
            link,
            position: Vector3::from(p),
        };
        vec![
            m("a", 1, [0.05, 0.0, 0.0]),
            m("b", 1, [0.0, 0.05, 0.0]),
            m("c", 1, [0.0, 0.0, 0.05]),
            m("d", 2, [0.0, 0.0, 0.0]),
        ]
    }

    fn frames(scale: f64) -> MarkerFrames {
        // The set turned a quarter turn about z and moved: distances kept.
        let p = |x: f64, y: f64, z: f64| Some(Vector3::new(0.3 - y, 0.1 + x, 0.5 + z) * scale);
        MarkerFrames {
            t: vec![0.0],
            positions: vec![vec![
                p(0.05, 0.0, 0.0),
                p(0.0, 0.05, 0.0),
                p(0.0, 0.0, 0.05),
                None,
            ]],
        }
    }

    /// Issue 29, class 3: frames in millimetres (the base would be fitted hundreds of
    /// metres up) are refused naming the unit; in metres, or with a marker unseen, taken.
    #[test]
    fn frames_in_another_unit_than_the_set_are_refused() {
        assert!(check_frame_units(&frames(1.0), &set()).is_ok());
        let e = check_frame_units(&frames(1000.0), &set())
            .unwrap_err()
            .to_string();
        assert!(e.contains("millimetres") && e.contains("marker:b.x"), "{e}");
        let e = check_frame_units(&frames(100.0), &set())
            .unwrap_err()
            .to_string();
        assert!(e.contains("centimetres"), "{e}");
        let mut one_seen = frames(1000.0);
        one_seen.positions[0][1] = None;
        one_seen.positions[0][2] = None;
        assert!(
            check_frame_units(&one_seen, &set()).is_ok(),
            "nothing to compare"
        );
    }
}
