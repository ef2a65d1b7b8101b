//! Several servos of one type fitted together: one Levenberg-Marquardt problem whose
//! parameter vector holds the shared parameters once and the per-servo ones once per
//! servo, over the logs of every servo (each on its own load). And the question
//! the fit answers: does each servo need its own parameters?
//!
//! A per-servo parameter moves only its servo's residuals, so a Jacobian column
//! of one costs one servo's simulations, not the group's: each servo keeps its
//! last three residual blocks keyed by its parameters, and an evaluation
//! simulates only the servos whose parameters changed (in threads).

use crate::bench::Pendulum;
use crate::error::ActuatorError;
use crate::identify::{
    Fit, UNDETERMINED_RELATIVE_SD, heldout_error, motor_combinations, uncertainty,
};
use crate::lm::{LmOptions, levenberg_marquardt};
use crate::load::Load;
use crate::log::ServoLog;
use crate::params::{FRICTION_VISCOUS, ModelLevel, N_PARAMS, PARAM_NAMES, ServoParams};
use crate::robust_covariance::robust_covariance;
use crate::segments::{Segment, mean_voltage, position_sum_squares, residual_blocks, split_logs};
use crate::servo_type::ServoType;
use nalgebra::DMatrix;
use std::ops::Range;
use twinloop_sysid::stats::chi2_sf;

/// One servo's data: its logs (the last `holdout_fraction` of each held out when
/// `holdout` is empty), logs only scored, and its load.
#[derive(Debug, Clone)]
pub struct ServoData {
    /// How reports name it (`id 3`).
    pub name: String,
    pub logs: Vec<ServoLog>,
    pub holdout: Vec<ServoLog>,
    pub load: Pendulum,
}

/// One servo's share of a group fit.
#[derive(Debug, Clone)]
pub struct ServoFit {
    pub name: String,
    /// Its parameters (shared and own), with their standard deviations.
    pub params: ServoParams,
    /// `kt/resistance` and `kt^2/resistance + friction_viscous` with their
    /// deviations, as [`crate::identify::Identification::combinations`].
    pub combinations: Vec<(&'static str, f64, f64)>,
    /// RMS of its fitted position residuals, mrad.
    pub fit_rms_mrad: f64,
    /// Held-out RMS and mean absolute position error, mrad, and its rows.
    pub heldout_rms_mrad: f64,
    pub heldout_mae_mrad: f64,
    pub heldout_rows: usize,
    /// Its weighted residuals: count and sum of squares.
    pub residuals: usize,
    pub sum_squares: f64,
    /// The deviations the Jacobian states (residuals taken as independent);
    /// `params.uncertainty` holds the robust ones (the block sandwich, `robust_covariance`).
    pub sd_independent: [f64; N_PARAMS],
}

/// A group fit.
#[derive(Debug, Clone)]
pub struct GroupFit {
    pub servos: Vec<ServoFit>,
    /// Fitted parameters (indices into [`PARAM_NAMES`]) held in common, and per servo.
    pub shared: Vec<usize>,
    pub per_servo: Vec<usize>,
    /// Parameters whose relative deviation exceeds [`UNDETERMINED_RELATIVE_SD`] for
    /// some servo (and, in position-only logs, kt, resistance, friction_viscous).
    pub undetermined: Vec<&'static str>,
    /// Length of the parameter vector: shared + servos x per-servo.
    pub n_params: usize,
    pub iterations: usize,
    /// Simulations of one servo's logs (a whole-group evaluation counts one per servo).
    pub simulations: usize,
}

impl GroupFit {
    /// Sum of the squared weighted residuals and their count, over every servo.
    pub fn sum_squares(&self) -> (f64, usize) {
        (
            self.servos.iter().map(|s| s.sum_squares).sum(),
            self.servos.iter().map(|s| s.residuals).sum(),
        )
    }
}

/// A residual block kept for a servo, keyed by the parameters that made it.
struct Cached {
    values: [f64; N_PARAMS],
    r: Vec<f64>,
    used: u64,
}

/// Blocks kept per servo: the Jacobian's base point and its plus and minus steps.
const CACHED: usize = 3;

struct Group<'a> {
    servos: &'a [ServoData],
    base: Vec<ServoParams>,
    segments: Vec<Vec<Segment>>,
    offsets: Vec<Range<usize>>,
    shared: Vec<usize>,
    per: Vec<usize>,
    sd_q: f64,
    cache: Vec<Vec<Cached>>,
    clock: u64,
    /// One (positions, currents) scratch pair per thread.
    buffers: Vec<(Vec<f64>, Vec<f64>)>,
    simulations: usize,
}

