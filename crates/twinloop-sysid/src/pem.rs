//! Prediction-error method (seed 003, section 7.2: the final model "estimated by
//! the prediction error method" from an initial model, as MATLAB's `ssest`).
//!
//! The cost is the mean weighted one-step prediction error of the Kalman
//! predictor of the innovations form,
//!
//! ```text
//! x^(k+1) = A x^(k) + B u(k) + K e(k),   e(k) = y(k) - C x^(k) - D u(k)
//! V = (1/N) sum_k e(k)^T W e(k)
//! ```
//!
//! minimised by Levenberg-Marquardt with an exact Jacobian from the sensitivity
//! recursion (the predictor differentiated along each parameter direction:
//! `dx(k+1) = (A - KC) dx + dA x^ + dB u + dK e - K (dC x^ + dD u)`,
//! `de = -(C dx + dC x^ + dD u)`).
//!
//! **Parameterisation.** All entries of `A, B, C, K` (and `D`, `x0` when asked)
//! are parameters, but a change of state basis `T = I + X` leaves the predictor
//! unchanged, so the `n^2` directions `(XA - AX, XB, -CX, XK, 0, X x0)` do not
//! change the cost and make the plain full parameterisation singular. At every
//! iteration the search is restricted to the orthogonal complement of those
//! directions at the current model ("data-driven local coordinates", McKelvey):
//! the step has no component that only rotates the state, the reduced Jacobian
//! has full column rank for a minimal model, and the model stays a full,
//! unstructured matrix set, which is better conditioned than canonical forms
//! whose parameters can be far apart in scale. The damped normal equations
//! `(J^T J + lambda diag(J^T J)) d = -J^T r` (Marquardt's scaling) are solved by
//! Cholesky: the number of parameters is small beside the number of residuals,
//! the damping keeps the system positive definite, and every step is accepted
//! only if the exactly evaluated cost decreases, so the result is never worse
//! than the initial model. Steps that make the predictor `A - KC` unstable are
//! rejected.

use crate::data::IoData;
use crate::error::{Result, SysidError};
use crate::linalg::{HouseholderQr, gemm_tn};
use crate::ss::{StateSpace, spectral_radius};
use nalgebra::{DMatrix, DVector};

/// How the outputs' prediction errors are weighted in the cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputWeight {
    /// `W = I`: the plain sum of squared errors.
    Identity,
    /// `W = Lambda0^-1`, the inverse of the initial model's innovation covariance
    /// (fixed during the search): outputs with larger noise count less.
    InverseNoise,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PemOptions {
    pub max_iterations: usize,
    /// Stop when the Gauss-Newton step is expected to lower the cost by less than
    /// this fraction.
    pub tolerance: f64,
    /// Stop when an accepted step lowered the cost by less than this fraction (the
    /// search crawls along a flat valley, as in over-parameterised models).
    pub min_decrease: f64,
    /// Estimate a feedthrough `D` (else it stays as in the initial model).
    pub feedthrough: bool,
    /// Estimate the initial state (else it stays at the given one, zero by default).
    pub estimate_x0: bool,
    pub weight: OutputWeight,
    /// Keep `A` itself stable (MATLAB's `ssestOptions.EnforceStability`): a step that
    /// puts an eigenvalue of `A` on or outside the unit circle is rejected like one
    /// that destabilises the predictor. Off by default, as in MATLAB: the prediction
    /// error only needs `A - KC` stable, and on data that barely excite some modes
    /// the search can trade a slightly lower one-step error for an unstable `A`,
    /// whose simulation diverges (seen on the lab17 walking record).
    pub enforce_stability: bool,
    /// Output-error structure (MATLAB's `ssestOptions.Focus = 'simulation'`): `K` is
    /// fixed at zero, so the one-step predictor is the simulation and the cost is the
    /// simulation error. The predictor's stability is then `A`'s, so the search also
    /// keeps `A` stable. Off by default (`K` estimated, the innovations form).
    pub output_error: bool,
    /// Largest pole radius a step may leave on `A` when `A` is kept stable
    /// (`enforce_stability` or `output_error`); 1 = plain stability. Below 1 it is a
    /// damping margin: on periodic data the search otherwise drives a lightly damped
    /// mode onto the unit circle, an undamped oscillator that buys a little fit.
    pub max_pole_radius: f64,
}

impl Default for PemOptions {
    fn default() -> Self {
        PemOptions {
            max_iterations: 100,
            tolerance: 1e-7,
            min_decrease: 1e-8,
            feedthrough: false,
            estimate_x0: false,
            weight: OutputWeight::Identity,
            enforce_stability: false,
            output_error: false,
            max_pole_radius: 1.0,
        }
    }
}

/// Reported after every iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PemProgress {
    pub iteration: usize,
    pub max_iterations: usize,
    pub cost: f64,
    pub lambda: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct PemResult {
    pub model: StateSpace,
    pub x0: DVector<f64>,
    /// Weighted prediction cost `V` of the initial model.
    pub initial_cost: f64,
    /// `V` of the returned model (never above `initial_cost`).
    pub final_cost: f64,
    /// Plain `(1/N) sum |e|^2` of the initial and the returned model.
    pub initial_prediction_cost: f64,
    pub final_prediction_cost: f64,
    pub iterations: usize,
    /// Parameters free in each step (all entries minus the `n^2` basis changes).
    pub free_parameters: usize,
    /// Why the search stopped.
    pub termination: String,
    /// `V` after each accepted iteration, starting with the initial one.
    pub cost_history: Vec<f64>,
}

