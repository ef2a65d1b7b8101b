//! Static identification of link masses and centres of mass from force-plate poses
//! (seed 004, section 3.3, eq 8-9).
//!
//! The CoM is linear in each link's mass `m_l` and first moment `h_l = m_l c_l`
//! (`c_l` in the link frame): `M com(q) = G(q) phi` with the static CoM regressor
//! `G` ([`twinloop_dynamics::static_com_regressor`]). In a static pose the force
//! plate's centre of pressure is the ground-projected CoM, so each pose gives two
//! linear equations `G_xy(q_n) phi = M cop_n`. Seed 004 minimises the GCOM-to-CoP
//! distance subject to the measured total mass; here that is solved directly as a
//! constrained linear least-squares problem in `x = (m_l, h_l)` of the identified
//! links, the others kept at the prior:
//!
//! ```text
//! minimise |A x - b|^2 + lambda^2 |S^-1 (x - x0)|^2
//! subject to sum m_l = M - m_fixed,   m_l >= m_min,l,   m_l c_lo,l <= h_l <= m_l c_hi,l
//! ```
//!
//! **The regulariser, and why this one.** `x0` is the prior (the CAD model), `S` a
//! diagonal of prior uncertainties (100 % of each mass; that mass times the link's
//! size for each first moment) and `lambda = M sigma_cop` the noise of one equation.
//! This is the maximum a-posteriori estimate for a Gaussian prior around the CAD
//! values and Gaussian plate noise. In the SVD basis of the scaled regressor
//! `A S = U Sigma V^T` its unconstrained solution is `z = sum_i f_i (u_i^T r / sigma_i) v_i`
//! with filter factors `f_i = sigma_i^2 / (sigma_i^2 + lambda^2)`: directions the poses
//! see well (`sigma_i >> lambda`) come from the data unbiased, directions they do
//! not see (`sigma_i = 0`: links welded to one body, a first moment along an axis
//! that never tilts, a joint that never moves) keep exactly the prior's component,
//! and the few in between are blended by their signal-to-noise ratio. A truncated
//! SVD ("keep the prior in the null space") does the first two as well but must
//! pick a hard cut-off: just above it noise is amplified by `1/sigma_i`, just below
//! it real information is thrown away; the filter factors need no cut-off, the
//! noise level sets it. And it keeps the problem a strictly convex QP, so the mass
//! equality and the bounds (masses positive, CoMs inside a box around the link)
//! are solved exactly by an active-set method ([`crate::qp`]) instead of clipping a
//! TSVD solution afterwards. With `sigma_cop = 0` (noise-free data) `lambda` falls
//! to `1e-7 sigma_max`: the data decide every direction they see at all.
//!
//! The SVD (from the eigen-decomposition of `(A S)^T (A S)`) also gives the
//! identifiability report: rank, singular values, condition number, and the
//! parameter combinations the poses cannot determine, grouped by the links they involve.

use crate::anatomy::link_geometry_points;
use crate::error::IdentError;
use crate::plate::{Plan, PlateGenerator};
use crate::poses::{PoseCategory, StaticPose};
use crate::qp::Qp;
use nalgebra::{DMatrix, DVector, SymmetricEigen, Vector3};
use serde::Serialize;
use twinloop_description::Description;
use twinloop_dynamics::{Data, Model, static_com_regressor};

/// Settings of the fit.
#[derive(Debug, Clone)]
pub struct StaticOptions {
    /// Links to identify (`None`: every link with a positive prior mass).
    pub links: Option<Vec<String>>,
    /// Assumed CoP noise per axis (m): sets the regulariser's weight. 0 for exact data.
    pub cop_sigma: f64,
    /// How far a CoM may leave the box around the link's geometry and prior CoM (m).
    pub com_margin: f64,
    /// Lower bound of each mass as a fraction of its prior mass.
    pub min_mass_fraction: f64,
}

impl Default for StaticOptions {
    fn default() -> Self {
        StaticOptions {
            links: None,
            cop_sigma: 1e-3,
            com_margin: 0.03,
            min_mass_fraction: 0.01,
        }
    }
}

/// Relative singular-value threshold below which a direction counts as not seen at
/// all (the Gram matrix gives singular values to about 1e-8 of the largest).
pub const RANK_TOLERANCE: f64 = 1e-7;

/// One identified link.
#[derive(Debug, Clone, Serialize)]
pub struct LinkEstimate {
    pub name: String,
    pub prior_mass: f64,
    pub mass: f64,
    /// Posterior standard deviation of the mass (from the noise level), kg.
    pub mass_std: f64,
    /// CoM in the link frame (the URDF `<inertial><origin xyz>`), m.
    pub prior_com: [f64; 3],
    pub com: [f64; 3],
    pub com_std: [f64; 3],
    /// The box the CoM was kept in.
    pub com_lower: [f64; 3],
    pub com_upper: [f64; 3],
    /// Bounds active at the solution ("mass", "com.x lower", ...).
    pub at_bounds: Vec<String>,
    /// How much of the mass and of each first-moment component the poses determine
    /// (0: all prior, 1: all data).
    pub mass_determined: f64,
    pub first_moment_determined: [f64; 3],
}

/// Parameters that move together in directions the data do not determine.
#[derive(Debug, Clone, Serialize)]
pub struct ParameterGroup {
    /// Parameter names `<link>.m`, `<link>.mc_x`, ... (first moment m c in the link frame).
    pub parameters: Vec<String>,
    pub links: Vec<String>,
    /// How many independent directions in this group are undetermined.
    pub directions: usize,
    pub why: String,
}