impl Group<'_> {
    /// Servo `s`'s parameters at the log-parameter vector `x`.
    fn params_of(&self, x: &[f64], s: usize) -> ServoParams {
        let mut p = self.base[s].clone();
        let ns = self.shared.len();
        for (k, &i) in self.shared.iter().enumerate() {
            p.values[i] = x[k].exp();
        }
        let np = self.per.len();
        for (k, &i) in self.per.iter().enumerate() {
            p.values[i] = x[ns + s * np + k].exp();
        }
        p
    }

    fn residuals(&mut self, x: &[f64], out: &mut [f64]) {
        self.clock += 1;
        let clock = self.clock;
        let mut jobs: Vec<(usize, ServoParams, Vec<f64>)> = Vec::new();
        for s in 0..self.servos.len() {
            let p = self.params_of(x, s);
            let range = self.offsets[s].clone();
            if let Some(c) = self.cache[s].iter_mut().find(|c| c.values == p.values) {
                c.used = clock;
                out[range].copy_from_slice(&c.r);
                continue;
            }
            // Reuse the least recently used block's storage.
            let r = if self.cache[s].len() == CACHED {
                let k = (0..CACHED)
                    .min_by_key(|&k| self.cache[s][k].used)
                    .expect("CACHED > 0");
                self.cache[s].swap_remove(k).r
            } else {
                vec![0.0; range.len()]
            };
            jobs.push((s, p, r));
        }
        self.simulations += jobs.len();
        let per_thread = jobs.len().div_ceil(self.buffers.len()).max(1);
        let (servos, segments, sd_q) = (self.servos, &self.segments, self.sd_q);
        let run = |chunk: &mut [(usize, ServoParams, Vec<f64>)],
                   (qb, cb): &mut (Vec<f64>, Vec<f64>)| {
            for (s, p, r) in chunk {
                let load = Load::from(servos[*s].load);
                let fit = Fit {
                    logs: &servos[*s].logs,
                    load: &load,
                    segments: &segments[*s],
                    sd_q,
                    iterations: 0,
                    evaluations: 0,
                };
                fit.residuals(p, qb, cb, r);
            }
        };
        if jobs.len() > 1 && self.buffers.len() > 1 {
            std::thread::scope(|scope| {
                for (chunk, buf) in jobs.chunks_mut(per_thread).zip(self.buffers.iter_mut()) {
                    scope.spawn(|| run(chunk, buf));
                }
            });
        } else {
            run(&mut jobs, &mut self.buffers[0]);
        }
        for (s, p, r) in jobs {
            out[self.offsets[s].clone()].copy_from_slice(&r);
            self.cache[s].push(Cached {
                values: p.values,
                r,
                used: clock,
            });
        }
    }
}