/// Where each matrix sits in the parameter vector.
#[derive(Debug, Clone, Copy)]
struct Layout {
    n: usize,
    nu: usize,
    ny: usize,
    nd: usize, // inputs with a feedthrough parameter (nu or 0)
    x0: bool,
}

impl Layout {
    /// `[A B K]` column-major, then `[C D]` column-major, then `x0`.
    fn len(&self) -> usize {
        self.n * (self.n + self.nu + self.ny)
            + self.ny * (self.n + self.nd)
            + if self.x0 { self.n } else { 0 }
    }
    fn off_cd(&self) -> usize {
        self.n * (self.n + self.nu + self.ny)
    }
    fn off_x0(&self) -> usize {
        self.off_cd() + self.ny * (self.n + self.nd)
    }

    fn pack(&self, m: &StateSpace, x0: &DVector<f64>) -> DVector<f64> {
        let (n, nu, ny) = (self.n, self.nu, self.ny);
        let mut th = DVector::zeros(self.len());
        for c in 0..n + nu + ny {
            for r in 0..n {
                th[r + n * c] = if c < n {
                    m.a[(r, c)]
                } else if c < n + nu {
                    m.b[(r, c - n)]
                } else {
                    m.k[(r, c - n - nu)]
                };
            }
        }
        let o = self.off_cd();
        for c in 0..n + self.nd {
            for r in 0..ny {
                th[o + r + ny * c] = if c < n { m.c[(r, c)] } else { m.d[(r, c - n)] };
            }
        }
        if self.x0 {
            th.rows_mut(self.off_x0(), n).copy_from(x0);
        }
        th
    }

    fn unpack(
        &self,
        th: &DVector<f64>,
        template: &StateSpace,
        x0: &mut DVector<f64>,
    ) -> StateSpace {
        let (n, nu, ny) = (self.n, self.nu, self.ny);
        let mut m = template.clone();
        for c in 0..n + nu + ny {
            for r in 0..n {
                let v = th[r + n * c];
                if c < n {
                    m.a[(r, c)] = v;
                } else if c < n + nu {
                    m.b[(r, c - n)] = v;
                } else {
                    m.k[(r, c - n - nu)] = v;
                }
            }
        }
        let o = self.off_cd();
        for c in 0..n + self.nd {
            for r in 0..ny {
                let v = th[o + r + ny * c];
                if c < n {
                    m.c[(r, c)] = v;
                } else {
                    m.d[(r, c - n)] = v;
                }
            }
        }
        if self.x0 {
            x0.copy_from(&th.rows(self.off_x0(), n));
        }
        m
    }

    /// The `n^2` directions of a change of state basis at `(m, x0)`, one per column.
    fn basis_change_directions(&self, m: &StateSpace, x0: &DVector<f64>) -> DMatrix<f64> {
        let (n, nu, ny) = (self.n, self.nu, self.ny);
        let o = self.off_cd();
        let mut t = DMatrix::zeros(self.len(), n * n);
        for s in 0..n {
            for r in 0..n {
                let col = r + n * s; // X = E_rs
                // dA = X A - A X: row r gains A[s, :], column s loses A[:, r].
                for c in 0..n {
                    t[(r + n * c, col)] += m.a[(s, c)];
                    t[(c + n * s, col)] -= m.a[(c, r)];
                }
                for c in 0..nu {
                    t[(r + n * (n + c), col)] += m.b[(s, c)];
                }
                for c in 0..ny {
                    t[(r + n * (n + nu + c), col)] += m.k[(s, c)];
                }
                // dC = -C X: column s of dC is -C[:, r].
                for i in 0..ny {
                    t[(o + i + ny * s, col)] -= m.c[(i, r)];
                }
                if self.x0 {
                    t[(self.off_x0() + r, col)] += x0[s];
                }
            }
        }
        t
    }
}

/// Work space of the predictor and the sensitivity recursion, allocated once.
struct Workspace {
    xs: DMatrix<f64>, // n x N: x^(k)
    e: DMatrix<f64>,  // ny x N: e(k)
    r: DVector<f64>,  // N ny: weighted residuals
    j: DMatrix<f64>,  // N ny x m: Jacobian of r
    s: DMatrix<f64>,  // n x m: dx^(k)
    s_next: DMatrix<f64>,
    dy: DMatrix<f64>,  // ny x m
    wdy: DMatrix<f64>, // ny x m
    vin: DMatrix<f64>, // (n+nu+ny+n+nd) x chunk: [z; w] per step
    f: DMatrix<f64>,   // n m x chunk
    g: DMatrix<f64>,   // ny m x chunk
    abar: DMatrix<f64>,
    x: DVector<f64>,
    xn: DVector<f64>,
    ek: DVector<f64>,
}

const CHUNK: usize = 64;