/// What the poses can and cannot tell.
#[derive(Debug, Clone, Serialize)]
pub struct Identifiability {
    pub parameters: usize,
    /// Directions seen at all (singular value above `RANK_TOLERANCE` of the largest).
    pub rank: usize,
    /// Directions seen above the noise (singular value above `noise_level`).
    pub well_determined: usize,
    /// Singular values of the prior-scaled regressor, largest first (kg m).
    pub singular_values: Vec<f64>,
    /// Largest over smallest singular value within the rank.
    pub condition_number: f64,
    /// Largest over smallest singular value of all (infinite when rank-deficient).
    pub condition_number_full: f64,
    /// `lambda`: the noise of one equation, M sigma_cop (kg m).
    pub noise_level: f64,
    /// Directions no static pose can ever determine (from CoP data a link's mass and
    /// its first moment along its joint axis act exactly like parameters of its
    /// parent; links welded to one body act as one): kept at the prior.
    pub structural_null: usize,
    pub structural_explanation: String,
    /// Identified links welded to one body (fixed joints): from CoM data only their
    /// combined mass and first moment are seen; how they split stays at the prior.
    pub welded: Vec<Vec<String>>,
    /// Further combinations these poses do not determine but other poses would:
    /// kept at the prior; see the suggested poses.
    pub unidentifiable: Vec<ParameterGroup>,
    /// Combinations seen, but below the noise: mostly kept at the prior.
    pub poorly_identified: Vec<ParameterGroup>,
    /// Per parameter, how much of it the data determine (0: all prior, 1: all data).
    pub determined_fraction: Vec<(String, f64)>,
}

/// Summary of distances, m.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct Stats {
    pub mean: f64,
    pub std: f64,
    pub max: f64,
}

