//! Building robots in code.
//!
//! ```
//! use twinloop_description::{DescriptionBuilder, Inertia, JointKind, Pose, Geometry};
//! let robot = DescriptionBuilder::new("pendulum")
//!     .link("base").box_shape([0.1, 0.1, 0.1]).done()
//!     .link("arm").mass(1.0, [0.0, 0.0, -0.25], Inertia::solid_cylinder(1.0, 0.02, 0.5)).done()
//!     .revolute("hinge", "base", "arm", [0.0, 1.0, 0.0]).origin(Pose::from_xyz([0.0, 0.0, -0.05]))
//!         .limits(-1.5, 1.5, 3.0, 5.0).done()
//!     .build()
//!     .unwrap();
//! assert_eq!(robot.links.len(), 2);
//! ```

use crate::description::*;
use crate::error::DescriptionError;

/// Builds a [`Description`]; `build` checks that the result is a tree.
pub struct DescriptionBuilder {
    robot: Description,
}

impl DescriptionBuilder {
    pub fn new(name: impl Into<String>) -> Self {
        DescriptionBuilder {
            robot: Description {
                name: name.into(),
                ..Default::default()
            },
        }
    }

    /// Start a link; finish it with [`LinkBuilder::done`].
    pub fn link(self, name: impl Into<String>) -> LinkBuilder {
        LinkBuilder {
            parent: self,
            link: Link::new(name),
        }
    }

    /// Add a finished link.
    pub fn add_link(mut self, link: Link) -> Self {
        self.robot.order.push(Item::Link(self.robot.links.len()));
        self.robot.links.push(link);
        self
    }

    /// Add a finished joint.
    pub fn add_joint(mut self, joint: Joint) -> Self {
        self.robot.order.push(Item::Joint(self.robot.joints.len()));
        self.robot.joints.push(joint);
        self
    }

    /// Start a joint of any kind.
    pub fn joint(
        self,
        name: impl Into<String>,
        kind: JointKind,
        parent: impl Into<String>,
        child: impl Into<String>,
    ) -> JointBuilder {
        JointBuilder {
            parent: self,
            joint: Joint::new(name, kind, parent, child),
        }
    }

    pub fn revolute(
        self,
        name: impl Into<String>,
        parent: impl Into<String>,
        child: impl Into<String>,
        axis: [f64; 3],
    ) -> JointBuilder {
        let mut b = self.joint(name, JointKind::Revolute, parent, child);
        b.joint.axis = Some(axis);
        b
    }

    pub fn fixed(
        self,
        name: impl Into<String>,
        parent: impl Into<String>,
        child: impl Into<String>,
    ) -> JointBuilder {
        self.joint(name, JointKind::Fixed, parent, child)
    }

    /// A named frame on a link.
    pub fn frame(mut self, name: impl Into<String>, link: impl Into<String>, origin: Pose) -> Self {
        self.robot.order.push(Item::Frame(self.robot.frames.len()));
        self.robot.frames.push(Frame {
            name: name.into(),
            link: link.into(),
            origin,
        });
        self
    }

    pub fn build(self) -> Result<Description, DescriptionError> {
        self.robot.validate()?;
        for f in &self.robot.frames {
            if self.robot.link(&f.link).is_none() {
                return Err(DescriptionError::new(format!(
                    "frame \"{}\" is on unknown link \"{}\"",
                    f.name, f.link
                )));
            }
        }
        Ok(self.robot)
    }
}

pub struct LinkBuilder {
    parent: DescriptionBuilder,
    link: Link,
}

impl LinkBuilder {
    /// Mass, CoM (in the link frame) and inertia about the CoM (axes of the link frame).
    pub fn mass(mut self, mass: f64, com: [f64; 3], inertia: Inertia) -> Self {
        self.link.inertial = Some(Inertial {
            origin: Pose::from_xyz(com),
            mass,
            inertia,
        });
        self
    }

    pub fn inertial(mut self, inertial: Inertial) -> Self {
        self.link.inertial = Some(inertial);
        self
    }

    pub fn visual(mut self, origin: Pose, geometry: Geometry) -> Self {
        self.link.visuals.push(Shape {
            name: None,
            origin,
            geometry,
            material: None,
        });
        self
    }

    pub fn collision(mut self, origin: Pose, geometry: Geometry) -> Self {
        self.link.collisions.push(Shape {
            name: None,
            origin,
            geometry,
            material: None,
        });
        self
    }

    /// A box used for both visual and collision, centred on the link frame.
    pub fn box_shape(self, size: [f64; 3]) -> Self {
        let g = Geometry::Box { size };
        self.visual(Pose::IDENTITY, g.clone())
            .collision(Pose::IDENTITY, g)
    }

    pub fn done(self) -> DescriptionBuilder {
        self.parent.add_link(self.link)
    }
}

pub struct JointBuilder {
    parent: DescriptionBuilder,
    joint: Joint,
}

impl JointBuilder {
    pub fn origin(mut self, origin: Pose) -> Self {
        self.joint.origin = origin;
        self
    }

    pub fn axis(mut self, axis: [f64; 3]) -> Self {
        self.joint.axis = Some(axis);
        self
    }

    pub fn limits(mut self, lower: f64, upper: f64, effort: f64, velocity: f64) -> Self {
        self.joint.limit = Some(Limit {
            lower: Some(lower),
            upper: Some(upper),
            effort: Some(effort),
            velocity: Some(velocity),
        });
        self
    }

    pub fn damping(mut self, damping: f64, friction: f64) -> Self {
        self.joint.dynamics = Some(JointDynamics {
            damping: Some(damping),
            friction: Some(friction),
        });
        self
    }

    pub fn mimic(mut self, joint: impl Into<String>, multiplier: f64, offset: f64) -> Self {
        self.joint.mimic = Some(Mimic {
            joint: joint.into(),
            multiplier,
            offset,
        });
        self
    }

    pub fn done(self) -> DescriptionBuilder {
        self.parent.add_joint(self.joint)
    }
}