impl Workspace {
    fn new(l: &Layout, n_samples: usize, m: usize) -> Workspace {
        let (n, nu, ny) = (l.n, l.nu, l.ny);
        Workspace {
            xs: DMatrix::zeros(n, n_samples),
            e: DMatrix::zeros(ny, n_samples),
            r: DVector::zeros(n_samples * ny),
            j: DMatrix::zeros(n_samples * ny, m),
            s: DMatrix::zeros(n, m),
            s_next: DMatrix::zeros(n, m),
            dy: DMatrix::zeros(ny, m),
            wdy: DMatrix::zeros(ny, m),
            vin: DMatrix::zeros(n + nu + ny + n + l.nd, CHUNK),
            f: DMatrix::zeros(n * m, CHUNK),
            g: DMatrix::zeros(ny * m, CHUNK),
            abar: DMatrix::zeros(n, n),
            x: DVector::zeros(n),
            xn: DVector::zeros(n),
            ek: DVector::zeros(ny),
        }
    }
}

/// Run the predictor: fills `xs`, `e` and the weighted residuals `r = L^T e`;
/// returns `sum |r|^2` (infinite if the predictor blows up).
fn predict(
    model: &StateSpace,
    x0: &DVector<f64>,
    data: &IoData,
    lt: &DMatrix<f64>,
    ws: &mut Workspace,
) -> f64 {
    let ny = model.ny();
    ws.x.copy_from(x0);
    let mut sum = 0.0;
    for k in 0..data.len() {
        let uk = data.u.column(k);
        ws.xs.set_column(k, &ws.x);
        ws.ek.copy_from(&data.y.column(k));
        ws.ek.gemv(-1.0, &model.c, &ws.x, 1.0);
        ws.ek.gemv(-1.0, &model.d, &uk, 1.0);
        ws.e.set_column(k, &ws.ek);
        for o in 0..ny {
            let mut v = 0.0;
            for i in 0..ny {
                v += lt[(o, i)] * ws.ek[i];
            }
            ws.r[k * ny + o] = v;
            sum += v * v;
        }
        ws.xn.gemv(1.0, &model.a, &ws.x, 0.0);
        ws.xn.gemv(1.0, &model.b, &uk, 1.0);
        ws.xn.gemv(1.0, &model.k, &ws.ek, 1.0);
        std::mem::swap(&mut ws.x, &mut ws.xn);
        if !sum.is_finite() {
            return f64::INFINITY;
        }
    }
    sum
}

/// The basis rearranged for the sensitivity recursion: `P2` maps `w = [x^; u]` to
/// `dC x^ + dD u` and `Pf = [P1, -(K applied blockwise to P2)]` maps `[z; w]`
/// (`z = [x^; u; e]`) to `dA x^ + dB u + dK e - K(dC x^ + dD u)`, every direction at
/// once (direction `j` in rows `n j..n (j+1)`, resp. `ny j..ny (j+1)`).
fn recursion_maps(
    model: &StateSpace,
    l: &Layout,
    basis: &DMatrix<f64>,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let (n, nu, ny, nd) = (l.n, l.nu, l.ny, l.nd);
    let m = basis.ncols();
    let nz = n + nu + ny;
    let nw = n + nd;
    // P1[(r + n j), c] = basis[c n + r, j]; P2[(o + ny j), c] = basis[off + c ny + o, j].
    let mut p2 = DMatrix::zeros(ny * m, nw);
    let o2 = l.off_cd();
    for c in 0..nw {
        for j in 0..m {
            for o in 0..ny {
                p2[(o + ny * j, c)] = basis[(o2 + c * ny + o, j)];
            }
        }
    }
    // Pf = [P1, -(K applied blockwise to P2)].
    let mut pf = DMatrix::zeros(n * m, nz + nw);
    for c in 0..nz {
        for j in 0..m {
            for r in 0..n {
                pf[(r + n * j, c)] = basis[(c * n + r, j)];
            }
        }
    }
    for c in 0..nw {
        for j in 0..m {
            for r in 0..n {
                let mut v = 0.0;
                for o in 0..ny {
                    v += model.k[(r, o)] * p2[(o + ny * j, c)];
                }
                pf[(r + n * j, nz + c)] = -v;
            }
        }
    }
    (pf, p2)
}

/// The recursion's inputs `[z; w]` of steps `k0..k0 + len` into the columns of `ws.vin`.
fn load_chunk_inputs(l: &Layout, data: &IoData, k0: usize, len: usize, ws: &mut Workspace) {
    let (n, nu, ny, nd) = (l.n, l.nu, l.ny, l.nd);
    let nz = n + nu + ny;
    for t in 0..len {
        let k = k0 + t;
        let mut col = ws.vin.column_mut(t);
        for i in 0..n {
            col[i] = ws.xs[(i, k)];
            col[nz + i] = ws.xs[(i, k)];
        }
        for i in 0..nu {
            col[n + i] = data.u[(i, k)];
        }
        for i in 0..ny {
            col[n + nu + i] = ws.e[(i, k)];
        }
        for i in 0..nd {
            col[nz + n + i] = data.u[(i, k)];
        }
    }
}

