//! The dynamics `Model`: constant, compiled once from a robot description.
//!
//! Bodies are the rigid groups between movable joints: links joined by fixed
//! joints are merged into one body (their inertias summed in the body frame), as
//! Pinocchio does, while every link keeps a frame so results can be reported and
//! written back per link. Bodies are numbered depth-first, so a parent always
//! precedes its children; the children of a link come in file order
//! ([`JointOrder::File`], what the CLI uses) or, as Pinocchio's URDF parser numbers
//! them, by joint name ([`JointOrder::UrdfByName`], what the Python package uses).

use nalgebra::{Matrix3, Vector3};
use twinloop_description::{Description, DescriptionError, JointKind};
use twinloop_spatial::{Inertia, Se3};

/// The largest dynamics workspace (`Data`) a model may need, in bytes.
pub const MAX_DATA_BYTES: usize = 4_000_000_000;

/// Marks a body attached directly to the base (or to the world for a fixed base).
pub const BASE: usize = usize::MAX;

/// Joint types. Axis-aligned revolute joints get their own variants so the hot loops
/// can skip the general Rodrigues rotation (most humanoid joints are).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointType {
    RevoluteX,
    RevoluteY,
    RevoluteZ,
    /// Revolute about a general unit axis (`Model::axes`).
    Revolute,
    /// Prismatic along a unit axis (`Model::axes`).
    Prismatic,
    /// A ball joint (Pinocchio's JointModelSpherical): 4 configuration entries, a unit
    /// quaternion (x, y, z, w) of the child frame in the joint frame; 3 velocity
    /// entries, the angular velocity in the child frame. Its `Model::axes` entry is zero.
    Spherical,
}

impl JointType {
    /// A 1-DoF rotation (not a prismatic or a spherical joint).
    pub fn is_revolute(self) -> bool {
        !matches!(self, JointType::Prismatic | JointType::Spherical)
    }

    /// Number of configuration entries (1, or 4 for a spherical joint).
    pub fn nq(self) -> usize {
        if self == JointType::Spherical { 4 } else { 1 }
    }

    /// Number of velocity entries (1, or 3 for a spherical joint).
    pub fn nv(self) -> usize {
        if self == JointType::Spherical { 3 } else { 1 }
    }
}

/// Where a named frame sits: on a body (or the base) at a fixed placement.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameInfo {
    pub name: String,
    /// Body index, or [`BASE`].
    pub body: usize,
    /// Placement of the frame in the body frame.
    pub placement: Se3,
    /// Index of the description link this frame is, if it is a link frame.
    pub link: Option<usize>,
}

/// Per description link: where its frame and its own inertia are, so per-link
/// parameters can be mapped to body parameters and back.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkInfo {
    pub name: String,
    /// Body index, or [`BASE`] (for a fixed base: the world; its mass is then inert).
    pub body: usize,
    /// Placement of the link frame in the body frame.
    pub placement: Se3,
    /// The link's own inertia in the link frame (zero without `<inertial>`).
    pub inertia: Inertia,
}

/// In which order the depth-first walk visits the joints below a link, which fixes
/// the order of the joints in q, v and tau.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum JointOrder {
    /// File order (the description's joint order): what the CLI, its CSV columns
    /// and Pinocchio's MJCF parser (which walks the body tree as written) use.
    #[default]
    File,
    /// Byte order of the joint names, as Pinocchio's URDF parser numbers the joints
    /// (urdfdom keeps a link's child joints in a `std::map` keyed by name;
    /// tools/oracle/README.md, "Joint order"; checked on every URDF of
    /// example-robot-data by python/tests/test_joint_order.py).
    UrdfByName,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BaseKind {
    /// A 6-DoF free-flyer root (Pinocchio's JointModelFreeFlyer): q has 7 base
    /// entries (x, y, z, qx, qy, qz, qw), v has 6 (linear, angular, base frame).
    Floating,
    /// The root link is welded to the world.
    Fixed,
}

