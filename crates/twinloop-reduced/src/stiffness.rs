//! Cartesian stiffness and damping at the CoM (seed 002, eq 7-8).
//!
//! # The support-leg Jacobian J_CoM
//!
//! With the support foot held on the ground and every joint but the support leg's
//! frozen, the robot is a serial chain from the foot (the sole frame "below the ankle",
//! seed 002 Fig. 3) to the pelvis, carrying the rest of the body rigidly. J_CoM maps the
//! six leg joint velocities to the CoM's linear velocity and the pelvis's angular
//! velocity, both in the foot frame.
//!
//! From the floating-base Jacobians (base columns b, leg columns l): the foot twist
//! (LocalWorldAligned) is `J_fb v_b + J_fl dq = 0`, so `v_b = -J_fb^-1 J_fl dq` (J_fb is
//! always invertible: it is the foot's motion under a rigid motion of the whole body).
//! The CoM moves at `dc = J_cb v_b + J_cl dq` and the pelvis turns at `R_b w_b`. Hence
//!
//! ```text
//! J_CoM = R_f^T [ J_cl - J_cb J_fb^-1 J_fl ;  -R_b [0 I] J_fb^-1 J_fl ]   (6 x 6)
//! ```
//!
//! with R_f the foot's and R_b the base's orientation in the world.

use crate::error::{ReducedError, err};
use nalgebra::{DMatrix, Matrix2, Matrix6, Vector6};
use twinloop_dynamics::{
    Data, Model, ReferenceFrame, compute_joint_jacobians, frame_jacobian, jacobian_center_of_mass,
};

/// The support leg: six joints from the hip down, and the sole frame under the ankle.
#[derive(Debug, Clone, PartialEq)]
pub struct SupportLeg {
    pub joints: [String; 6],
    pub foot_frame: String,
}

impl SupportLeg {
    /// COMAN's left or right leg (joints `{L,R}HipSag .. {L,R}AnkSag`, frame `{l,r}_sole`).
    pub fn coman(left: bool) -> SupportLeg {
        let (p, f) = if left {
            ("L", "l_sole")
        } else {
            ("R", "r_sole")
        };
        SupportLeg {
            joints: ["HipSag", "HipLat", "HipYaw", "KneeSag", "AnkLat", "AnkSag"]
                .map(|j| format!("{p}{j}")),
            foot_frame: f.to_string(),
        }
    }
}

/// Joint stiffness and damping of COMAN (seed 002, section 2.1).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct JointCompliance {
    /// Harmonic-drive stiffness K_h, N m/rad (about 8000).
    pub k_harmonic: f64,
    /// Series spring stiffness K_s, N m/rad (about 100).
    pub k_series: f64,
    /// Joint damping of stiff and compliant joints, N m s/rad (the seed gives no value).
    pub d_stiff: f64,
    pub d_compliant: f64,
    /// Name endings of the compliant joints (seed 002, A2: knee and ankle pitch).
    pub compliant: Vec<String>,
}

impl Default for JointCompliance {
    fn default() -> Self {
        JointCompliance {
            k_harmonic: 8000.0,
            k_series: 100.0,
            d_stiff: 1.0,
            d_compliant: 1.0,
            compliant: vec!["KneeSag".into(), "AnkSag".into()],
        }
    }
}

impl JointCompliance {
    /// k_j = K_h K_s / (K_h + K_s) for a compliant joint, K_h for a stiff one
    /// (seed 002, section 2.1); the damping d_j likewise per class.
    pub fn joint(&self, name: &str) -> Result<(f64, f64), ReducedError> {
        for (what, v) in [
            ("harmonic-drive stiffness K_h", self.k_harmonic),
            ("series stiffness K_s", self.k_series),
            ("stiff-joint damping", self.d_stiff),
            ("compliant-joint damping", self.d_compliant),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return err(format!("{what} must be positive and finite, got {v}"));
            }
        }
        if self.compliant.iter().any(|c| name.ends_with(c.as_str())) {
            let k = self.k_harmonic * self.k_series / (self.k_harmonic + self.k_series);
            Ok((k, self.d_compliant))
        } else {
            Ok((self.k_harmonic, self.d_stiff))
        }
    }
}