/// The Jacobian of the weighted residuals along the columns of `basis` (after
/// `predict` ran at the same model). Per step only two small products are left:
/// the inputs of the recursion for a chunk of steps are formed at once by
/// `F = Pf [z; w]` and `G = P2 w` (`z = [x^; u; e]`, `w = [x^; u]`), where `Pf`, `P2`
/// rearrange the basis so that column `k` of `F` is `dA x^ + dB u + dK e - K(dC x^ + dD u)`
/// for every direction at once.
fn jacobian(
    model: &StateSpace,
    l: &Layout,
    basis: &DMatrix<f64>,
    data: &IoData,
    lt: &DMatrix<f64>,
    ws: &mut Workspace,
) {
    let (n, nu, ny, nd) = (l.n, l.nu, l.ny, l.nd);
    let m = basis.ncols();
    let nz = n + nu + ny;
    let nw = n + nd;
    let (pf, p2) = recursion_maps(model, l, basis);
    ws.abar.copy_from(&model.a);
    ws.abar.gemm(-1.0, &model.k, &model.c, 1.0);
    // dx(0): the initial-state directions.
    ws.s.fill(0.0);
    if l.x0 {
        let ox = l.off_x0();
        for j in 0..m {
            for r in 0..n {
                ws.s[(r, j)] = basis[(ox + r, j)];
            }
        }
    }
    let n_samples = data.len();
    let mut k0 = 0;
    while k0 < n_samples {
        let len = CHUNK.min(n_samples - k0);
        load_chunk_inputs(l, data, k0, len, ws);
        ws.f.view_mut((0, 0), (n * m, len)).gemm(
            1.0,
            &pf,
            &ws.vin.view((0, 0), (nz + nw, len)),
            0.0,
        );
        ws.g.view_mut((0, 0), (ny * m, len))
            .gemm(1.0, &p2, &ws.vin.view((nz, 0), (nw, len)), 0.0);
        for t in 0..len {
            let k = k0 + t;
            // dyhat = C dx + dC x^ + dD u
            ws.dy
                .copy_from_slice(&ws.g.as_slice()[t * ny * m..(t + 1) * ny * m]);
            ws.dy.gemm(1.0, &model.c, &ws.s, 1.0);
            // rows of J: d r = -L^T dyhat
            ws.wdy.gemm(-1.0, lt, &ws.dy, 0.0);
            for j in 0..m {
                for o in 0..ny {
                    ws.j[(k * ny + o, j)] = ws.wdy[(o, j)];
                }
            }
            // dx(k+1) = (A - KC) dx + F(k)
            ws.s_next
                .copy_from_slice(&ws.f.as_slice()[t * n * m..(t + 1) * n * m]);
            ws.s_next.gemm(1.0, &ws.abar, &ws.s, 1.0);
            std::mem::swap(&mut ws.s, &mut ws.s_next);
        }
        k0 += len;
    }
}

/// Refine a state-space model (seed 003, eq 9) by the prediction-error method of
/// its section 7.2 (see the module notes). `x0` is the initial state of the record (zero when `None`); it is
/// estimated only with `estimate_x0`. `progress` is called after every iteration.
pub fn pem(
    data: &IoData,
    initial: &StateSpace,
    x0: Option<&DVector<f64>>,
    opts: &PemOptions,
    progress: &mut dyn FnMut(&PemProgress),
) -> Result<PemResult> {
    let (l, m) = parameter_layout(data, initial, opts)?;
    let (n, ny) = (l.n, l.ny);
    let x0v = x0.cloned().unwrap_or_else(|| DVector::zeros(n));
    if x0v.len() != n {
        return Err(SysidError::order("the initial state has the wrong length"));
    }
    let oe_initial;
    let initial = if opts.output_error {
        oe_initial = StateSpace {
            k: DMatrix::zeros(n, ny),
            ..initial.clone()
        };
        &oe_initial
    } else {
        initial
    };
    check_initial_stability(initial, opts)?;
    let mut ws = Workspace::new(&l, data.len(), m);
    let lt = output_weight(initial, &x0v, data, opts, &mut ws)?;
    let nf = data.len() as f64;
    let search = Search {
        data,
        l,
        lt,
        opts,
        n_res: data.len() * ny,
        m,
    };
    let mut it = Iterate {
        model: initial.clone(),
        x0: x0v,
        cost: 0.0,
        lambda: 1e-3,
        nu_fac: 2.0,
    };
    it.cost = predict(&it.model, &it.x0, data, &search.lt, &mut ws);
    let initial_cost = it.cost / nf;
    let mut history = vec![initial_cost];
    let (iterations, termination) = search.minimise(&mut it, &mut ws, &mut history, progress);
    let Iterate {
        mut model,
        x0: x0v,
        cost,
        ..
    } = it;
    let final_cost = cost / nf;
    let (_, e) = model.predictor_states(data, Some(&x0v))?;
    model.noise_covariance = &e * e.transpose() / nf;
    let final_prediction_cost = e.norm_squared() / nf;
    let (_, e0) = initial.predictor_states(data, x0)?;
    Ok(PemResult {
        model,
        x0: x0v,
        initial_cost,
        final_cost,
        initial_prediction_cost: e0.norm_squared() / nf,
        final_prediction_cost,
        iterations,
        free_parameters: m,
        termination,
        cost_history: history,
    })
}

