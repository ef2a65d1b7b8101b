//! Structural checks of a description: names unique, every joint's links exist,
//! one root, no cycles. Run by the readers and the builder so that everything
//! downstream can assume a tree.

use crate::description::Description;
use crate::error::DescriptionError;
use std::collections::HashMap;

impl Description {
    /// Check that the description is a tree; the error names the joint or link at fault.
    pub fn validate(&self) -> Result<(), DescriptionError> {
        let link_ix = self.link_indices()?;
        let parent_of = self.link_parents(&link_ix)?;
        self.check_inertials()?;
        self.check_one_tree(&parent_of)
    }

    /// Index of every link by name; links must have unique, non-empty names, and
    /// there must be one.
    fn link_indices(&self) -> Result<HashMap<&str, usize>, DescriptionError> {
        let mut link_ix: HashMap<&str, usize> = HashMap::with_capacity(self.links.len());
        for (i, l) in self.links.iter().enumerate() {
            if l.name.is_empty() {
                return Err(DescriptionError::new("link without a name")
                    .at_element(format!("link #{}", i + 1)));
            }
            if link_ix.insert(l.name.as_str(), i).is_some() {
                return Err(DescriptionError::new("duplicate link name")
                    .at_element(format!("<link name=\"{}\">", l.name)));
            }
        }
        if self.links.is_empty() {
            return Err(DescriptionError::new("the robot has no links"));
        }
        Ok(link_ix)
    }

    /// The parent link of every link, from the joints, whose names must be unique,
    /// whose links must exist (a link the child of at most one joint) and whose
    /// numbers must be finite.
    fn link_parents(
        &self,
        link_ix: &HashMap<&str, usize>,
    ) -> Result<Vec<Option<usize>>, DescriptionError> {
        let mut joint_names: HashMap<&str, ()> = HashMap::with_capacity(self.joints.len());
        let mut parent_of: Vec<Option<usize>> = vec![None; self.links.len()];
        for j in &self.joints {
            let here = || format!("<joint name=\"{}\">", j.name);
            if joint_names.insert(j.name.as_str(), ()).is_some() {
                return Err(DescriptionError::new("duplicate joint name").at_element(here()));
            }
            let Some(&p) = link_ix.get(j.parent.as_str()) else {
                return Err(DescriptionError::new(format!(
                    "parent link \"{}\" does not exist",
                    j.parent
                ))
                .at_element(here()));
            };
            let Some(&c) = link_ix.get(j.child.as_str()) else {
                return Err(DescriptionError::new(format!(
                    "child link \"{}\" does not exist",
                    j.child
                ))
                .at_element(here()));
            };
            if p == c {
                return Err(
                    DescriptionError::new("a joint cannot join a link to itself")
                        .at_element(here()),
                );
            }
            if parent_of[c].is_some() {
                return Err(DescriptionError::new(format!(
                    "link \"{}\" is the child of more than one joint",
                    j.child
                ))
                .at_element(here()));
            }
            parent_of[c] = Some(p);
            self.check_joint_values(j)?;
        }
        Ok(parent_of)
    }

    /// A joint's origin and axis are finite, a moving joint's axis is not zero, and
    /// a mimic names a joint that exists.
    fn check_joint_values(&self, j: &crate::Joint) -> Result<(), DescriptionError> {
        let here = || format!("<joint name=\"{}\">", j.name);
        if !j.origin.is_finite() {
            return Err(DescriptionError::new("origin is not finite").at_element(here()));
        }
        if let Some(a) = j.axis {
            if a.iter().any(|v| !v.is_finite()) {
                return Err(DescriptionError::new("axis is not finite").at_element(here()));
            }
            let moves = matches!(
                j.kind,
                crate::JointKind::Revolute
                    | crate::JointKind::Continuous
                    | crate::JointKind::Prismatic
            );
            if moves && a.iter().all(|v| *v == 0.0) {
                return Err(
                    DescriptionError::new("a moving joint has a zero axis").at_element(here())
                );
            }
        }
        // A mimic of an unknown joint is not an error: twinloop never couples mimic
        // joints, so lint warns about it (Pinocchio and urdfdom load such files).
        Ok(())
    }

    /// Every `<inertial>` is finite.
    fn check_inertials(&self) -> Result<(), DescriptionError> {
        for l in &self.links {
            if let Some(i) = l.inertial {
                let vals = [
                    i.mass,
                    i.inertia.ixx,
                    i.inertia.ixy,
                    i.inertia.ixz,
                    i.inertia.iyy,
                    i.inertia.iyz,
                    i.inertia.izz,
                ];
                if vals.iter().any(|v| !v.is_finite()) || !i.origin.is_finite() {
                    return Err(DescriptionError::new("inertial is not finite")
                        .at_element(format!("<link name=\"{}\">", l.name)));
                }
            }
        }
        Ok(())
    }

    /// Exactly one root, and every link reaches it (else it sits on a cycle).
    fn check_one_tree(&self, parent_of: &[Option<usize>]) -> Result<(), DescriptionError> {
        let roots: Vec<usize> = (0..self.links.len())
            .filter(|&i| parent_of[i].is_none())
            .collect();
        if roots.len() != 1 {
            let names: Vec<&str> = roots
                .iter()
                .take(5)
                .map(|&i| self.links[i].name.as_str())
                .collect();
            return Err(DescriptionError::new(if roots.is_empty() {
                "no root link: the joints form a cycle".to_string()
            } else {
                format!(
                    "{} root links (a robot is one tree): {}",
                    roots.len(),
                    names.join(", ")
                )
            }));
        }
        // Every link must reach the root: otherwise it sits on a cycle. Each walk up
        // stops at a link already known to reach it, so every link is walked once
        // (a walk from every link to the root is quadratic on a long chain).
        let mut reaches = vec![false; self.links.len()];
        let mut path = Vec::new();
        for start in 0..self.links.len() {
            let mut at = start;
            path.clear();
            while !reaches[at] {
                path.push(at);
                match parent_of[at] {
                    Some(p) if path.len() <= self.links.len() => at = p,
                    Some(_) => {
                        return Err(DescriptionError::new("the joints form a cycle")
                            .at_element(format!("<link name=\"{}\">", self.links[start].name)));
                    }
                    None => break,
                }
            }
            for &l in &path {
                reaches[l] = true;
            }
        }
        Ok(())
    }

    /// The root link (call after [`Description::validate`]).
    pub fn root_link(&self) -> Option<&str> {
        let r = self.root_links();
        if r.len() == 1 { Some(r[0]) } else { None }
    }

    /// Joints in depth-first order from the root, children in file order.
    /// This is twinloop's joint order (docs/architecture.md, "Conventions").
    pub fn joints_depth_first(&self) -> Vec<usize> {
        let mut children: HashMap<&str, Vec<usize>> = HashMap::new();
        for (i, j) in self.joints.iter().enumerate() {
            children.entry(j.parent.as_str()).or_default().push(i);
        }
        let mut out = Vec::with_capacity(self.joints.len());
        let Some(root) = self.root_link() else {
            return out;
        };
        let mut stack: Vec<usize> = children
            .get(root)
            .map(|v| v.iter().rev().copied().collect())
            .unwrap_or_default();
        while let Some(j) = stack.pop() {
            out.push(j);
            if out.len() > self.joints.len() {
                break; // cycle; validate() reports it
            }
            if let Some(ch) = children.get(self.joints[j].child.as_str()) {
                stack.extend(ch.iter().rev());
            }
        }
        out
    }
}