/// The constant part of the dynamics.
#[derive(Debug, Clone)]
pub struct Model {
    pub name: String,
    pub base: BaseKind,
    /// Name of the base link (the root link, or the child of a URDF floating root joint).
    pub base_link: String,
    pub nq: usize,
    pub nv: usize,
    /// Number of jointed bodies (the floating base is not counted). Equal to the
    /// number of joint velocity coordinates `nv - v_offset` unless the model has
    /// spherical joints ([`Model::has_spherical_joints`]).
    pub nbodies: usize,
    /// Offsets of the first joint coordinate in q and in v (7 and 6 for a floating base).
    pub q_offset: usize,
    pub v_offset: usize,
    pub parents: Vec<usize>,
    pub joint_types: Vec<JointType>,
    /// Index of each body's first configuration and velocity entry in q and v
    /// (Pinocchio's `idx_q`, `idx_v`): `q_offset + i` and `v_offset + i` when every
    /// joint has one DoF.
    pub idx_q: Vec<usize>,
    pub idx_v: Vec<usize>,
    /// Unit axis of each joint in its own frame.
    pub axes: Vec<Vector3<f64>>,
    /// Placement of each joint frame in its parent body frame (fixed chains folded in).
    pub joint_placements: Vec<Se3>,
    /// Inertia of each body in its frame (links fixed to it included).
    pub inertias: Vec<Inertia>,
    /// Inertia of the floating base body (zero and unused for a fixed base).
    pub base_inertia: Inertia,
    pub joint_names: Vec<String>,
    /// Name of the link each body starts with (the joint's child link).
    pub body_names: Vec<String>,
    /// Index one past the last body of each body's subtree (depth-first numbering).
    pub subtree_end: Vec<usize>,
    pub lower_limits: Vec<f64>,
    pub upper_limits: Vec<f64>,
    pub effort_limits: Vec<f64>,
    pub velocity_limits: Vec<f64>,
    /// Rotor inertia reflected to each joint (added to the mass-matrix diagonal): the
    /// description's (MJCF `armature`), zero for URDF.
    pub armature: Vec<f64>,
    /// The floating base's armature (the description's, MJCF free joint `armature`;
    /// 0 for a fixed base). MuJoCo adds it to the free joint's six diagonal entries
    /// of M in its coordinates (linear velocity in the world frame, angular in the
    /// body frame). Its kinetic energy `a (|v|^2 + |w|^2) / 2` is the same in the
    /// base-frame coordinates here, so it is `a` on the base's six diagonal entries
    /// of M and, as the base frame turns, `a (w x v)` on the base force in the bias
    /// forces; gravity does not act on it.
    pub base_armature: f64,
    /// The description's gravity (MJCF `<option gravity>`), else (0, 0, -9.81).
    pub gravity: Vector3<f64>,
    pub frames: Vec<FrameInfo>,
    pub links: Vec<LinkInfo>,
    /// Sum of body masses (the base included for a floating base).
    pub total_mass: f64,
    /// Per body: the joint turns about an axis of its own frame (`RevoluteX/Y/Z`) and
    /// its placement has no rotation, so `liMi` keeps that axis and composing with it
    /// turns two columns (`joint::compose`). Set with `joint_placements`.
    pub(crate) keeps_axis: Vec<bool>,
}

/// A description pose (xyz, rpy) as a rigid placement.
pub fn pose_to_se3(p: &twinloop_description::Pose) -> Se3 {
    let r = p.rotation();
    Se3::new(
        Matrix3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        ),
        Vector3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
    )
}

fn link_inertia(link: &twinloop_description::Link) -> Inertia {
    match &link.inertial {
        None => Inertia::ZERO,
        Some(i) => {
            let local = Inertia::new(
                i.mass,
                Vector3::zeros(),
                Matrix3::from_fn(|r, c| i.inertia.matrix()[r][c]),
            );
            local.transformed(&pose_to_se3(&i.origin))
        }
    }
}

/// A link still to visit in the depth-first walk: (link, the body it belongs to,
/// placement of the link in that body, the moving joint that leads to it if its body
/// is still to be made).
type Pending = (usize, usize, Se3, Option<usize>);

/// The joints below each link, each with its child link, in `order`: from one index
/// of the links by name (a search per joint is quadratic in the robot's size).
fn child_joints(robot: &Description, order: JointOrder) -> Vec<Vec<(usize, usize)>> {
    let index = robot.links_by_name();
    let ix = |name: &str| *index.get(name).expect("validated");
    let mut children: Vec<Vec<(usize, usize)>> = vec![Vec::new(); robot.links.len()];
    for (j, joint) in robot.joints.iter().enumerate() {
        children[ix(&joint.parent)].push((j, ix(&joint.child)));
    }
    if order == JointOrder::UrdfByName {
        for c in &mut children {
            c.sort_by(|&(a, _), &(b, _)| {
                robot.joints[a]
                    .name
                    .as_bytes()
                    .cmp(robot.joints[b].name.as_bytes())
            });
        }
    }
    children
}