/// Fit `servos` together: the rung's parameters named in `shared` once for all,
/// the others once per servo, from `starts` (one per servo; a shared parameter
/// starts at their geometric mean). Position-only logs hold friction_viscous at 0,
/// as [`crate::identify::identify`] does. Backlash and delays keep the starts'
/// values. `threads` simulate servos at once.
pub fn identify_group(
    servos: &[ServoData],
    starts: &[ServoParams],
    shared: &[usize],
    holdout_fraction: f64,
    threads: usize,
) -> Result<GroupFit, ActuatorError> {
    let (servo_type, level) = check_group(servos, starts)?;
    let mut fitted = level.parameters();
    let senses_current = servos
        .iter()
        .all(|d| d.logs.iter().all(|l| l.current.is_some()));
    if !senses_current {
        fitted.retain(|&i| i != FRICTION_VISCOUS);
    }
    let (shared_f, per_f): (Vec<usize>, Vec<usize>) =
        fitted.iter().partition(|i| shared.contains(i));
    let layout = Layout::of(servos, starts, holdout_fraction, senses_current);
    let x0 = start_vector(&layout.base, &shared_f, &per_f);
    let mut group = Group {
        servos,
        base: layout.base,
        segments: layout.segments,
        offsets: layout.offsets,
        shared: shared_f.clone(),
        per: per_f.clone(),
        sd_q: servo_type.resolution() / 12f64.sqrt(),
        cache: (0..servos.len()).map(|_| Vec::new()).collect(),
        clock: 0,
        buffers: (0..threads.max(1))
            .map(|_| (vec![0.0; layout.longest], vec![0.0; layout.longest]))
            .collect(),
        simulations: 0,
    };
    let result = levenberg_marquardt(
        &x0,
        layout.rows,
        |x, out| group.residuals(x, out),
        &LmOptions::default(),
    );
    let n = x0.len();
    let stats = uncertainty(&result.jacobian, &result.residuals, &result.x, n);
    let robust = robust_covariance(&result.jacobian, &result.residuals, &layout.block);
    let mut undetermined: Vec<&'static str> = Vec::new();
    if !senses_current {
        undetermined.extend(["kt", "resistance", "friction_viscous"]);
    }
    let fitted_s: Vec<usize> = shared_f.iter().chain(&per_f).copied().collect();
    let mut qb = vec![0.0; layout.longest];
    let mut cb = vec![0.0; layout.longest];
    let fits = (0..servos.len())
        .map(|s| {
            let p = group.params_of(&result.x, s);
            // This servo's columns of the parameter vector, in `fitted_s`'s order.
            let (ns, np) = (shared_f.len(), per_f.len());
            let cols: Vec<usize> = (0..ns).chain(ns + s * np..ns + (s + 1) * np).collect();
            let covariance = Covariance {
                robust: &robust,
                independent_sd_log: &stats.sd_log,
                cols: &cols,
                fitted: &fitted_s,
            };
            let residuals = &result.residuals.as_slice()[group.offsets[s].clone()];
            let fit_rms = 1e3 * group.sd_q * rms(residuals, &group.segments[s]);
            let held = held_of(&servos[s], &layout.held[s]);
            let (fit, names) = servo_fit(
                &servos[s],
                p,
                &covariance,
                residuals,
                fit_rms,
                &held,
                (&mut qb, &mut cb),
            );
            for name in names {
                if !undetermined.contains(&name) {
                    undetermined.push(name);
                }
            }
            fit
        })
        .collect();
    Ok(GroupFit {
        servos: fits,
        shared: shared_f,
        per_servo: per_f,
        undetermined,
        n_params: n,
        iterations: result.iterations,
        simulations: group.simulations,
    })
}

/// The servo type and rung every servo of a group fit shares; refuses a group with
/// no servo, a servo with no log, or mixed types, rungs or logs.
fn check_group(
    servos: &[ServoData],
    starts: &[ServoParams],
) -> Result<(ServoType, ModelLevel), ActuatorError> {
    let Some(first) = starts.first() else {
        return Err(ActuatorError::new("", "--data", "no servo to fit"));
    };
    if starts.len() != servos.len() {
        return Err(ActuatorError::new("", "", "one start per servo"));
    }
    let (servo_type, level) = (first.servo, first.level);
    for (d, st) in servos.iter().zip(starts) {
        if d.logs.is_empty() {
            return Err(ActuatorError::new(&d.name, "--data", "no log to fit"));
        }
        if st.servo != servo_type || st.level != level {
            return Err(ActuatorError::new(
                &d.name,
                "",
                "every servo of a group fit is of one type and rung",
            ));
        }
        for l in d.logs.iter().chain(&d.holdout) {
            if l.servo != Some(servo_type) {
                return Err(ActuatorError::new(
                    &l.file,
                    "line 1",
                    format!(
                        "a log of {:?}, but the group is of {servo_type}",
                        l.servo.map(|s| s.name())
                    ),
                ));
            }
        }
    }
    Ok((servo_type, level))
}

/// Where each servo's rows sit in the group's residual vector.
struct Layout {
    /// Each servo's start with its logs' mean voltage.
    base: Vec<ServoParams>,
    segments: Vec<Vec<Segment>>,
    /// Each servo's held-out rows: (log, rows).
    held: Vec<Vec<(usize, Range<usize>)>>,
    offsets: Vec<Range<usize>>,
    /// Residual rows in all.
    rows: usize,
    /// The longest log of any servo, rows.
    longest: usize,
    /// The time block of each residual row, for the robust covariance.
    block: Vec<usize>,
}

