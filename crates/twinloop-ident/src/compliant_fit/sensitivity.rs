//! Forward sensitivities of the compact model's CoM to its ten parameters, and the
//! Gauss-Newton normal equations built from them without storing the Jacobian.
//!
//! With the state s = [x, z, x', z'] and s' = f(s, r, p) (seed 002, eq 14-17), the
//! sensitivities S_j = ds/dp_j obey S_j' = A(p) S_j + df/dp_j, where A = df/ds. They are
//! integrated by the same RK4 stages as the state, each stage's S evaluated at that
//! stage's state: this is exactly the derivative of the discrete RK4 map (explicit
//! Runge-Kutta methods commute with differentiation), so the Jacobian is that of the
//! rollout the cost sees, not an approximation of it.

use super::dataset::Dataset;
use twinloop_reduced::CompactModel;
use twinloop_reduced::compact::State;

/// J^T J, J^T r and r^T r over the trajectory, for the residuals r = model - data in x
/// and z at every sample, and all ten parameters (alpha1 .. epsilon2, eta1, eta2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalEquations {
    pub jtj: [[f64; 10]; 10],
    pub jtr: [f64; 10],
    pub sse: f64,
    /// Number of residuals (2 per sample).
    pub residuals: usize,
}

/// Sensitivities of the state to the 10 parameters: `s[j][k] = d state_k / d p_j`.
type Sens = [[f64; 4]; 10];

/// The state Jacobian rows of x'' and z'' (the parts of A = df/ds that are not 0/1).
#[derive(Clone, Copy)]
struct Rows {
    x: [f64; 4],
    z: [f64; 4],
}

fn rows(model: &CompactModel, double_support: bool) -> Rows {
    let p = &model.plant;
    let c = &model.corrections;
    let (e1, e2) = if double_support {
        (c.eta1, c.eta2)
    } else {
        (1.0, 1.0)
    };
    let (a, b) = (e1 / p.m, e2 / p.m);
    Rows {
        x: [
            -a * c.alpha1 * p.Kxx,
            -a * c.beta1 * p.Kxz,
            -a * c.gamma1 * p.Dxx,
            -a * c.epsilon1 * p.Dxz,
        ],
        z: [
            -b * c.alpha2 * p.Kzx,
            -b * c.beta2 * p.Kzz,
            -b * c.gamma2 * p.Dzx,
            -b * c.epsilon2 * p.Dzz,
        ],
    }
}

/// d/dt of (state, sensitivities) at one RK4 stage.
#[inline(always)]
fn stage(
    model: &CompactModel,
    a: &Rows,
    s: &State,
    sens: &Sens,
    xr: f64,
    zr: f64,
    ds: bool,
) -> (State, Sens) {
    let p = &model.plant;
    let c = &model.corrections;
    let acc = model.acceleration(s, xr, zr, ds);
    let (e1, e2) = if ds { (c.eta1, c.eta2) } else { (1.0, 1.0) };
    let (ex, ez) = (s[0] - xr, s[1] - zr);
    let (ux, uz) = (-e1 / p.m, -e2 / p.m);
    // df/dp: the parameter multiplies one term of x'' or z''.
    let mut fx = [0.0; 10];
    let mut fz = [0.0; 10];
    fx[0] = ux * p.Kxx * ex;
    fx[1] = ux * p.Kxz * ez;
    fx[2] = ux * p.Dxx * s[2];
    fx[3] = ux * p.Dxz * s[3];
    fz[4] = uz * p.Kzx * ex;
    fz[5] = uz * p.Kzz * ez;
    fz[6] = uz * p.Dzx * s[2];
    fz[7] = uz * p.Dzz * s[3];
    if ds {
        // x'' = eta1 fx/m, z'' = -g + eta2 fz/m
        fx[8] = acc[0] / c.eta1;
        fz[9] = (acc[1] + p.g) / c.eta2;
    }
    let mut d_sens = [[0.0; 4]; 10];
    for j in 0..10 {
        let q = &sens[j];
        d_sens[j] = [
            q[2],
            q[3],
            a.x[0] * q[0] + a.x[1] * q[1] + a.x[2] * q[2] + a.x[3] * q[3] + fx[j],
            a.z[0] * q[0] + a.z[1] * q[1] + a.z[2] * q[2] + a.z[3] * q[3] + fz[j],
        ];
    }
    ([s[2], s[3], acc[0], acc[1]], d_sens)
}

#[inline(always)]
fn advance(s: &State, sens: &Sens, k: &State, dk: &Sens, h: f64) -> (State, Sens) {
    let s2 = std::array::from_fn(|i| s[i] + h * k[i]);
    let q2 = std::array::from_fn(|j| std::array::from_fn(|i| sens[j][i] + h * dk[j][i]));
    (s2, q2)
}

/// Rolls the model along the data's reference from the first recorded CoM at rest,
/// with the sensitivities, and accumulates the normal equations. Eta1 and eta2 need
/// nonzero values (their sensitivity divides by them). Allocates nothing.
pub fn normal_equations(model: &CompactModel, data: &Dataset) -> NormalEquations {
    let r = &data.reference;
    let rows_single = rows(model, false);
    let rows_double = rows(model, true);
    let mut s: State = [data.x[0], data.z[0], 0.0, 0.0];
    let mut sens: Sens = [[0.0; 4]; 10];
    let mut out = NormalEquations {
        jtj: [[0.0; 10]; 10],
        jtr: [0.0; 10],
        sse: 0.0,
        residuals: 2 * data.len(),
    };
    for i in 1..data.len() {
        let h = r.t[i] - r.t[i - 1];
        let ds = r.double_support[i - 1];
        let a = if ds { &rows_double } else { &rows_single };
        let (xa, za) = (r.xr[i - 1], r.zr[i - 1]);
        let (xb, zb) = (r.xr[i], r.zr[i]);
        let (xm, zm) = (0.5 * (xa + xb), 0.5 * (za + zb));
        let (k1, q1) = stage(model, a, &s, &sens, xa, za, ds);
        let (s2, p2) = advance(&s, &sens, &k1, &q1, 0.5 * h);
        let (k2, q2) = stage(model, a, &s2, &p2, xm, zm, ds);
        let (s3, p3) = advance(&s, &sens, &k2, &q2, 0.5 * h);
        let (k3, q3) = stage(model, a, &s3, &p3, xm, zm, ds);
        let (s4, p4) = advance(&s, &sens, &k3, &q3, h);
        let (k4, q4) = stage(model, a, &s4, &p4, xb, zb, ds);
        // Same arithmetic as CompactModel::rk4_step, so the residuals match the rollout.
        s = std::array::from_fn(|k| s[k] + h / 6.0 * (k1[k] + 2.0 * k2[k] + 2.0 * k3[k] + k4[k]));
        for j in 0..10 {
            for k in 0..4 {
                sens[j][k] += h / 6.0 * (q1[j][k] + 2.0 * q2[j][k] + 2.0 * q3[j][k] + q4[j][k]);
            }
        }
        let (rx, rz) = (s[0] - data.x[i], s[1] - data.z[i]);
        out.sse += rx * rx + rz * rz;
        for j in 0..10 {
            out.jtr[j] += sens[j][0] * rx + sens[j][1] * rz;
            for k in 0..=j {
                out.jtj[j][k] += sens[j][0] * sens[k][0] + sens[j][1] * sens[k][1];
            }
        }
    }
    for j in 0..10 {
        for k in 0..j {
            out.jtj[k][j] = out.jtj[j][k];
        }
    }
    if !out.sse.is_finite() {
        out.sse = f64::INFINITY;
    }
    out
}