/// The base link and, for a URDF "world -> floating -> base", the world link that the
/// floating joint hangs from: that joint is then the free flyer and the world link is
/// dropped.
fn find_base_link(
    robot: &Description,
    children: &[Vec<(usize, usize)>],
) -> Result<(usize, Option<usize>), DescriptionError> {
    let root = robot
        .root_link()
        .ok_or_else(|| DescriptionError::new("no single root link"))?;
    let root = robot.link_index(root).expect("validated");
    let root_children = &children[root];
    if let [(j, child)] = root_children[..]
        && robot.joints[j].kind == JointKind::Floating
    {
        let fj = &robot.joints[j];
        if !fj.origin.is_identity() {
            // q would then not be the base link's pose; refuse rather than mislead.
            return Err(DescriptionError::new(
                "the floating root joint has a non-identity <origin>: twinloop's base pose q is the base \
                 link's world pose, so move the offset into the robot (or remove it)",
            )
            .at_element(format!("<joint name=\"{}\">", fj.name)));
        }
        return Ok((child, Some(root)));
    }
    Ok((root, None))
}

/// The joint type of a moving joint with unit axis `axis`: axis-aligned revolute
/// joints get their own variants for the hot loops.
fn joint_type(kind: JointKind, axis: &Vector3<f64>) -> JointType {
    if kind == JointKind::Spherical {
        JointType::Spherical
    } else if kind == JointKind::Prismatic {
        JointType::Prismatic
    } else if *axis == Vector3::x() {
        JointType::RevoluteX
    } else if *axis == Vector3::y() {
        JointType::RevoluteY
    } else if *axis == Vector3::z() {
        JointType::RevoluteZ
    } else {
        JointType::Revolute
    }
}

/// Queue the links below `link` (placed at `placement` in `body`): a fixed joint keeps
/// its child in the same body, a moving joint starts a new one. Pushed in reverse so
/// children are visited in the order given.
fn push_child_links(
    robot: &Description,
    children: &[(usize, usize)],
    body: usize,
    placement: Se3,
    stack: &mut Vec<Pending>,
) -> Result<(), DescriptionError> {
    for &(j, child) in children.iter().rev() {
        let joint = &robot.joints[j];
        let origin = placement * pose_to_se3(&joint.origin);
        let here = || format!("<joint name=\"{}\">", joint.name);
        match joint.kind {
            JointKind::Fixed => stack.push((child, body, origin, None)),
            JointKind::Revolute
            | JointKind::Continuous
            | JointKind::Prismatic
            | JointKind::Spherical => {
                stack.push((child, body, origin, Some(j)));
            }
            JointKind::Floating => {
                return Err(DescriptionError::new(
                    "a floating joint is only supported as the root joint (world -> base)",
                )
                .at_element(here()));
            }
            JointKind::Planar => {
                return Err(DescriptionError::new(
                    "planar joints are not supported by the dynamics",
                )
                .at_element(here()));
            }
        }
    }
    Ok(())
}

impl Model {
    /// Compile with a floating base (the usual case for a humanoid).
    pub fn from_description(robot: &Description) -> Result<Model, DescriptionError> {
        Model::from_description_with_base(robot, BaseKind::Floating)
    }

    /// Compile a description. A URDF whose root link has a `floating` joint (COMAN's
    /// `world` link) uses that joint as the free flyer and drops the root link.
    pub fn from_description_with_base(
        robot: &Description,
        base: BaseKind,
    ) -> Result<Model, DescriptionError> {
        Model::from_description_ordered(robot, base, JointOrder::File)
    }