impl Layout {
    fn of(
        servos: &[ServoData],
        starts: &[ServoParams],
        holdout_fraction: f64,
        senses_current: bool,
    ) -> Layout {
        let mut layout = Layout {
            base: Vec::new(),
            segments: Vec::new(),
            held: Vec::new(),
            offsets: Vec::new(),
            rows: 0,
            longest: 0,
            block: Vec::new(),
        };
        for (d, st) in servos.iter().zip(starts) {
            let mut p = st.clone();
            p.uncertainty = None;
            p.voltage = mean_voltage(&d.logs);
            if !senses_current {
                p.values[FRICTION_VISCOUS] = 0.0;
            }
            layout.base.push(p);
            let (segs, held) = split_logs(&d.logs, !d.holdout.is_empty(), holdout_fraction, |_| {
                senses_current
            });
            residual_blocks(&d.logs, &segs, &mut layout.block);
            let rows: usize = segs.iter().map(Segment::residual_rows).sum();
            layout.offsets.push(layout.rows..layout.rows + rows);
            layout.rows += rows;
            let longest = d.logs.iter().chain(&d.holdout).map(ServoLog::len).max();
            layout.longest = layout.longest.max(longest.unwrap_or(0));
            layout.segments.push(segs);
            layout.held.push(held);
        }
        layout
    }
}

/// The LM start: each shared parameter's log at the servos' geometric mean, then
/// each servo's own parameters' logs.
fn start_vector(base: &[ServoParams], shared: &[usize], per: &[usize]) -> Vec<f64> {
    let mut x0 = Vec::with_capacity(shared.len() + base.len() * per.len());
    for &i in shared {
        let mean_ln =
            base.iter().map(|p| p.values[i].max(1e-6).ln()).sum::<f64>() / base.len() as f64;
        x0.push(mean_ln);
    }
    for p in base {
        for &i in per {
            x0.push(p.values[i].max(1e-6).ln());
        }
    }
    x0
}

/// The RMS of the position residuals among a servo's `residuals`, in their units.
fn rms(residuals: &[f64], segments: &[Segment]) -> f64 {
    let (sq, count) = position_sum_squares(residuals, segments);
    (sq / count.max(1) as f64).sqrt()
}

/// A servo's held-out rows as (log, rows): its fit logs' tails and its held-out logs.
fn held_of<'a>(
    d: &'a ServoData,
    held: &[(usize, Range<usize>)],
) -> Vec<(&'a ServoLog, Range<usize>)> {
    held.iter()
        .map(|(k, rows)| (&d.logs[*k], rows.clone()))
        .chain(d.holdout.iter().map(|l| (l, 0..l.len())))
        .collect()
}

/// One servo's view of the group fit's covariance of the log-parameters.
struct Covariance<'a> {
    robust: &'a DMatrix<f64>,
    independent_sd_log: &'a [f64],
    /// The servo's columns of the parameter vector, in `fitted`'s order.
    cols: &'a [usize],
    fitted: &'a [usize],
}

/// One servo's [`ServoFit`]: its deviations from the covariance, its motor
/// combinations and held-out error; and the names of its parameters not determined.
fn servo_fit(
    d: &ServoData,
    mut p: ServoParams,
    cov: &Covariance,
    residuals: &[f64],
    fit_rms_mrad: f64,
    held: &[(&ServoLog, Range<usize>)],
    (qb, cb): (&mut [f64], &mut [f64]),
) -> (ServoFit, Vec<&'static str>) {
    let mut undetermined = Vec::new();
    let mut sd = [0.0; N_PARAMS];
    let mut sd_independent = [0.0; N_PARAMS];
    for (&c, &i) in cov.cols.iter().zip(cov.fitted) {
        let sd_log = cov.robust[(c, c)].max(0.0).sqrt();
        sd[i] = p.values[i] * sd_log;
        sd_independent[i] = p.values[i] * cov.independent_sd_log[c];
        // NaN (a flat direction) counts as not determined.
        let determined = sd_log <= UNDETERMINED_RELATIVE_SD;
        if !determined && !undetermined.contains(&PARAM_NAMES[i]) {
            undetermined.push(PARAM_NAMES[i]);
        }
    }
    p.uncertainty = Some(sd);
    let servo_cov = cov.robust.select_rows(cov.cols).select_columns(cov.cols);
    let combinations = motor_combinations(&p, cov.fitted, &servo_cov);
    let (heldout_rms_mrad, heldout_mae_mrad, heldout_rows) =
        heldout_error(&p, &Load::from(d.load), held, qb, cb);
    let fit = ServoFit {
        name: d.name.clone(),
        params: p,
        combinations,
        fit_rms_mrad,
        heldout_rms_mrad,
        heldout_mae_mrad,
        heldout_rows,
        residuals: residuals.len(),
        sum_squares: residuals.iter().map(|e| e * e).sum(),
        sd_independent,
    };
    (fit, undetermined)
}