/// The parameter layout for `initial` and `opts`, and the number of free
/// parameters of a step (all minus the `n^2` basis changes, minus `K` for an
/// output-error fit); errors when the record does not fit the model or has fewer
/// prediction errors than free parameters.
fn parameter_layout(
    data: &IoData,
    initial: &StateSpace,
    opts: &PemOptions,
) -> Result<(Layout, usize)> {
    let (n, nu, ny) = (initial.n(), initial.nu(), initial.ny());
    if data.nu() != nu || data.ny() != ny {
        return Err(SysidError::data(format!(
            "the model has {nu} inputs and {ny} outputs, the record {} and {}",
            data.nu(),
            data.ny()
        )));
    }
    if n == 0 {
        return Err(SysidError::order("the initial model has no states"));
    }
    data.check_excitation()?;
    let l = Layout {
        n,
        nu,
        ny,
        nd: if opts.feedthrough { nu } else { 0 },
        x0: opts.estimate_x0,
    };
    let p = l.len();
    // Output error: the n ny entries of K are held at zero as well.
    let m = p - n * n - if opts.output_error { n * ny } else { 0 };
    let n_res = data.len() * ny;
    if n_res <= m {
        return Err(SysidError::data(format!(
            "{} samples of {ny} outputs give {n_res} prediction errors for {m} free parameters: \
             the prediction-error fit needs more samples than parameters",
            data.len()
        )));
    }
    Ok((l, m))
}

/// The search starts from a model whose predictor `A - KC` is stable and, when `A`
/// is kept stable, whose `A` is inside `max_pole_radius` (itself in (0, 1]).
fn check_initial_stability(initial: &StateSpace, opts: &PemOptions) -> Result<()> {
    if !(opts.max_pole_radius > 0.0 && opts.max_pole_radius <= 1.0) {
        return Err(SysidError::order(format!(
            "max_pole_radius must be in (0, 1], got {}",
            opts.max_pole_radius
        )));
    }
    if (opts.enforce_stability || opts.output_error)
        && !spectral_radius(&initial.a).is_some_and(|r| r < opts.max_pole_radius)
    {
        return Err(SysidError::numerical(format!(
            "enforce_stability: the initial model's A has a pole radius at or above {}; start \
             from a model inside it",
            opts.max_pole_radius
        )));
    }
    if !spectral_radius(&(&initial.a - &initial.k * &initial.c)).is_some_and(|r| r < 1.0) {
        return Err(SysidError::numerical(
            "the initial model's predictor A - KC is unstable (or not finite): the prediction errors \
             grow without bound; start from a model with a stable predictor",
        ));
    }
    Ok(())
}

/// The weight factor `L^T` (`W = L L^T`) of the cost: the identity, or for
/// [`OutputWeight::InverseNoise`] the Cholesky factor of the inverse of the initial
/// model's innovation covariance. Runs the initial predictor unweighted into `ws`.
fn output_weight(
    initial: &StateSpace,
    x0: &DVector<f64>,
    data: &IoData,
    opts: &PemOptions,
    ws: &mut Workspace,
) -> Result<DMatrix<f64>> {
    let ny = initial.ny();
    let eye = DMatrix::identity(ny, ny);
    let sum0 = predict(initial, x0, data, &eye, ws);
    if !sum0.is_finite() {
        return Err(SysidError::numerical(
            "the initial model's prediction errors are not finite",
        ));
    }
    let nf = data.len() as f64;
    Ok(match opts.weight {
        OutputWeight::Identity => eye,
        OutputWeight::InverseNoise => {
            let lam = &ws.e * ws.e.transpose() / nf;
            let inv = lam.clone().cholesky().map(|c| c.inverse()).ok_or_else(|| {
                SysidError::numerical(
                    "the initial innovation covariance is singular: cannot weight by it",
                )
            })?;
            inv.cholesky()
                .ok_or_else(|| {
                    SysidError::numerical("inverse noise covariance is not positive definite")
                })?
                .l()
                .transpose()
        }
    })
}

/// What stays fixed during the search: the record, the layout, the weight factor
/// `L^T`, the options, and the numbers of residuals and free parameters.
struct Search<'a> {
    data: &'a IoData,
    l: Layout,
    lt: DMatrix<f64>,
    opts: &'a PemOptions,
    n_res: usize,
    m: usize,
}

/// Where the search stands: the model and its initial state, its cost `sum |r|^2`,
/// and Marquardt's damping `lambda` with its growth factor.
struct Iterate {
    model: StateSpace,
    x0: DVector<f64>,
    cost: f64,
    lambda: f64,
    nu_fac: f64,
}

/// Expected cost decrease `-g^T d - d^T H d / 2` of the step `d` on the quadratic model.
fn predicted_decrease(h: &DMatrix<f64>, g: &DVector<f64>, step: &DVector<f64>) -> f64 {
    -g.dot(step) - 0.5 * step.dot(&(h * step))
}