/// K_C and D_C at the CoM with the Jacobian they came from.
#[derive(Debug, Clone, PartialEq)]
pub struct CartesianCompliance {
    /// J_CoM (rows: CoM x, y, z, pelvis wx, wy, wz in the foot frame; columns: leg joints).
    pub jacobian: Matrix6<f64>,
    pub k_joint: Vector6<f64>,
    pub d_joint: Vector6<f64>,
    /// K_C = J^-T K_j J^-1 (seed 002, eq 7).
    pub stiffness: Matrix6<f64>,
    /// D_C = J^-T D_j J^-1 (seed 002, eq 8).
    pub damping: Matrix6<f64>,
    /// CoM relative to the foot frame origin, in the foot frame, m.
    pub com_in_foot: [f64; 3],
    /// Smallest / largest singular value of J_CoM, linear rows divided by |com_in_foot|.
    pub inverse_condition: f64,
}

impl CartesianCompliance {
    /// The sagittal block [[xx, xz], [zx, zz]] of K_C (eq 11).
    pub fn stiffness_xz(&self) -> Matrix2<f64> {
        xz(&self.stiffness)
    }
    /// The x-z stiffness seen by forces alone (no moment on the pelvis, which may then
    /// turn): the inverse of the x-z block of the compliance J K_j^-1 J^T. Eq 7's block
    /// [`Self::stiffness_xz`] instead holds the pelvis orientation fixed, which loads the
    /// stiff hip joints and so is much stiffer. None if the block is singular.
    pub fn stiffness_xz_force_only(&self) -> Option<Matrix2<f64>> {
        let kinv = Matrix6::from_diagonal(&self.k_joint.map(|k| 1.0 / k));
        let c = self.jacobian * kinv * self.jacobian.transpose();
        xz(&c).try_inverse()
    }

    /// The sagittal block of D_C (eq 11).
    pub fn damping_xz(&self) -> Matrix2<f64> {
        xz(&self.damping)
    }
}

fn xz(m: &Matrix6<f64>) -> Matrix2<f64> {
    Matrix2::new(m[(0, 0)], m[(0, 2)], m[(2, 0)], m[(2, 2)])
}

fn leg_columns(model: &Model, leg: &SupportLeg) -> Result<[usize; 6], ReducedError> {
    let mut cols = [0; 6];
    for (c, name) in cols.iter_mut().zip(&leg.joints) {
        match model.joint_index(name) {
            Some(i) => *c = model.v_offset + i,
            None => return err(format!("the model has no joint named {name}")),
        }
    }
    Ok(cols)
}