    /// As [`Model::from_description_with_base`], the joints numbered in `order`.
    pub fn from_description_ordered(
        robot: &Description,
        base: BaseKind,
        order: JointOrder,
    ) -> Result<Model, DescriptionError> {
        robot.validate()?;
        let children = child_joints(robot, order);
        let (base_link, dropped_root) = find_base_link(robot, &children)?;
        let mut m = Model::without_bodies(robot, base, base_link);
        let mut link_info: Vec<Option<LinkInfo>> = vec![None; robot.links.len()];
        if let Some(r) = dropped_root {
            // The world link of a "world -> floating" URDF is not part of the robot.
            link_info[r] = Some(LinkInfo {
                name: robot.links[r].name.clone(),
                body: BASE,
                placement: Se3::IDENTITY,
                inertia: Inertia::ZERO,
            });
        }
        m.add_bodies(robot, &children, base_link, &mut link_info)?;
        m.number_subtrees();
        m.check_workspace_size(robot.links.len())?;
        m.add_frames(robot, link_info)?;
        if base != BaseKind::Floating {
            m.base_inertia = Inertia::ZERO;
        }
        m.total_mass = m.base_inertia.mass + m.inertias.iter().map(|i| i.mass).sum::<f64>();
        Ok(m)
    }

    /// The model of the base alone: offsets set, every per-body list empty.
    fn without_bodies(robot: &Description, base: BaseKind, base_link: usize) -> Model {
        let (q_offset, v_offset) = if base == BaseKind::Floating {
            (7, 6)
        } else {
            (0, 0)
        };
        Model {
            name: robot.name.clone(),
            base,
            base_link: robot.links[base_link].name.clone(),
            nq: q_offset,
            nv: v_offset,
            nbodies: 0,
            q_offset,
            v_offset,
            parents: Vec::new(),
            joint_types: Vec::new(),
            idx_q: Vec::new(),
            idx_v: Vec::new(),
            axes: Vec::new(),
            joint_placements: Vec::new(),
            inertias: Vec::new(),
            base_inertia: Inertia::ZERO,
            joint_names: Vec::new(),
            body_names: Vec::new(),
            subtree_end: Vec::new(),
            lower_limits: Vec::new(),
            upper_limits: Vec::new(),
            effort_limits: Vec::new(),
            velocity_limits: Vec::new(),
            armature: Vec::new(),
            base_armature: if base == BaseKind::Floating {
                robot.base_armature
            } else {
                0.0
            },
            gravity: robot.gravity.map_or(
                Vector3::new(0.0, 0.0, -twinloop_description::GRAVITY),
                Vector3::from,
            ),
            frames: Vec::new(),
            links: Vec::new(),
            total_mass: 0.0,
            keeps_axis: Vec::new(),
        }
    }

    /// Walk the tree from the base link depth-first, making a body at every moving
    /// joint and adding each link's inertia to its body; `link_info` gets where each
    /// link is. A body is numbered when its link is reached, not when its parent is, so
    /// that bodies come in depth-first pre-order with children in the chosen order, and every
    /// subtree is a contiguous range.
    fn add_bodies(
        &mut self,
        robot: &Description,
        children: &[Vec<(usize, usize)>],
        base_link: usize,
        link_info: &mut [Option<LinkInfo>],
    ) -> Result<(), DescriptionError> {
        let mut stack: Vec<Pending> = vec![(base_link, BASE, Se3::IDENTITY, None)];
        while let Some((link, parent_body, placement, via)) = stack.pop() {
            let (body, placement) = match via {
                None => (parent_body, placement),
                Some(j) => (
                    self.add_joint_body(&robot.joints[j], parent_body, placement)?,
                    Se3::IDENTITY,
                ),
            };
            let own = link_inertia(&robot.links[link]);
            link_info[link] = Some(LinkInfo {
                name: robot.links[link].name.clone(),
                body,
                placement,
                inertia: own,
            });
            let in_body = own.transformed(&placement);
            if body == BASE {
                self.base_inertia += in_body;
            } else {
                self.inertias[body] += in_body;
            }
            push_child_links(robot, &children[link], body, placement, &mut stack)?;
        }
        Ok(())
    }