impl Search<'_> {
    /// Levenberg-Marquardt iterations from `it` until convergence, the iteration
    /// limit or exhausted damping; `history` gets the cost after every accepted
    /// step. Returns the number of iterations and why the search stopped.
    fn minimise(
        &self,
        it: &mut Iterate,
        ws: &mut Workspace,
        history: &mut Vec<f64>,
        progress: &mut dyn FnMut(&PemProgress),
    ) -> (usize, String) {
        let opts = self.opts;
        let nf = self.data.len() as f64;
        let mut iterations = 0;
        let mut termination = format!("reached the iteration limit ({})", opts.max_iterations);
        let mut trial_x0 = it.x0.clone();
        let mut ws_trial = Workspace::new(&self.l, self.data.len(), 0);
        while iterations < opts.max_iterations {
            let basis = self.local_basis(&it.model, &it.x0); // p x m
            // predict() left xs, e, r at the current model.
            predict(&it.model, &it.x0, self.data, &self.lt, ws);
            jacobian(&it.model, &self.l, &basis, self.data, &self.lt, ws);
            let (h, g) = self.normal_equations(ws);
            let diag: Vec<f64> = (0..self.m).map(|i| h[(i, i)]).collect();
            let dmax = diag.iter().fold(0.0f64, |a, &b| a.max(b));
            if dmax == 0.0 || g.amax() <= 1e-14 * it.cost.max(f64::MIN_POSITIVE) {
                termination = "the gradient vanished".to_string();
                break;
            }
            let dfloor = dmax * 1e-12;
            // Expected improvement of a (barely damped) Gauss-Newton step.
            if let Some(step) = damped_step(&h, &g, &diag, 1e-10, dfloor) {
                let pred = predicted_decrease(&h, &g, &step);
                if pred <= opts.tolerance * it.cost {
                    termination = format!(
                        "converged: a Gauss-Newton step would lower the cost by less than {:.0e}",
                        opts.tolerance
                    );
                    break;
                }
            }
            let step = DampedSystem {
                h: &h,
                g: &g,
                diag: &diag,
                floor: dfloor,
                basis: &basis,
            };
            let Some(crawled) = self.damped_search(it, &step, &mut trial_x0, &mut ws_trial) else {
                termination = "no step lowers the cost (damping exhausted)".to_string();
                break;
            };
            iterations += 1;
            history.push(it.cost / nf);
            progress(&PemProgress {
                iteration: iterations,
                max_iterations: opts.max_iterations,
                cost: it.cost / nf,
                lambda: it.lambda,
            });
            if crawled {
                termination = format!(
                    "converged: the last step lowered the cost by less than {:.0e}",
                    opts.min_decrease
                );
                break;
            }
        }
        (iterations, termination)
    }

    /// Local coordinates at `(model, x0)`: an orthonormal basis of the complement of
    /// the basis-change directions (and, for an output-error fit, of `K`'s
    /// coordinates, so that `K` stays zero).
    fn local_basis(&self, model: &StateSpace, x0: &DVector<f64>) -> DMatrix<f64> {
        let (n, nu, ny) = (self.l.n, self.l.nu, self.l.ny);
        let mut t = self.l.basis_change_directions(model, x0);
        if self.opts.output_error {
            // Hold K at zero: its coordinates join the directions the step avoids.
            let base = t.ncols();
            t = t.resize_horizontally(base + n * ny, 0.0);
            for c in 0..ny {
                for r in 0..n {
                    t[(r + n * (n + nu + c), base + r + n * c)] = 1.0;
                }
            }
        }
        HouseholderQr::new(t).complement_basis()
    }

    /// Gauss-Newton's `H = J^T J` and gradient `g = J^T r` from the Jacobian and
    /// residuals in `ws`.
    fn normal_equations(&self, ws: &Workspace) -> (DMatrix<f64>, DVector<f64>) {
        let (m, n_res) = (self.m, self.n_res);
        let mut h = DMatrix::zeros(m, m);
        gemm_tn(
            &mut h.view_mut((0, 0), (m, m)),
            1.0,
            &ws.j,
            (0, 0),
            (n_res, m),
            &ws.j.view((0, 0), (n_res, m)),
            0.0,
        );
        let g = ws.j.tr_mul(&ws.r);
        (h, g)
    }

    /// Whether a trial model may be taken: a stable predictor `A - KC` and, when `A`
    /// is kept stable, `A` inside `max_pole_radius`.
    fn admissible(&self, trial: &StateSpace) -> bool {
        let opts = self.opts;
        spectral_radius(&(&trial.a - &trial.k * &trial.c)).is_some_and(|r| r < 1.0)
            && (!(opts.enforce_stability || opts.output_error)
                || spectral_radius(&trial.a).is_some_and(|r| r < opts.max_pole_radius))
    }

    /// Raise the damping until a step lowers the exactly evaluated cost, and take it
    /// (Nielsen's update of `lambda`). Returns whether the decrease was below
    /// `min_decrease` (the search crawls), or `None` when the damping is exhausted.
    fn damped_search(
        &self,
        it: &mut Iterate,
        sys: &DampedSystem,
        trial_x0: &mut DVector<f64>,
        ws_trial: &mut Workspace,
    ) -> Option<bool> {
        loop {
            let Some(step) = damped_step(sys.h, sys.g, sys.diag, it.lambda, sys.floor) else {
                it.lambda *= it.nu_fac;
                it.nu_fac *= 2.0;
                if it.lambda > 1e20 {
                    return None;
                }
                continue;
            };
            let mut th = self.l.pack(&it.model, &it.x0);
            th.gemv(1.0, sys.basis, &step, 1.0);
            let trial = self.l.unpack(&th, &it.model, trial_x0);
            let new_cost = if self.admissible(&trial) {
                predict(&trial, trial_x0, self.data, &self.lt, ws_trial)
            } else {
                f64::INFINITY
            };
            let pred = predicted_decrease(sys.h, sys.g, &step);
            if new_cost < it.cost {
                let rho = if pred > 0.0 {
                    (it.cost - new_cost) / (2.0 * pred)
                } else {
                    1.0
                };
                it.lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                it.nu_fac = 2.0;
                it.model = trial;
                it.x0.copy_from(trial_x0);
                let small = it.cost - new_cost <= self.opts.min_decrease * it.cost;
                it.cost = new_cost;
                return Some(small);
            }
            it.lambda *= it.nu_fac;
            it.nu_fac *= 2.0;
            if it.lambda > 1e20 {
                return None;
            }
        }
    }
}