/// Each servo fitted alone (every parameter its own), `threads` servos at once;
/// as one [`GroupFit`] with nothing shared.
pub fn identify_each(
    servos: &[ServoData],
    starts: &[ServoParams],
    holdout_fraction: f64,
    threads: usize,
) -> Result<GroupFit, ActuatorError> {
    let threads = threads.clamp(1, servos.len().max(1));
    let mut results: Vec<Option<Result<GroupFit, ActuatorError>>> =
        (0..servos.len()).map(|_| None).collect();
    let per_thread = servos.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        for (k, out) in results.chunks_mut(per_thread).enumerate() {
            let first = k * per_thread;
            scope.spawn(move || {
                for (j, slot) in out.iter_mut().enumerate() {
                    let s = first + j;
                    *slot = Some(identify_group(
                        &servos[s..s + 1],
                        &starts[s..s + 1],
                        &[],
                        holdout_fraction,
                        1,
                    ));
                }
            });
        }
    });
    let mut all = GroupFit {
        servos: Vec::new(),
        shared: Vec::new(),
        per_servo: Vec::new(),
        undetermined: Vec::new(),
        n_params: 0,
        iterations: 0,
        simulations: 0,
    };
    for r in results {
        let g = r.expect("every servo ran")?;
        all.per_servo = g.per_servo;
        for u in g.undetermined {
            if !all.undetermined.contains(&u) {
                all.undetermined.push(u);
            }
        }
        all.n_params += g.n_params;
        all.iterations += g.iterations;
        all.simulations += g.simulations;
        all.servos.extend(g.servos);
    }
    Ok(all)
}

/// Whether the servos differ in one parameter, from their separate fits.
#[derive(Debug, Clone)]
pub struct Spread {
    pub index: usize,
    pub name: &'static str,
    /// Each servo's value and its deviation as the Jacobian states it.
    pub values: Vec<f64>,
    pub sd: Vec<f64>,
    /// Relative spread of the values (their sample standard deviation over their
    /// mean) and the median relative (robust) deviation.
    pub relative_spread: f64,
    pub relative_sd: f64,
    /// `sum ((ln p_s - mean)/sd_s)^2` over the servos with the robust relative
    /// deviations (weighted mean), its degrees of freedom (servos - 1) and the chance of as
    /// large a value if the servos were alike.
    pub chi2: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Whether every servo's fit determines it (relative deviation at most
    /// [`UNDETERMINED_RELATIVE_SD`]); only those are tested.
    pub tested: bool,
    /// Tested, `p_value` below [`DIFFER_P`] / parameters tested (Bonferroni), and
    /// `relative_spread` above [`MIN_SPREAD`].
    pub differs: bool,
}

/// Least relative spread called a difference: below it the servos' values are
/// within what the fit recovers of a known truth over the bus (docs/servo-models.md:
/// errors up to 2.5 %, from timing the deviations do not capture).
pub const MIN_SPREAD: f64 = 0.03;

/// Family-wise significance of "the servos differ" over the parameters tested.
pub const DIFFER_P: f64 = 0.01;

/// The answer to "does each servo need its own parameters?".
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Every servo fitted alone.
    pub each: GroupFit,
    /// One parameter set for all.
    pub all_shared: GroupFit,
    /// Per parameter, from `each`.
    pub spreads: Vec<Spread>,
}

impl Comparison {
    /// The parameters the servos differ in.
    pub fn differing(&self) -> Vec<usize> {
        self.spreads
            .iter()
            .filter(|s| s.differs)
            .map(|s| s.index)
            .collect()
    }
}