/// J_CoM of the support leg at configuration q (seed 002, section 2.2 and Fig. 3; the
/// derivation is in the module documentation). Also returns the CoM in the foot frame.
pub fn support_leg_com_jacobian(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    leg: &SupportLeg,
) -> Result<(Matrix6<f64>, [f64; 3]), ReducedError> {
    if !model.is_floating() {
        return err("the model needs a floating base to hold the foot and move the body");
    }
    if q.len() != model.nq {
        return err(format!(
            "configuration has {} values, the model needs {}",
            q.len(),
            model.nq
        ));
    }
    if let Some(i) = q.iter().position(|x| !x.is_finite()) {
        return err(format!("configuration value {i} is not finite"));
    }
    let cols = leg_columns(model, leg)?;
    let Some(foot) = model.frame_index(&leg.foot_frame) else {
        return err(format!("the model has no frame named {}", leg.foot_frame));
    };
    let jc = jacobian_center_of_mass(model, data, q).clone();
    let com = data.com;
    compute_joint_jacobians(model, data, q);
    let mut jf = DMatrix::zeros(6, model.nv);
    frame_jacobian(
        model,
        data,
        foot,
        ReferenceFrame::LocalWorldAligned,
        &mut jf,
    );
    let f = &model.frames[foot];
    let o_m_f = if f.body == twinloop_dynamics::BASE {
        data.base_placement
    } else {
        data.o_m_i[f.body]
    } * f.placement;
    let rb = data.base_placement.rotation;
    let jfb: Matrix6<f64> = jf.fixed_view::<6, 6>(0, 0).into_owned();
    let jfl = Matrix6::from_fn(|r, c| jf[(r, cols[c])]);
    let Some(jfb_inv) = jfb.try_inverse() else {
        return err("the foot Jacobian's base block is singular (zero base motion?)");
    };
    // base twist per unit leg joint velocity with the foot held
    let vb = -(jfb_inv * jfl);
    let mut j = Matrix6::zeros();
    for c in 0..6 {
        let vb_c = vb.column(c);
        let mut dc = nalgebra::Vector3::from_fn(|r, _| jc[(r, cols[c])]);
        for k in 0..6 {
            dc += jc.fixed_view::<3, 1>(0, k) * vb_c[k];
        }
        let w = rb * nalgebra::Vector3::new(vb_c[3], vb_c[4], vb_c[5]);
        let rf_t = o_m_f.rotation.transpose();
        j.fixed_view_mut::<3, 1>(0, c).copy_from(&(rf_t * dc));
        j.fixed_view_mut::<3, 1>(3, c).copy_from(&(rf_t * w));
    }
    let rel = o_m_f.rotation.transpose() * (com - o_m_f.translation);
    Ok((j, [rel.x, rel.y, rel.z]))
}

/// Below this inverse condition number (of the length-scaled J_CoM) the leg counts as
/// singular: a stretched knee.
pub const MIN_INVERSE_CONDITION: f64 = 1e-3;

/// K_C = J^-T K_j J^-1 (seed 002, eq 7) and D_C = J^-T D_j J^-1 (seed 002, eq 8) at
/// configuration q with the given support leg. Errors name a missing joint or frame, a
/// non-positive stiffness or damping, and a singular Jacobian (a stretched knee).
pub fn cartesian_compliance(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    leg: &SupportLeg,
    joints: &JointCompliance,
) -> Result<CartesianCompliance, ReducedError> {
    let mut k_joint = Vector6::zeros();
    let mut d_joint = Vector6::zeros();
    for (i, name) in leg.joints.iter().enumerate() {
        let (k, d) = joints.joint(name)?;
        k_joint[i] = k;
        d_joint[i] = d;
    }
    let (jacobian, com_in_foot) = support_leg_com_jacobian(model, data, q, leg)?;
    // Condition of J_CoM with its linear rows made dimensionless by the foot-CoM
    // distance, so that metres and radians weigh alike.
    let length = nalgebra::Vector3::from(com_in_foot).norm().max(1e-3);
    let mut scaled = jacobian;
    for r in 0..3 {
        for c in 0..6 {
            scaled[(r, c)] /= length;
        }
    }
    let sv = scaled.singular_values();
    let inverse_condition = sv.min() / sv.max();
    if inverse_condition.is_nan() || inverse_condition <= MIN_INVERSE_CONDITION {
        return err(format!(
            "the support-leg Jacobian J_CoM is singular (inverse condition {inverse_condition:.1e}): \
             is the knee stretched? bend it"
        ));
    }
    let Some(j_inv) = jacobian.try_inverse() else {
        return err("the support-leg Jacobian J_CoM is singular: is the knee stretched?");
    };
    let stiffness = j_inv.transpose() * Matrix6::from_diagonal(&k_joint) * j_inv;
    let damping = j_inv.transpose() * Matrix6::from_diagonal(&d_joint) * j_inv;
    Ok(CartesianCompliance {
        jacobian,
        k_joint,
        d_joint,
        stiffness: 0.5 * (stiffness + stiffness.transpose()),
        damping: 0.5 * (damping + damping.transpose()),
        com_in_foot,
        inverse_condition,
    })
}