/// One iteration's damped normal equations in local coordinates: `H`, `g`, the
/// diagonal Marquardt scales by (floored at `floor`), and the basis that maps a
/// step back to the full parameters.
struct DampedSystem<'a> {
    h: &'a DMatrix<f64>,
    g: &'a DVector<f64>,
    diag: &'a [f64],
    floor: f64,
    basis: &'a DMatrix<f64>,
}

/// Solve `(H + lambda diag(max(H_ii, floor))) d = -g` by Cholesky.
fn damped_step(
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    diag: &[f64],
    lambda: f64,
    floor: f64,
) -> Option<DVector<f64>> {
    let mut a = h.clone();
    for (i, &d) in diag.iter().enumerate() {
        a[(i, i)] += lambda * d.max(floor);
    }
    let chol = a.cholesky()?;
    let step = -chol.solve(g);
    step.iter().all(|x| x.is_finite()).then_some(step)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toy() -> (StateSpace, IoData) {
        let a = DMatrix::from_row_slice(3, 3, &[0.6, 0.3, 0.0, -0.3, 0.6, 0.1, 0.0, 0.2, -0.4]);
        let b = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.5, -1.0, 0.0, 0.7]);
        let c = DMatrix::from_row_slice(2, 3, &[1.0, 0.5, 0.0, 0.0, -0.3, 1.0]);
        let k = DMatrix::from_row_slice(3, 2, &[0.2, 0.0, 0.1, 0.1, 0.0, -0.2]);
        let d = DMatrix::from_row_slice(2, 2, &[0.1, 0.0, -0.2, 0.3]);
        let m = StateSpace {
            a,
            b,
            c,
            d,
            k,
            noise_covariance: DMatrix::identity(2, 2),
            sample_time: None,
        };
        let n = 80;
        let u = DMatrix::from_fn(2, n, |i, t| ((t * (i + 2)) as f64 * 0.71).sin());
        let y = DMatrix::from_fn(2, n, |i, t| ((t + 3 * i) as f64 * 0.37).cos());
        let data = IoData::new(
            vec!["u1".into(), "u2".into()],
            vec!["y1".into(), "y2".into()],
            u,
            y,
            None,
        )
        .unwrap();
        (m, data)
    }

    /// The sensitivity Jacobian equals central differences of the residuals along
    /// every free direction, with D, x0 and a non-identity weight all active.
    #[test]
    fn jacobian_equals_finite_differences() {
        let (model, data) = toy();
        let l = Layout {
            n: 3,
            nu: 2,
            ny: 2,
            nd: 2,
            x0: true,
        };
        let x0 = DVector::from_vec(vec![0.3, -0.2, 0.5]);
        let lt = DMatrix::from_row_slice(2, 2, &[1.5, 0.4, 0.0, 0.8]);
        let basis = HouseholderQr::new(l.basis_change_directions(&model, &x0)).complement_basis();
        let m = basis.ncols();
        assert_eq!(m, l.len() - 9);
        let mut ws = Workspace::new(&l, data.len(), m);
        predict(&model, &x0, &data, &lt, &mut ws);
        jacobian(&model, &l, &basis, &data, &lt, &mut ws);
        let th = l.pack(&model, &x0);
        let h = 1e-6;
        let mut worst = 0.0f64;
        for j in 0..m {
            let mut rs = Vec::new();
            for sgn in [1.0, -1.0] {
                let mut x = x0.clone();
                let t = &th + basis.column(j) * (sgn * h);
                let mm = l.unpack(&t, &model, &mut x);
                let mut w2 = Workspace::new(&l, data.len(), 0);
                predict(&mm, &x, &data, &lt, &mut w2);
                rs.push(w2.r.clone());
            }
            let fd = (&rs[0] - &rs[1]) / (2.0 * h);
            worst = worst.max((fd - ws.j.column(j)).amax());
        }
        assert!(worst < 1e-7, "Jacobian vs finite differences: {worst}");
        // Basis changes leave the residuals alone: T is in the null space of the full Jacobian.
        let t = l.basis_change_directions(&model, &x0);
        for s in 0..9 {
            let mut x = x0.clone();
            let mm = l.unpack(&(&th + t.column(s) * 1e-6), &model, &mut x);
            let mut w2 = Workspace::new(&l, data.len(), 0);
            predict(&mm, &x, &data, &lt, &mut w2);
            assert!(
                (&w2.r - &ws.r).amax() < 1e-10,
                "basis change moved the residuals"
            );
        }
    }

    #[test]
    fn pack_unpack_round_trip() {
        let (model, _) = toy();
        let l = Layout {
            n: 3,
            nu: 2,
            ny: 2,
            nd: 2,
            x0: true,
        };
        let x0 = DVector::from_vec(vec![1.0, 2.0, 3.0]);
        let th = l.pack(&model, &x0);
        let mut x = DVector::zeros(3);
        let m2 = l.unpack(&th, &model, &mut x);
        assert_eq!(m2, model);
        assert_eq!(x, x0);
    }

    /// Deterministic white noise.
    fn noise(seed: u64, rows: usize, cols: usize, sd: f64) -> DMatrix<f64> {
        let mut rng = twinloop_random::SplitMix64(seed);
        DMatrix::from_fn(rows, cols, |_, _| sd * rng.normal())
    }

    /// An output-error system (K = 0) with white measurement noise: the
    /// simulation-focus search, started from a perturbed model with a non-zero K,
    /// keeps K at exactly zero, frees n^2 + n ny fewer parameters, and reaches the
    /// true system's simulation cost (the noise variance) within 1 %.
    #[test]
    fn output_error_recovers_a_known_oe_system() {
        let (mut truth, _) = toy();
        truth.k.fill(0.0);
        truth.d.fill(0.0);
        let n = 600;
        let u = noise(7, 2, n, 1.0);
        let clean = truth.simulate(&u, None).unwrap();
        let sd = 0.05;
        let y = &clean + noise(11, 2, n, sd);
        let data = IoData::new(
            vec!["u1".into(), "u2".into()],
            vec!["y1".into(), "y2".into()],
            u,
            y,
            None,
        )
        .unwrap();
        let (toy_model, _) = toy();
        let start = StateSpace {
            a: &truth.a * 0.85,
            b: &truth.b * 1.1,
            c: &truth.c * 0.9,
            k: toy_model.k.clone(),
            ..truth.clone()
        };
        let opts = PemOptions {
            output_error: true,
            max_iterations: 200,
            ..Default::default()
        };
        let r = pem(&data, &start, None, &opts, &mut |_| {}).unwrap();
        assert_eq!(r.model.k, DMatrix::zeros(3, 2));
        assert_eq!(r.free_parameters, 3 * (3 + 2 + 2) + 2 * 3 - 9 - 6);
        assert!(r.final_cost <= r.initial_cost);
        // The true system's cost: its simulation error is the added noise.
        let e_true = &data.y - truth.simulate(&data.u, None).unwrap();
        let true_cost = e_true.norm_squared() / n as f64;
        assert!(
            r.final_cost <= 1.01 * true_cost,
            "OE cost {} vs the true system's {true_cost}",
            r.final_cost
        );
        // K = 0: the one-step predictor is the simulation.
        let sim = r.model.simulate(&data.u, None).unwrap();
        let sim_cost = (&data.y - sim).norm_squared() / n as f64;
        assert!((sim_cost - r.final_cost).abs() <= 1e-9 * sim_cost);
    }

    /// With `enforce_stability` an unstable start is refused, and a stable one stays stable.
    #[test]
    fn enforce_stability_keeps_a_stable() {
        let (model, data) = toy();
        let opts = PemOptions {
            enforce_stability: true,
            ..Default::default()
        };
        let r = pem(&data, &model, None, &opts, &mut |_| {}).unwrap();
        assert!(r.model.spectral_radius().is_some_and(|x| x < 1.0));
        assert!(r.final_cost <= r.initial_cost);
        let unstable = StateSpace {
            a: &model.a * 2.0,
            k: DMatrix::zeros(3, 2),
            ..model.clone()
        };
        let e = pem(&data, &unstable, None, &opts, &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains("enforce_stability"), "{e}");
        // A damping margin just outside the start's pole radius: the search never
        // crosses it, a start outside it is refused, and a radius above 1 is an error.
        let rho0 = model.spectral_radius().unwrap();
        let margin = PemOptions {
            output_error: true,
            max_pole_radius: rho0 + 0.02,
            ..Default::default()
        };
        let r = pem(&data, &model, None, &margin, &mut |_| {}).unwrap();
        assert!(r.model.spectral_radius().unwrap() < rho0 + 0.02);
        assert!(r.final_cost <= r.initial_cost);
        let tight = PemOptions {
            max_pole_radius: 0.5 * rho0,
            ..margin
        };
        assert!(pem(&data, &model, None, &tight, &mut |_| {}).is_err());
        let silly = PemOptions {
            max_pole_radius: 1.5,
            ..margin
        };
        let e = pem(&data, &model, None, &silly, &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains("max_pole_radius"), "{e}");
    }
}