    /// A new body moved by `joint`, whose frame sits at `placement` in `parent_body`;
    /// returns its index. Its inertia starts at zero.
    fn add_joint_body(
        &mut self,
        joint: &twinloop_description::Joint,
        parent_body: usize,
        placement: Se3,
    ) -> Result<usize, DescriptionError> {
        let spherical = joint.kind == JointKind::Spherical;
        let a = joint.axis_or_default();
        let axis = Vector3::new(a[0], a[1], a[2]);
        let n = axis.norm();
        let direction = n > 1e-12 && n.is_finite();
        if !spherical && !direction {
            return Err(
                DescriptionError::new("a moving joint needs a non-zero, finite axis")
                    .at_element(format!("<joint name=\"{}\">", joint.name)),
            );
        }
        // A ball joint has no axis: it turns about its origin in every direction.
        let axis = if spherical {
            Vector3::zeros()
        } else {
            axis / n
        };
        let lim = joint.limit.unwrap_or_default();
        let new_body = self.parents.len();
        self.parents.push(parent_body);
        let jt = joint_type(joint.kind, &axis);
        self.joint_types.push(jt);
        self.axes.push(axis);
        // `placement` is the joint frame in the parent body.
        self.keeps_axis.push(
            matches!(
                jt,
                JointType::RevoluteX | JointType::RevoluteY | JointType::RevoluteZ
            ) && placement.rotation == Matrix3::identity(),
        );
        self.joint_placements.push(placement);
        self.inertias.push(Inertia::ZERO);
        self.joint_names.push(joint.name.clone());
        self.body_names.push(joint.child.clone());
        let continuous = joint.kind == JointKind::Continuous || spherical;
        self.lower_limits.push(if continuous {
            f64::NEG_INFINITY
        } else {
            lim.lower.unwrap_or(f64::NEG_INFINITY)
        });
        self.upper_limits.push(if continuous {
            f64::INFINITY
        } else {
            lim.upper.unwrap_or(f64::INFINITY)
        });
        self.effort_limits.push(lim.effort.unwrap_or(f64::INFINITY));
        self.velocity_limits
            .push(lim.velocity.unwrap_or(f64::INFINITY));
        self.armature.push(joint.armature);
        Ok(new_body)
    }

    /// Refuse a model whose `Data` would not fit in memory, before anything
    /// allocates it: the regressor alone is nv x 10 (bodies + base) numbers, so a
    /// 20 000-joint chain would need 32 GB.
    fn check_workspace_size(&self, links: usize) -> Result<(), DescriptionError> {
        let nparam = self.nbodies + usize::from(self.is_floating());
        let numbers = [
            self.nv.checked_mul(10 * nparam),
            self.nv.checked_mul(self.nv),
            links.checked_mul(12),
        ]
        .into_iter()
        .try_fold(0usize, |sum, n| n.and_then(|n| sum.checked_add(n)));
        match numbers.and_then(|n| n.checked_mul(8)) {
            Some(bytes) if bytes <= MAX_DATA_BYTES => Ok(()),
            bytes => Err(DescriptionError::new(format!(
                "the model has {} moving joints: its dynamics workspace would need {}, more \
                 than twinloop's limit of {} GB (the joint-torque regressor alone is nv x 10 \
                 bodies numbers)",
                self.nbodies,
                bytes.map_or("more than 2^64 bytes".to_string(), |b| format!(
                    "{:.1} GB",
                    b as f64 / 1e9
                )),
                MAX_DATA_BYTES / 1_000_000_000
            ))),
        }
    }

    /// Count the bodies into `nq`, `nv`, `idx_q`, `idx_v` and `subtree_end`.
    /// Depth-first numbering makes a subtree a contiguous range.
    fn number_subtrees(&mut self) {
        self.nbodies = self.parents.len();
        for t in &self.joint_types {
            self.idx_q.push(self.nq);
            self.idx_v.push(self.nv);
            self.nq += t.nq();
            self.nv += t.nv();
        }
        self.subtree_end = (0..self.nbodies).map(|i| i + 1).collect();
        for i in (0..self.nbodies).rev() {
            let p = self.parents[i];
            if p != BASE {
                self.subtree_end[p] = self.subtree_end[p].max(self.subtree_end[i]);
            }
        }
    }

    /// A frame per link (in description order, every link must have been reached),
    /// then the description's named frames.
    fn add_frames(
        &mut self,
        robot: &Description,
        link_info: Vec<Option<LinkInfo>>,
    ) -> Result<(), DescriptionError> {
        for (l, info) in link_info.into_iter().enumerate() {
            let info = info.ok_or_else(|| {
                DescriptionError::new("link is not reachable from the root")
                    .at_element(format!("<link name=\"{}\">", robot.links[l].name))
            })?;
            self.frames.push(FrameInfo {
                name: info.name.clone(),
                body: info.body,
                placement: info.placement,
                link: Some(l),
            });
            self.links.push(info);
        }
        for f in &robot.frames {
            let l = robot.link_index(&f.link).ok_or_else(|| {
                DescriptionError::new(format!(
                    "frame \"{}\" is on unknown link \"{}\"",
                    f.name, f.link
                ))
            })?;
            let li = &self.links[l];
            self.frames.push(FrameInfo {
                name: f.name.clone(),
                body: li.body,
                placement: li.placement * pose_to_se3(&f.origin),
                link: None,
            });
        }
        Ok(())
    }