/// A crouched COMAN pose with flat feet: for both legs KneeSag = bend and
/// HipSag = AnkSag = -bend/2 (all pitch axes along +y), every other joint at zero.
pub fn coman_crouch(model: &Model, bend: f64) -> Result<Vec<f64>, ReducedError> {
    if !bend.is_finite() {
        return err(format!("knee bend must be finite, got {bend}"));
    }
    let mut q = model.neutral_configuration();
    for side in ["L", "R"] {
        for (j, v) in [
            ("HipSag", -0.5 * bend),
            ("KneeSag", bend),
            ("AnkSag", -0.5 * bend),
        ] {
            let name = format!("{side}{j}");
            let Some(i) = model.joint_index(&name) else {
                return err(format!("the model has no joint named {name} (not COMAN?)"));
            };
            q[model.q_offset + i] = v;
        }
    }
    Ok(q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
    use twinloop_dynamics::frames_forward_kinematics;
    use twinloop_spatial::Se3;

    fn coman() -> Model {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/coman/coman.urdf");
        let robot = twinloop_description::load(std::path::Path::new(path)).unwrap();
        Model::from_description(&robot).unwrap()
    }

    fn set_base(q: &mut [f64], m: &Se3) {
        let uq =
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m.rotation));
        q[0..3].copy_from_slice(m.translation.as_slice());
        q[3..7].copy_from_slice(uq.coords.as_slice());
    }

    /// CoM and pelvis orientation after moving leg joint `col` by `dq` with the foot held.
    fn held(
        model: &Model,
        q0: &[f64],
        leg: &SupportLeg,
        col: usize,
        dq: f64,
    ) -> (Vector3<f64>, Matrix3<f64>) {
        let mut data = Data::new(model);
        let foot = model.frame_index(&leg.foot_frame).unwrap();
        frames_forward_kinematics(model, &mut data, q0);
        let o_m_f = data.o_m_f[foot];
        let mut q = q0.to_vec();
        q[model.q_offset + model.joint_index(&leg.joints[col]).unwrap()] += dq;
        set_base(&mut q, &Se3::IDENTITY);
        frames_forward_kinematics(model, &mut data, &q);
        let b_m_f = data.o_m_f[foot];
        let o_m_b = o_m_f * b_m_f.inverse();
        set_base(&mut q, &o_m_b);
        let c = twinloop_dynamics::center_of_mass(model, &mut data, &q);
        // the foot did not move
        frames_forward_kinematics(model, &mut data, &q);
        assert!((data.o_m_f[foot].translation - o_m_f.translation).norm() < 1e-12);
        (c, data.base_placement.rotation)
    }

    fn tilted_pose(model: &Model) -> Vec<f64> {
        let mut q = coman_crouch(model, 0.5).unwrap();
        for (name, v) in [
            ("RHipLat", 0.08),
            ("RHipYaw", 0.05),
            ("RAnkLat", -0.06),
            ("WaistSag", 0.1),
            ("LHipLat", 0.07),
        ] {
            q[model.q_offset + model.joint_index(name).unwrap()] = v;
        }
        let r = UnitQuaternion::from_euler_angles(0.05, -0.1, 0.3);
        q[0..3].copy_from_slice(&[0.2, -0.1, 0.6]);
        q[3..7].copy_from_slice(r.coords.as_slice());
        q
    }

    #[test]
    fn com_jacobian_matches_finite_differences_with_the_foot_held() {
        let model = coman();
        let mut data = Data::new(&model);
        for left in [false, true] {
            let leg = SupportLeg::coman(left);
            let q = tilted_pose(&model);
            let (j, _) = support_leg_com_jacobian(&model, &mut data, &q, &leg).unwrap();
            frames_forward_kinematics(&model, &mut data, &q);
            let rf = data.o_m_f[model.frame_index(&leg.foot_frame).unwrap()].rotation;
            let h = 1e-6;
            let mut worst: f64 = 0.0;
            for c in 0..6 {
                let (cp, rp) = held(&model, &q, &leg, c, h);
                let (cm, rm) = held(&model, &q, &leg, c, -h);
                let dc = rf.transpose() * (cp - cm) / (2.0 * h);
                // angular velocity: skew(w) = dR R^T
                let rb = data.base_placement.rotation;
                let s = (rp - rm) / (2.0 * h) * rb.transpose();
                let w = rf.transpose() * Vector3::new(s[(2, 1)], s[(0, 2)], s[(1, 0)]);
                for r in 0..3 {
                    worst = worst.max((dc[r] - j[(r, c)]).abs());
                    worst = worst.max((w[r] - j[(3 + r, c)]).abs());
                }
            }
            assert!(worst < 1e-8, "J_CoM vs finite differences: {worst:e}");
        }
    }

    #[test]
    fn stiffness_maps_back_to_the_joint_stiffness() {
        // eq 7 in reverse: J^T K_C J = K_j, J^T D_C J = D_j.
        let model = coman();
        let mut data = Data::new(&model);
        let q = coman_crouch(&model, 0.6).unwrap();
        let joints = JointCompliance::default();
        let cc =
            cartesian_compliance(&model, &mut data, &q, &SupportLeg::coman(true), &joints).unwrap();
        let ks = 8000.0 * 100.0 / 8100.0;
        assert!((cc.k_joint[3] - ks).abs() < 1e-12 && (cc.k_joint[5] - ks).abs() < 1e-12);
        assert_eq!(cc.k_joint[0], 8000.0);
        let back = cc.jacobian.transpose() * cc.stiffness * cc.jacobian;
        let kj = Matrix6::from_diagonal(&cc.k_joint);
        assert!((back - kj).norm() / kj.norm() < 1e-9);
        let back = cc.jacobian.transpose() * cc.damping * cc.jacobian;
        assert!((back - Matrix6::from_diagonal(&cc.d_joint)).norm() < 1e-9);
        // symmetric positive definite, and the sagittal block too
        assert!(cc.stiffness.symmetric_eigenvalues().min() > 0.0);
        assert!(cc.stiffness_xz().symmetric_eigenvalues().min() > 0.0);
        // forces alone meet a softer leg than eq 7's block (pelvis orientation held)
        let soft = cc.stiffness_xz_force_only().unwrap();
        assert!(soft[(0, 0)] > 0.0 && soft[(0, 0)] < cc.stiffness_xz()[(0, 0)]);
        // the CoM sits above the foot
        assert!(cc.com_in_foot[2] > 0.3);
    }

    #[test]
    fn stretched_knee_and_bad_stiffness_are_named() {
        let model = coman();
        let mut data = Data::new(&model);
        let leg = SupportLeg::coman(false);
        let q = model.neutral_configuration();
        let e = cartesian_compliance(&model, &mut data, &q, &leg, &JointCompliance::default())
            .unwrap_err();
        assert!(
            e.message.contains("singular") && e.message.contains("knee"),
            "{e}"
        );
        let q = coman_crouch(&model, 0.5).unwrap();
        let bad = JointCompliance {
            k_series: -1.0,
            ..JointCompliance::default()
        };
        let e = cartesian_compliance(&model, &mut data, &q, &leg, &bad).unwrap_err();
        assert!(e.message.contains("series stiffness"), "{e}");
        let wrong = SupportLeg {
            joints: SupportLeg::coman(true)
                .joints
                .map(|j| j.replace("Hip", "Hop")),
            foot_frame: "l_sole".into(),
        };
        let e = cartesian_compliance(&model, &mut data, &q, &wrong, &JointCompliance::default())
            .unwrap_err();
        assert!(e.message.contains("LHopSag"), "{e}");
        assert!(
            cartesian_compliance(
                &model,
                &mut data,
                &q[1..],
                &leg,
                &JointCompliance::default()
            )
            .is_err()
        );
    }
}