impl Stats {
    pub fn of(x: &[f64]) -> Stats {
        if x.is_empty() {
            return Stats::default();
        }
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
        Stats {
            mean,
            std: var.sqrt(),
            max: x.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// The result of [`identify_static`].
#[derive(Debug, Clone, Serialize)]
pub struct StaticResult {
    pub model: String,
    pub poses: usize,
    /// The measured total mass (seed eq 9), kg.
    pub total_mass: f64,
    pub prior_total_mass: f64,
    /// Mass of the links kept at their prior values, kg.
    pub fixed_mass: f64,
    pub links: Vec<LinkEstimate>,
    /// Links not identified (name, mass), with mass.
    pub fixed_links: Vec<(String, f64)>,
    /// Distance from the model's GCOM to the measured CoP per pose, prior model (m).
    pub gcom_distance_before: Vec<f64>,
    /// The same for the identified model.
    pub gcom_distance_after: Vec<f64>,
    pub before: Stats,
    pub after: Stats,
    pub identifiability: Identifiability,
    pub qp_iterations: usize,
    /// Per description link, (m, m c_x, m c_y, m c_z) after identification.
    #[serde(skip)]
    pub parameters: Vec<f64>,
    /// The prior's GCOM and the adapted model's, per pose (world x, y).
    #[serde(skip)]
    pub gcom_before: Vec<[f64; 2]>,
    #[serde(skip)]
    pub gcom_after: Vec<[f64; 2]>,
}

/// The fit's fixed part: which links, their prior, scales and bounds.
#[derive(Debug, Clone)]
pub struct StaticProblem {
    /// Identified description links.
    pub links: Vec<usize>,
    pub total_mass: f64,
    pub fixed_mass: f64,
    /// Prior per description link (m, h).
    pub prior: Vec<f64>,
    /// Prior of the identified unknowns, and their scales.
    pub x0: DVector<f64>,
    pub scale: DVector<f64>,
    pub com_lower: Vec<Vector3<f64>>,
    pub com_upper: Vec<Vector3<f64>>,
    pub min_mass: Vec<f64>,
    pub cop_sigma: f64,
    pub names: Vec<String>,
    /// Body of each identified link (for explaining unidentifiable groups).
    bodies: Vec<usize>,
    link_names: Vec<String>,
}

fn param_names(link: &str) -> [String; 4] {
    [
        format!("{link}.m"),
        format!("{link}.mc_x"),
        format!("{link}.mc_y"),
        format!("{link}.mc_z"),
    ]
}

/// The input checks of [`StaticProblem::new`], each error naming its option.
fn check_static_inputs(
    model: &Model,
    total_mass: f64,
    options: &StaticOptions,
) -> Result<(), IdentError> {
    if !model.is_floating() {
        return Err(IdentError::new(
            "static identification needs a floating-base model",
        ));
    }
    if !(total_mass.is_finite() && total_mass > 0.0) {
        return Err(IdentError::new(format!(
            "{total_mass} is not a mass: give the robot's weight on a scale, in kg"
        ))
        .option("total_mass"));
    }
    if !(options.cop_sigma.is_finite() && options.cop_sigma >= 0.0) {
        return Err(IdentError::new(format!(
            "{} is not a standard deviation (finite, >= 0)",
            options.cop_sigma
        ))
        .option("cop_sigma"));
    }
    Ok(())
}

/// The description links to identify: the named ones (each once, each with an
/// `<inertial>` in the prior), or every link with mass.
fn identified_links(
    robot: &Description,
    model: &Model,
    options: &StaticOptions,
) -> Result<Vec<usize>, IdentError> {
    let nl = model.links.len();
    let links: Vec<usize> = match &options.links {
        None => (0..nl)
            .filter(|&l| model.links[l].inertia.mass > 0.0)
            .collect(),
        Some(names) => {
            let mut v = Vec::new();
            for n in names {
                let l = robot.link_index(n).ok_or_else(|| {
                    IdentError::new(format!(
                        "no link named \"{n}\" in the model \"{}\"",
                        model.name
                    ))
                    .option("links")
                })?;
                if robot.links[l].inertial.is_none() {
                    return Err(IdentError::new(format!(
                        "link \"{n}\" has no <inertial> in the prior: give it one, or leave it out"
                    ))
                    .option("links"));
                }
                if !v.contains(&l) {
                    v.push(l);
                }
            }
            v
        }
    };
    if links.is_empty() {
        return Err(IdentError::new("no link to identify").option("links"));
    }
    Ok(links)
}

/// The identified unknowns' prior, scales, CoM bounds and names.
struct PriorScales {
    x0: DVector<f64>,
    scale: DVector<f64>,
    com_lower: Vec<Vector3<f64>>,
    com_upper: Vec<Vector3<f64>>,
    names: Vec<String>,
}

/// Per identified link: the prior (m, h); the prior uncertainty, the mass itself
/// (floored) and that mass times the link's size for its first moment; and the CoM box,
/// the link's geometry (with its prior CoM) grown by the CoM margin.
fn prior_scales(
    robot: &Description,
    model: &Model,
    links: &[usize],
    prior: &[f64],
    total_mass: f64,
    com_margin: f64,
) -> PriorScales {
    let n = 4 * links.len();
    let mut out = PriorScales {
        x0: DVector::zeros(n),
        scale: DVector::zeros(n),
        com_lower: Vec::new(),
        com_upper: Vec::new(),
        names: Vec::new(),
    };
    for (k, &l) in links.iter().enumerate() {
        let m = model.links[l].inertia.mass;
        let c = model.links[l].inertia.com;
        for j in 0..4 {
            out.x0[4 * k + j] = prior[4 * l + j];
        }
        let sm = m.max(0.01 * total_mass / links.len() as f64).max(1e-3);
        let pts = link_geometry_points(robot, l);
        let mut lo = c;
        let mut hi = c;
        for p in &pts {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let size = (hi - lo).amax().max(c.norm()).max(0.05);
        out.scale[4 * k] = sm;
        for j in 1..4 {
            out.scale[4 * k + j] = sm * size;
        }
        let margin = Vector3::repeat(com_margin);
        out.com_lower.push(lo - margin);
        out.com_upper.push(hi + margin);
        out.names.extend(param_names(&model.links[l].name));
    }
    out
}

impl StaticProblem {
    /// Choose the links, check the total mass, and set scales and bounds.
    pub fn new(
        robot: &Description,
        model: &Model,
        total_mass: f64,
        options: &StaticOptions,
    ) -> Result<StaticProblem, IdentError> {
        check_static_inputs(model, total_mass, options)?;
        let nl = model.links.len();
        let links = identified_links(robot, model, options)?;
        let prior = twinloop_dynamics::link_static_parameters(model);
        let fixed_mass: f64 = (0..nl)
            .filter(|l| !links.contains(l))
            .map(|l| model.links[l].inertia.mass)
            .sum();
        let min_mass: Vec<f64> = links
            .iter()
            .map(|&l| (options.min_mass_fraction * model.links[l].inertia.mass).max(1e-6))
            .collect();
        let floor: f64 = min_mass.iter().sum();
        if total_mass - fixed_mass <= floor {
            return Err(IdentError::new(format!(
                "{total_mass} kg is not more than the {fixed_mass:.6} kg of the links kept fixed \
                 (plus {floor:.6} kg of minimum masses): the identified links would have no mass"
            ))
            .option("total_mass"));
        }
        let p = prior_scales(robot, model, &links, &prior, total_mass, options.com_margin);
        Ok(StaticProblem {
            bodies: links.iter().map(|&l| model.links[l].body).collect(),
            link_names: model.links.iter().map(|l| l.name.clone()).collect(),
            links,
            total_mass,
            fixed_mass,
            prior,
            x0: p.x0,
            scale: p.scale,
            com_lower: p.com_lower,
            com_upper: p.com_upper,
            min_mass,
            cop_sigma: options.cop_sigma,
            names: p.names,
        })
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        4 * self.links.len()
    }

    /// Fewest poses that give at least as many equations (2 per pose, plus the mass) as unknowns.
    pub fn min_poses(&self) -> usize {
        (self.unknowns().saturating_sub(1)).div_ceil(2)
    }
}

/// Reusable buffers for the fit.
#[derive(Debug, Clone)]
pub struct StaticWorkspace {
    data: Data,
    /// Columns of the identified links, 2 rows per pose.
    pub a: DMatrix<f64>,
    pub b: DVector<f64>,
    is_identified: Vec<Option<usize>>,
}

impl StaticWorkspace {
    pub fn new(model: &Model, problem: &StaticProblem, poses: usize) -> Self {
        let mut is_identified = vec![None; model.links.len()];
        for (k, &l) in problem.links.iter().enumerate() {
            is_identified[l] = Some(k);
        }
        StaticWorkspace {
            data: Data::new(model),
            a: DMatrix::zeros(2 * poses, problem.unknowns()),
            b: DVector::zeros(2 * poses),
            is_identified,
        }
    }
}

/// Fill `A` and `b` of seed 004 eq 8: per pose, the x and y rows of the static CoM
/// regressor for the identified links, and `M cop - G_fixed phi_fixed`.
pub fn assemble(
    model: &Model,
    problem: &StaticProblem,
    poses: &[StaticPose],
    ws: &mut StaticWorkspace,
) {
    let m = problem.total_mass;
    for (n, pose) in poses.iter().enumerate() {
        let g = static_com_regressor(model, &mut ws.data, &pose.q);
        for r in 0..2 {
            let row = 2 * n + r;
            let mut rhs = m * pose.cop[r];
            for (l, slot) in ws.is_identified.iter().enumerate() {
                match slot {
                    Some(k) => {
                        for j in 0..4 {
                            ws.a[(row, 4 * k + j)] = g[(r, 4 * l + j)];
                        }
                    }
                    None => {
                        for j in 0..4 {
                            rhs -= g[(r, 4 * l + j)] * problem.prior[4 * l + j];
                        }
                    }
                }
            }
            ws.b[row] = rhs;
        }
    }
}

/// The fit of seed 004 eq 8-9 on an assembled system: returns the unknowns `x`, the QP
/// iteration count, the active inequalities, and the scaled Gram matrix and lambda.
pub struct Fit {
    pub x: DVector<f64>,
    pub iterations: usize,
    pub active: Vec<usize>,
    /// `(A S)^T (A S)`.
    pub gram: DMatrix<f64>,
    pub lambda: f64,
    /// `(A S)^T (A S) + lambda^2 I`.
    pub hessian: DMatrix<f64>,
}

/// Solve the constrained, regularised least-squares problem (seed 004, eq 8 subject
/// to eq 9 and the physical bounds) for the assembled `A`, `b`.
pub fn solve(problem: &StaticProblem, ws: &StaticWorkspace) -> Result<Fit, IdentError> {
    let n = problem.unknowns();
    let s = &problem.scale;
    // A S, r = b - A x0.
    let mut a_s = ws.a.clone();
    for j in 0..n {
        a_s.column_mut(j).scale_mut(s[j]);
    }
    let r = &ws.b - &ws.a * &problem.x0;
    let gram = symmetric_gram(&a_s);
    let f = a_s.tr_mul(&r);
    // Largest singular value squared is at most the trace; the largest diagonal is a
    // cheap lower bound good enough to set the floor of lambda.
    let dmax = (0..n).map(|j| gram[(j, j)]).fold(0.0, f64::max);
    let lambda = (problem.total_mass * problem.cop_sigma).max(RANK_TOLERANCE * dmax.sqrt());
    let mut hessian = gram.clone();
    for j in 0..n {
        hessian[(j, j)] += lambda * lambda;
    }
    // Constraints in z = S^-1 (x - x0).
    let nl = problem.links.len();
    let mut eq = DMatrix::zeros(1, n);
    for k in 0..nl {
        eq[(0, 4 * k)] = s[4 * k];
    }
    let free_mass = problem.total_mass - problem.fixed_mass;
    let prior_mass: f64 = (0..nl).map(|k| problem.x0[4 * k]).sum();
    let eq_rhs = DVector::from_element(1, free_mass - prior_mass);
    let mut ineq = DMatrix::zeros(7 * nl, n);
    let mut ineq_rhs = DVector::zeros(7 * nl);
    for k in 0..nl {
        let (im, ih) = (4 * k, 4 * k + 1);
        // -m <= -m_min
        ineq[(7 * k, im)] = -s[im];
        ineq_rhs[7 * k] = -problem.min_mass[k] + problem.x0[im];
        for a in 0..3 {
            let (lo, hi) = (problem.com_lower[k][a], problem.com_upper[k][a]);
            let j = ih + a;
            // h - m c_hi <= 0
            let row = 7 * k + 1 + 2 * a;
            ineq[(row, j)] = s[j];
            ineq[(row, im)] = -hi * s[im];
            ineq_rhs[row] = -(problem.x0[j] - hi * problem.x0[im]);
            // m c_lo - h <= 0
            ineq[(row + 1, j)] = -s[j];
            ineq[(row + 1, im)] = lo * s[im];
            ineq_rhs[row + 1] = -(lo * problem.x0[im] - problem.x0[j]);
        }
    }
    // Feasible start: the prior scaled to the measured mass (CoMs unchanged).
    let k = free_mass / prior_mass;
    let mut z0 = DVector::zeros(n);
    for j in 0..n {
        z0[j] = (k - 1.0) * problem.x0[j] / s[j];
    }
    let qp = Qp {
        h: &hessian,
        f: &f,
        eq: &eq,
        eq_rhs: &eq_rhs,
        ineq: &ineq,
        ineq_rhs: &ineq_rhs,
    };
    let sol = qp
        .solve(z0)
        .map_err(|e| IdentError::new(format!("the constrained fit failed: {e}")))?;
    let mut x = problem.x0.clone();
    for j in 0..n {
        x[j] += s[j] * sol.z[j];
    }
    Ok(Fit {
        x,
        iterations: sol.iterations,
        active: sol.active,
        gram,
        lambda,
        hessian,
    })
}

/// `M^T M`, computing each entry of the upper triangle once (half the work of a
/// general product) from contiguous column dot products.
pub fn symmetric_gram(m: &DMatrix<f64>) -> DMatrix<f64> {
    let n = m.ncols();
    let mut g = DMatrix::zeros(n, n);
    for j in 0..n {
        let cj = m.column(j);
        for i in 0..=j {
            let v = m.column(i).dot(&cj);
            g[(i, j)] = v;
            g[(j, i)] = v;
        }
    }
    g
}

/// Connected groups of parameters coupled through the projector `P = V V^T` onto the
/// given directions (columns of `v`).
fn groups(
    problem: &StaticProblem,
    v: &DMatrix<f64>,
    model: &Model,
    kind: &str,
) -> Vec<ParameterGroup> {
    let n = v.nrows();
    if v.ncols() == 0 {
        return Vec::new();
    }
    let p = v * v.transpose();
    // A parameter belongs to the group if at least 5 % of it lies in the subspace;
    // two are coupled if their correlation within the subspace is above 5 %.
    let member: Vec<bool> = (0..n).map(|i| p[(i, i)] > 0.05).collect();
    let mut comp = vec![usize::MAX; n];
    let mut out = Vec::new();
    for start in 0..n {
        if !member[start] || comp[start] != usize::MAX {
            continue;
        }
        let id = out.len();
        let mut stack = vec![start];
        comp[start] = id;
        let mut params = Vec::new();
        while let Some(i) = stack.pop() {
            params.push(i);
            for j in 0..n {
                if member[j]
                    && comp[j] == usize::MAX
                    && p[(i, j)].abs() > 0.05 * (p[(i, i)] * p[(j, j)]).sqrt()
                {
                    comp[j] = id;
                    stack.push(j);
                }
            }
        }
        params.sort_unstable();
        // Directions mostly inside this group: singular values of its rows of the basis.
        let mut sub = DMatrix::zeros(params.len(), v.ncols());
        for (r, &i) in params.iter().enumerate() {
            sub.row_mut(r).copy_from(&v.row(i));
        }
        let directions = sub
            .singular_values()
            .iter()
            .filter(|&&x| x > 0.5)
            .count()
            .max(1);
        let mut links: Vec<usize> = params.iter().map(|&i| i / 4).collect();
        links.dedup();
        let bodies: Vec<usize> = links.iter().map(|&k| problem.bodies[k]).collect();
        let one_body = bodies.iter().all(|&b| b == bodies[0]);
        let why = if links.len() > 1 && one_body {
            "links welded to one body: only their combined mass and first moment are seen, not how \
             they split"
                .to_string()
        } else if params.iter().all(|&i| i % 4 != 0) {
            format!(
                "{kind}: first-moment components along directions that stay (nearly) vertical or \
                 do not move relative to each other in these poses"
            )
        } else {
            format!(
                "{kind}: the joints between these links do not move enough in these poses to tell \
                 them apart"
            )
        };
        out.push(ParameterGroup {
            parameters: params.iter().map(|&i| problem.names[i].clone()).collect(),
            links: links
                .iter()
                .map(|&k| problem.link_names[problem.links[k]].clone())
                .collect(),
            directions,
            why,
        });
        let _ = model;
    }
    out
}

/// Orthonormal basis (columns) of the eigenvectors of a symmetric matrix whose
/// eigenvalues satisfy `keep(sqrt(eigenvalue))`, and all singular values (descending).
fn eigen_split(
    gram: &DMatrix<f64>,
    keep: &dyn Fn(f64) -> bool,
) -> (DMatrix<f64>, Vec<f64>, SymmetricEigen<f64, nalgebra::Dyn>) {
    let n = gram.nrows();
    let eig = SymmetricEigen::new(gram.clone());
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let sv: Vec<f64> = order
        .iter()
        .map(|&i| eig.eigenvalues[i].max(0.0).sqrt())
        .collect();
    let cols: Vec<usize> = order
        .iter()
        .copied()
        .filter(|&i| keep(eig.eigenvalues[i].max(0.0).sqrt()))
        .collect();
    let mut v = DMatrix::zeros(n, cols.len());
    for (k, &i) in cols.iter().enumerate() {
        v.column_mut(k).copy_from(&eig.eigenvectors.column(i));
    }
    (v, sv, eig)
}

/// Orthonormal basis of the part of span(`v`) orthogonal to span(`q`) (both orthonormal).
fn complement(v: &DMatrix<f64>, q: &DMatrix<f64>) -> DMatrix<f64> {
    let n = v.nrows();
    if v.ncols() == 0 {
        return DMatrix::zeros(n, 0);
    }
    let m = if q.ncols() > 0 {
        v - q * (q.transpose() * v)
    } else {
        v.clone()
    };
    let g = &m * m.transpose();
    let (basis, _, _) = eigen_split(&g, &|s| s > 1e-4);
    basis
}

/// The structural null space: directions of the scaled parameters that the CoP
/// equations of no configuration at all can see, from `2n` generic configurations
/// (random base orientation and joints), so only the tree's regrouping is left.
pub fn structural_null_space(model: &Model, problem: &StaticProblem) -> DMatrix<f64> {
    let n = problem.unknowns();
    let mut rng = twinloop_random::SplitMix64(0x0057_A71C);
    let configs: Vec<StaticPose> = (0..(2 * n).max(8))
        .map(|_| StaticPose {
            q: twinloop_dynamics::configuration::random_configuration(model, &mut rng),
            cop: [0.0; 2],
            category: None,
        })
        .collect();
    let mut ws = StaticWorkspace::new(model, problem, configs.len());
    assemble(model, problem, &configs, &mut ws);
    let mut a_s = ws.a;
    for j in 0..n {
        a_s.column_mut(j).scale_mut(problem.scale[j]);
    }
    let gram = a_s.tr_mul(&a_s);
    let smax = (0..n).map(|j| gram[(j, j)]).fold(0.0, f64::max).sqrt();
    // Exact data: a tighter threshold than for measured poses.
    let (null, _, _) = eigen_split(&gram, &|s| s <= 1e-9 * smax);
    null
}

/// Identifiability from the eigen-decomposition of the scaled Gram matrix, with the
/// structural null space (from [`structural_null_space`]) told apart from what only
/// these poses miss.
pub fn identifiability(
    problem: &StaticProblem,
    model: &Model,
    gram: &DMatrix<f64>,
    lambda: f64,
    structural: &DMatrix<f64>,
) -> Identifiability {
    let n = gram.nrows();
    let dmax = (0..n).map(|j| gram[(j, j)]).fold(0.0, f64::max).sqrt();
    // The rank tolerance is relative to the largest singular value, bounded by the trace.
    let (_, sv, eig) = eigen_split(gram, &|_| false);
    let smax = sv.first().copied().unwrap_or(dmax);
    let tol = RANK_TOLERANCE * smax;
    let rank = sv.iter().filter(|&&s| s > tol).count();
    let well = sv.iter().filter(|&&s| s > lambda).count();
    let pick = |f: &dyn Fn(f64) -> bool| {
        let cols: Vec<usize> = (0..n)
            .filter(|&i| f(eig.eigenvalues[i].max(0.0).sqrt()))
            .collect();
        let mut v = DMatrix::zeros(n, cols.len());
        for (k, &i) in cols.iter().enumerate() {
            v.column_mut(k).copy_from(&eig.eigenvectors.column(i));
        }
        v
    };
    let null = complement(&pick(&|s| s <= tol), structural);
    let weak = complement(&pick(&|s| s > tol && s <= lambda), structural);
    let determined_fraction = (0..n)
        .map(|j| {
            let mut d = 0.0;
            for i in 0..n {
                let s2 = eig.eigenvalues[i].max(0.0);
                let fi = s2 / (s2 + lambda * lambda);
                d += fi * eig.eigenvectors[(j, i)].powi(2);
            }
            (problem.names[j].clone(), d)
        })
        .collect();
    let cond = if rank > 0 {
        smax / sv[rank - 1]
    } else {
        f64::INFINITY
    };
    let smin = sv.last().copied().unwrap_or(0.0);
    Identifiability {
        parameters: n,
        rank,
        well_determined: well,
        singular_values: sv.clone(),
        condition_number: cond,
        condition_number_full: if smin > 0.0 {
            smax / smin
        } else {
            f64::INFINITY
        },
        noise_level: lambda,
        structural_null: structural.ncols(),
        welded: {
            let mut groups: Vec<(usize, Vec<String>)> = Vec::new();
            for (k, &b) in problem.bodies.iter().enumerate() {
                let name = problem.link_names[problem.links[k]].clone();
                match groups.iter_mut().find(|(gb, _)| *gb == b) {
                    Some((_, g)) => g.push(name),
                    None => groups.push((b, vec![name])),
                }
            }
            groups
                .into_iter()
                .filter(|(_, g)| g.len() > 1)
                .map(|(_, g)| g)
                .collect()
        },
        structural_explanation: format!(
            "{} of the {n} parameters' directions cannot be determined by any static pose: from the \
             centre of pressure, a link's mass and its first moment along its joint axis move the CoM \
             exactly as its parent's parameters do, and links welded to one body act as one. Static \
             poses determine each subtree's first moment across its joint axes; the rest stays at the prior.",
            structural.ncols()
        ),
        unidentifiable: groups(problem, &null, model, "not excited by these poses"),
        poorly_identified: groups(problem, &weak, model, "excited below the noise"),
        determined_fraction,
    }
}

/// The GCOM (x, y) of a model with parameters `phi` (per description link) at `q`:
/// the CoM of seed 004, eq 6, `r = sum m_b r_b / M`, projected on the ground.
pub fn gcom(model: &Model, data: &mut Data, phi: &[f64], q: &[f64]) -> [f64; 2] {
    let g = static_com_regressor(model, data, q);
    let mut out = [0.0; 2];
    let mass: f64 = phi.iter().step_by(4).sum();
    for (r, o) in out.iter_mut().enumerate() {
        let mut s = 0.0;
        for (j, p) in phi.iter().enumerate() {
            s += g[(r, j)] * p;
        }
        *o = s / mass;
    }
    out
}

/// Identify the masses and CoMs of the chosen links from static poses (seed 004,
/// section 3.3, eq 8-9), the others kept at the prior.
pub fn identify_static(
    robot: &Description,
    model: &Model,
    poses: &[StaticPose],
    total_mass: f64,
    options: &StaticOptions,
) -> Result<StaticResult, IdentError> {
    let problem = StaticProblem::new(robot, model, total_mass, options)?;
    if poses.len() < problem.min_poses() {
        return Err(IdentError::new(format!(
            "{} poses give {} equations for the {} unknowns (mass and first moment) of {} links: \
             at least {} poses are needed (or identify fewer links)",
            poses.len(),
            2 * poses.len() + 1,
            problem.unknowns(),
            problem.links.len(),
            problem.min_poses()
        ))
        .option("poses"));
    }
    for (i, p) in poses.iter().enumerate() {
        if p.q.len() != model.nq {
            return Err(IdentError::new(format!(
                "the pose has {} coordinates, the model needs {}",
                p.q.len(),
                model.nq
            ))
            .at_row(i));
        }
    }
    let mut ws = StaticWorkspace::new(model, &problem, poses.len());
    assemble(model, &problem, poses, &mut ws);
    let fit = solve(&problem, &ws)?;
    Ok(report(robot, model, poses, &problem, &mut ws, &fit))
}

/// Posterior standard deviations of the scaled unknowns: `sigma_b^2 S H^-1 S`, with
/// `sigma_b` the CoP noise as a moment (total weight times the CoP's deviation).
struct Posterior {
    sigma_b: f64,
    hinv: DMatrix<f64>,
}

impl Posterior {
    fn new(problem: &StaticProblem, fit: &Fit) -> Posterior {
        let n = problem.unknowns();
        let hinv = fit
            .hessian
            .clone()
            .cholesky()
            .map(|c| c.inverse())
            .unwrap_or_else(|| DMatrix::zeros(n, n));
        Posterior {
            sigma_b: problem.total_mass * problem.cop_sigma,
            hinv,
        }
    }

    /// Standard deviation of unknown `j` in its own units.
    fn std(&self, problem: &StaticProblem, j: usize) -> f64 {
        self.sigma_b * problem.scale[j] * self.hinv[(j, j)].max(0.0).sqrt()
    }
}

/// The bounds of identified link `k` active at the fit, in words (the QP's seven
/// constraints per link: mass lower bound, then upper and lower per CoM axis).
fn active_bounds(fit: &Fit, k: usize) -> Vec<String> {
    let labels = ["com.x", "com.y", "com.z"];
    let mut at_bounds = Vec::new();
    for &i in &fit.active {
        if i / 7 == k {
            let r = i % 7;
            at_bounds.push(if r == 0 {
                "mass lower bound".to_string()
            } else {
                let a = (r - 1) / 2;
                let side = if (r - 1) % 2 == 0 { "upper" } else { "lower" };
                format!("{} {side} bound", labels[a])
            });
        }
    }
    at_bounds
}

/// The estimate of identified link `k` (description link `l`): mass and CoM with
/// their prior, standard deviations (the CoM's by the delta method for `c = h / m`),
/// bounds and how well the data determine them.
fn link_estimate(
    model: &Model,
    problem: &StaticProblem,
    fit: &Fit,
    posterior: &Posterior,
    identifiability: &Identifiability,
    (k, l): (usize, usize),
) -> LinkEstimate {
    let std = |j: usize| posterior.std(problem, j);
    let m = fit.x[4 * k];
    let h = Vector3::new(fit.x[4 * k + 1], fit.x[4 * k + 2], fit.x[4 * k + 3]);
    let c = h / m;
    let pm = problem.x0[4 * k];
    let pc = Vector3::new(
        problem.x0[4 * k + 1],
        problem.x0[4 * k + 2],
        problem.x0[4 * k + 3],
    ) / pm;
    let com_std = [0, 1, 2].map(|a| {
        let sh = std(4 * k + 1 + a);
        let sm = std(4 * k);
        ((sh / m).powi(2) + (c[a] * sm / m).powi(2)).sqrt()
    });
    LinkEstimate {
        name: model.links[l].name.clone(),
        prior_mass: pm,
        mass: m,
        mass_std: std(4 * k),
        prior_com: [pc.x, pc.y, pc.z],
        com: [c.x, c.y, c.z],
        com_std,
        com_lower: problem.com_lower[k].into(),
        com_upper: problem.com_upper[k].into(),
        at_bounds: active_bounds(fit, k),
        mass_determined: identifiability.determined_fraction[4 * k].1,
        first_moment_determined: [1, 2, 3]
            .map(|j| identifiability.determined_fraction[4 * k + j].1),
    }
}

/// The ground projections of the CoM per pose with the prior and the fitted
/// parameters, and their distances from the measured CoP, m.
struct GcomComparison {
    before: Vec<[f64; 2]>,
    after: Vec<[f64; 2]>,
    distance_before: Vec<f64>,
    distance_after: Vec<f64>,
}

fn compare_gcom(
    model: &Model,
    data: &mut Data,
    poses: &[StaticPose],
    prior: &[f64],
    phi: &[f64],
) -> GcomComparison {
    let mut gb = Vec::with_capacity(poses.len());
    let mut ga = Vec::with_capacity(poses.len());
    let mut db = Vec::with_capacity(poses.len());
    let mut da = Vec::with_capacity(poses.len());
    for p in poses {
        let b = gcom(model, data, prior, &p.q);
        let a = gcom(model, data, phi, &p.q);
        db.push(((b[0] - p.cop[0]).powi(2) + (b[1] - p.cop[1]).powi(2)).sqrt());
        da.push(((a[0] - p.cop[0]).powi(2) + (a[1] - p.cop[1]).powi(2)).sqrt());
        gb.push(b);
        ga.push(a);
    }
    GcomComparison {
        before: gb,
        after: ga,
        distance_before: db,
        distance_after: da,
    }
}

/// Turn a fit into the result: per-link estimates, GCOM distances, identifiability.
pub fn report(
    _robot: &Description,
    model: &Model,
    poses: &[StaticPose],
    problem: &StaticProblem,
    ws: &mut StaticWorkspace,
    fit: &Fit,
) -> StaticResult {
    let mut phi = problem.prior.clone();
    for (k, &l) in problem.links.iter().enumerate() {
        for j in 0..4 {
            phi[4 * l + j] = fit.x[4 * k + j];
        }
    }
    let posterior = Posterior::new(problem, fit);
    let structural = structural_null_space(model, problem);
    let identifiability = identifiability(problem, model, &fit.gram, fit.lambda, &structural);
    let links = (problem.links.iter().copied().enumerate())
        .map(|kl| link_estimate(model, problem, fit, &posterior, &identifiability, kl))
        .collect();
    let fixed_links = (0..model.links.len())
        .filter(|l| !problem.links.contains(l) && model.links[*l].inertia.mass > 0.0)
        .map(|l| (model.links[l].name.clone(), model.links[l].inertia.mass))
        .collect();
    let g = compare_gcom(model, &mut ws.data, poses, &problem.prior, &phi);
    StaticResult {
        model: model.name.clone(),
        poses: poses.len(),
        total_mass: problem.total_mass,
        prior_total_mass: problem.prior.iter().step_by(4).sum(),
        fixed_mass: problem.fixed_mass,
        links,
        fixed_links,
        before: Stats::of(&g.distance_before),
        after: Stats::of(&g.distance_after),
        gcom_distance_before: g.distance_before,
        gcom_distance_after: g.distance_after,
        identifiability,
        qp_iterations: fit.iterations,
        parameters: phi,
        gcom_before: g.before,
        gcom_after: g.after,
    }
}

/// The prior description with the identified links' `<inertial>` mass and origin
/// (xyz) replaced; everything else, the inertia tensors included, untouched.
pub fn adapted_robot(prior: &Description, result: &StaticResult) -> Description {
    let mut robot = prior.clone();
    for est in &result.links {
        if let Some(link) = robot.link_mut(&est.name)
            && let Some(inertial) = link.inertial.as_mut()
        {
            // The CoM is given in the link frame; the inertial origin's xyz is that point.
            inertial.mass = est.mass;
            inertial.origin.xyz = est.com;
        }
    }
    robot
}

/// A pose worth measuring next.
#[derive(Debug, Clone, Serialize)]
pub struct Suggestion {
    pub category: PoseCategory,
    /// The configuration to put the robot in (model order).
    pub q: Vec<f64>,
    /// Smallest singular value of the structurally identifiable part before and
    /// after adding this pose (and the ones suggested before it), kg m.
    pub smallest_singular_value_before: f64,
    pub smallest_singular_value_after: f64,
}

/// Statically stable candidate poses for planning, `per_category` of each category
/// the robot can stand in, from the virtual force plate on `robot` (the prior: only
/// the kinematics matter for what a pose excites).
pub fn candidate_poses(
    robot: &Description,
    model: &Model,
    per_category: usize,
    seed: u64,
) -> Result<Vec<(PoseCategory, Vec<f64>)>, IdentError> {
    let mut generator = PlateGenerator::new(robot, model, seed, &[], None)?;
    let mut out = Vec::new();
    for cat in PoseCategory::ALL {
        let mut plans = generator.systematic_plans(cat);
        plans.truncate(per_category / 2);
        plans.resize(per_category, Plan::Random);
        for plan in plans {
            match generator.pose(cat, plan, 3) {
                Ok((q, _, _)) => out.push((cat, q)),
                Err(_) => break, // the robot cannot stand in this category
            }
        }
    }
    Ok(out)
}

/// Greedily pick the candidates that most increase the smallest singular value of
/// the scaled regressor on the subspace the poses and the candidates can see
/// together (an E-optimal design): the poses that would most help the
/// worst-determined combination. Directions no candidate reaches (e.g. single
/// support on a robot that cannot stand on one foot) cannot be helped and are left out.
pub fn suggest_poses(
    model: &Model,
    problem: &StaticProblem,
    gram: &DMatrix<f64>,
    candidates: &[(PoseCategory, Vec<f64>)],
    picks: usize,
) -> Vec<Suggestion> {
    let n = problem.unknowns();
    if candidates.is_empty() || picks == 0 {
        return Vec::new();
    }
    let poses: Vec<StaticPose> = candidates
        .iter()
        .map(|(c, q)| StaticPose {
            q: q.clone(),
            cop: [0.0; 2],
            category: Some(*c),
        })
        .collect();
    let mut ws = StaticWorkspace::new(model, problem, poses.len());
    assemble(model, problem, &poses, &mut ws);
    let mut a_s = ws.a;
    for j in 0..n {
        a_s.column_mut(j).scale_mut(problem.scale[j]);
    }
    // The subspace the data and all candidates see together.
    let reach = gram + a_s.tr_mul(&a_s);
    let smax = (0..n).map(|j| reach[(j, j)]).fold(0.0, f64::max).sqrt();
    let (t, _, _) = eigen_split(&reach, &|s| s > RANK_TOLERANCE * smax);
    let b = &a_s * &t; // 2 rows per candidate
    let mut m = t.transpose() * gram * &t;
    let smallest = |m: &DMatrix<f64>| {
        m.clone()
            .symmetric_eigenvalues()
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .max(0.0)
            .sqrt()
    };
    let mut taken = vec![false; candidates.len()];
    let mut out = Vec::new();
    let floor = (problem.total_mass * problem.cop_sigma)
        .max(RANK_TOLERANCE * smax)
        .powi(2);
    for _ in 0..picks.min(candidates.len()) {
        let before = smallest(&m);
        // Information gain (Bayesian D-optimality, the noise as prior floor):
        // log det(I + b (M + floor I)^-1 b^T), which rewards exciting what is least known.
        let mut mf = m.clone();
        for i in 0..mf.nrows() {
            mf[(i, i)] += floor;
        }
        let minv = mf.cholesky().map(|c| c.inverse());
        let mut best: Option<(usize, f64, f64)> = None;
        for (c, &done) in taken.iter().enumerate() {
            if done {
                continue;
            }
            let rows = b.rows(2 * c, 2);
            let trial = &m + rows.transpose() * rows;
            let s = smallest(&trial);
            let gain = match &minv {
                Some(mi) => {
                    let k = DMatrix::identity(2, 2) + rows * mi * rows.transpose();
                    k.determinant().max(1e-300).ln()
                }
                None => rows.norm_squared(),
            };
            // First the smallest singular value; while it cannot move (several unseen
            // directions), the information gain decides.
            if best.is_none_or(|(_, bs, bg)| {
                s > bs * (1.0 + 1e-6) + 1e-300 || (s >= bs * (1.0 - 1e-6) && gain > bg)
            }) {
                best = Some((c, s, gain));
            }
        }
        let Some((c, after, _)) = best else { break };
        taken[c] = true;
        let rows = b.rows(2 * c, 2);
        m += rows.transpose() * rows;
        out.push(Suggestion {
            category: candidates[c].0,
            q: candidates[c].1.clone(),
            smallest_singular_value_before: before,
            smallest_singular_value_after: after,
        });
    }
    out
}