    pub fn is_floating(&self) -> bool {
        self.base == BaseKind::Floating
    }

    /// Whether some joint is spherical: then a body's q and v entries are at
    /// `idx_q[i]`, `idx_v[i]`, not `q_offset + i`, `v_offset + i`.
    pub fn has_spherical_joints(&self) -> bool {
        // Every other joint has one coordinate: O(1), asked in every CRBA.
        self.nq - self.q_offset != self.nbodies
    }

    /// The body owning each joint velocity coordinate `v_offset + k`, and the
    /// coordinate's rank within its joint (0, 1, 2 for a spherical joint).
    pub fn velocity_owner(&self, k: usize) -> (usize, usize) {
        let v = self.v_offset + k;
        let i = self.idx_v.partition_point(|&x| x <= v) - 1;
        (i, v - self.idx_v[i])
    }

    /// Index of a joint by name (into bodies; its v index is `v_offset + i`).
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joint_names.iter().position(|n| n == name)
    }

    pub fn frame_index(&self, name: &str) -> Option<usize> {
        self.frames.iter().position(|f| f.name == name)
    }

    /// Bodies from `i` up to the root, `i` first.
    pub fn ancestors(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        std::iter::successors(Some(i), move |&j| {
            let p = self.parents[j];
            (p != BASE).then_some(p)
        })
    }

    /// The neutral configuration: base at the origin with identity orientation, joints at zero.
    pub fn neutral_configuration(&self) -> Vec<f64> {
        let mut q = vec![0.0; self.nq];
        if self.is_floating() {
            q[6] = 1.0;
        }
        for (i, t) in self.joint_types.iter().enumerate() {
            if *t == JointType::Spherical {
                q[self.idx_q[i] + 3] = 1.0;
            }
        }
        q
    }

    /// Names of the configuration coordinates, in the CSV convention (`base.x`, ...,
    /// joint names; a spherical joint's quaternion as `<joint>.qx` ... `<joint>.qw`).
    pub fn q_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::with_capacity(self.nq);
        if self.is_floating() {
            out.extend(
                [
                    "base.x", "base.y", "base.z", "base.qx", "base.qy", "base.qz", "base.qw",
                ]
                .map(String::from),
            );
        }
        self.extend_joint_names(&mut out, &["qx", "qy", "qz", "qw"]);
        out
    }

    /// Joint names into `out`, a spherical joint's as `<joint>.<suffix>` per entry.
    fn extend_joint_names(&self, out: &mut Vec<String>, spherical: &[&str]) {
        for (name, t) in self.joint_names.iter().zip(&self.joint_types) {
            if *t == JointType::Spherical {
                out.extend(spherical.iter().map(|s| format!("{name}.{s}")));
            } else {
                out.push(name.clone());
            }
        }
    }

    /// Names of the velocity coordinates (`base.vx`, ..., `base.wz`, joint names; a
    /// spherical joint's angular velocity as `<joint>.wx` ... `<joint>.wz`).
    pub fn v_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::with_capacity(self.nv);
        if self.is_floating() {
            out.extend(
                [
                    "base.vx", "base.vy", "base.vz", "base.wx", "base.wy", "base.wz",
                ]
                .map(String::from),
            );
        }
        self.extend_joint_names(&mut out, &["wx", "wy", "wz"]);
        out
    }

    /// Names of the generalised forces (`base.fx`, ..., `base.tz`, joint names; a
    /// spherical joint's torque as `<joint>.tx` ... `<joint>.tz`).
    pub fn tau_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::with_capacity(self.nv);
        if self.is_floating() {
            out.extend(
                [
                    "base.fx", "base.fy", "base.fz", "base.tx", "base.ty", "base.tz",
                ]
                .map(String::from),
            );
        }
        self.extend_joint_names(&mut out, &["tx", "ty", "tz"]);
        out
    }
}