/// Fit every servo alone and all with one set, and test per parameter whether the
/// servos differ beyond their (inflated) uncertainty.
pub fn compare(
    servos: &[ServoData],
    start: &ServoParams,
    holdout_fraction: f64,
    threads: usize,
) -> Result<Comparison, ActuatorError> {
    let starts = vec![start.clone(); servos.len()];
    let each = identify_each(servos, &starts, holdout_fraction, threads)?;
    // The shared fit starts from the separate fits' geometric mean: few iterations.
    let starts: Vec<ServoParams> = each.servos.iter().map(|s| s.params.clone()).collect();
    let all_shared = identify_group(servos, &starts, &each.per_servo, holdout_fraction, threads)?;
    // Tested: what every servo's fit determines (a position-only log's kt and
    // resistance are, with friction_viscous held at 0).
    let tested: Vec<usize> = each
        .per_servo
        .iter()
        .copied()
        .filter(|&i| {
            each.servos.iter().all(|s| {
                let sd = s.params.uncertainty.map_or(f64::NAN, |u| u[i]);
                sd <= UNDETERMINED_RELATIVE_SD * s.params.values[i]
            })
        })
        .collect();
    let mut spreads = Vec::new();
    for &i in &each.per_servo {
        let values: Vec<f64> = each.servos.iter().map(|s| s.params.values[i]).collect();
        let sd: Vec<f64> = each
            .servos
            .iter()
            .map(|s| s.params.uncertainty.map_or(f64::NAN, |u| u[i]))
            .collect();
        // Log scale (the fit's): relative deviations.
        let sd_ln: Vec<f64> = values.iter().zip(&sd).map(|(v, d)| d / v).collect();
        let ln: Vec<f64> = values.iter().map(|v| v.ln()).collect();
        let w: Vec<f64> = sd_ln.iter().map(|d| 1.0 / (d * d)).collect();
        let mean = ln.iter().zip(&w).map(|(l, w)| l * w).sum::<f64>() / w.iter().sum::<f64>();
        let chi2: f64 = ln.iter().zip(&w).map(|(l, w)| (l - mean).powi(2) * w).sum();
        let dof = values.len().saturating_sub(1);
        let p_value = if dof > 0 && chi2.is_finite() {
            chi2_sf(chi2, dof as f64)
        } else {
            1.0
        };
        let avg = values.iter().sum::<f64>() / values.len() as f64;
        let var = values.iter().map(|v| (v - avg).powi(2)).sum::<f64>() / dof.max(1) as f64;
        let mut rel: Vec<f64> = sd_ln.clone();
        rel.sort_by(f64::total_cmp);
        spreads.push(Spread {
            index: i,
            name: PARAM_NAMES[i],
            relative_spread: var.sqrt() / avg,
            relative_sd: rel[rel.len() / 2],
            tested: tested.contains(&i),
            differs: tested.contains(&i)
                && p_value < DIFFER_P / tested.len().max(1) as f64
                && var.sqrt() / avg > MIN_SPREAD,
            values,
            sd,
            chi2,
            dof,
            p_value,
        });
    }
    Ok(Comparison {
        each,
        all_shared,
        spreads,
    })
}

/// A group identification: the comparison and the fit chosen from it (or with the
/// shared parameters the user named).
#[derive(Debug, Clone)]
pub struct GroupIdentification {
    pub comparison: Comparison,
    /// The parameters the servos differ in own, the rest shared (or as asked).
    pub chosen: GroupFit,
}

/// Fit `servos` alone and together, test which parameters differ, and fit the
/// group with those per servo and the rest shared; `shared` (where given) names
/// the shared ones instead of the test.
pub fn identify_servos(
    servos: &[ServoData],
    start: &ServoParams,
    shared: Option<&[usize]>,
    holdout_fraction: f64,
    threads: usize,
) -> Result<GroupIdentification, ActuatorError> {
    let comparison = compare(servos, start, holdout_fraction, threads)?;
    let per_servo: Vec<usize> = match shared {
        Some(shared) => comparison
            .each
            .per_servo
            .iter()
            .copied()
            .filter(|i| !shared.contains(i))
            .collect(),
        None => comparison.differing(),
    };
    let chosen = if per_servo.is_empty() {
        comparison.all_shared.clone()
    } else if per_servo.len() == comparison.each.per_servo.len() {
        comparison.each.clone()
    } else {
        let shared: Vec<usize> = comparison
            .each
            .per_servo
            .iter()
            .copied()
            .filter(|i| !per_servo.contains(i))
            .collect();
        // From the separate fits: a per-servo parameter starts at its own value.
        let starts: Vec<ServoParams> = comparison
            .each
            .servos
            .iter()
            .map(|s| s.params.clone())
            .collect();
        identify_group(servos, &starts, &shared, holdout_fraction, threads)?
    };
    Ok(GroupIdentification { comparison, chosen })
}
