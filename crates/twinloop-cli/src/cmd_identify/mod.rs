//! `twinloop identify ...`: fit models to measurements: link masses and CoMs from
//! static poses (seed 004), black-box ARX and state-space models (seed 003), the
//! compact compliant model (seed 002), and seed 003's walk identification.

#[macro_use]
mod sysid;
mod compliant;
mod servo;
mod static_ident;
mod walk;

use crate::error::CliResult;
use clap::Subcommand;

#[derive(Subcommand, Debug)]
pub enum IdentifyCommand {
    /// Link masses and CoMs from static poses on a force plate (seed 004, eq 8-9)
    ///
    /// In a static pose the force plate's centre of pressure (CoP) is the
    /// ground-projected centre of mass (GCOM). The CoM is linear in each link's mass m and
    /// first moment m c, so the masses and CoMs that bring the model's GCOM closest
    /// to the measured CoPs, with the masses adding up to --total-mass (the robot on
    /// a scale), are the solution of a linear least-squares problem. It is solved
    /// exactly, with the masses kept positive and each CoM inside a box around its
    /// link (the link's primitive geometry and prior CoM, plus --com-margin).
    ///
    /// What the poses cannot see is kept at the prior (the PRIOR description): each
    /// unknown is weighted by its prior (100 % of each mass) against the plate noise
    /// --cop-sigma, so well-excited directions come from the data and unseen ones
    /// (links welded to one body, a joint that never moves) stay at the CAD values.
    /// From CoP data alone a link's mass and its first moment along its joint axis
    /// can always be traded for its parent's: those directions never move (see the
    /// identifiability section of the output).
    ///
    /// Example:
    ///   twinloop identify static --robot prior.urdf --poses poses.csv --total-mass 59.34 \
    ///       --out adapted.urdf --json result.json --report report.html
    ///   twinloop identify static --robot prior.urdf --poses poses.csv --total-mass 59.34 \
    ///       --links torso_link,pelvis --cop-sigma 0 --out adapted.urdf --json r.json
    ///
    /// Output: the adapted URDF (only the identified links' <inertial> mass and origin
    /// xyz change; inertia tensors and everything else are untouched), the JSON result
    /// (per link: prior and identified mass and CoM with standard deviations and how
    /// much the poses determine them; GCOM-to-CoP distance per pose before and after;
    /// identifiability: rank, singular values, condition number, what is not
    /// determined and why; suggested poses), and on stdout a summary. With --squat, the
    /// residual base wrench of the prior and adapted models on that motion (seed 004,
    /// Table 1) is added. --report writes an HTML page with the seed's Fig. 5 (and
    /// Fig. 6 with --squat), and beside it OUT_3d.html: the poses in 3D, one a second.
    #[command(verbatim_doc_comment)]
    Static(static_ident::IdentifyStaticArgs),

    /// Estimate a MIMO ARX model by least squares (MATLAB's arx structure)
    #[command(
        long_about = "Estimate a MIMO ARX model y(k) + A1 y(k-1) + ... + Ana y(k-na) = B1 u(k-nk) + ... + \
Bnb u(k-nk-nb+1) + e(k) with full ny x ny matrices A_i, by least squares (Householder QR) over the samples \
k = max(na, nb+nk-1) .. N-1, as MATLAB's arx; then simulate it and predict with it, and evaluate it as \
seed 003 did: FIT per output, Hankel singular values, singular values of the frequency response, \
residual tests. The seed's initial model was na = nb = 24, nk = 1 on 10 inputs and 6 outputs.",
        after_long_help = concat!(
            "Example:\n  twinloop identify arx --data lab17_walk.csv --val lab17_walk_val.csv --inputs 'u:*' --outputs 'gyro:*' \\\n",
            "      --na 24 --nb 24 --nk 1 --json arx.json --report arx.html\n\n",
            sysid_output_help!()
        )
    )]
    Arx(sysid::ArxArgs),
    /// Estimate a state-space model (n4sid, PEM as MATLAB's ssest, or the seed's ARX-reduce-PEM route)
    #[command(
        long_about = "Estimate a state-space model in innovations form x(k+1) = A x + B u + K e, y = C x + \
D u + e of the given order. --method n4sid: subspace identification alone; pem (default): the subspace \
estimate refined by the prediction-error method (Levenberg-Marquardt on the one-step prediction errors, \
as MATLAB's ssest); arx-reduce-pem: the route of seed 003, a high-order ARX model (--na --nb --nk), \
realised in state space, reduced to --order by balanced truncation, then refined by the prediction-error \
method. The prediction error never ends above the initial model's. The model is then evaluated as for arx.",
        after_long_help = concat!(
            "Examples:\n  twinloop identify ss --data lab17_walk.csv --val lab17_walk_val.csv --inputs 'u:*' --outputs 'gyro:*' \\\n",
            "      --order 6 --method pem --json ss.json --report ss.html\n",
            "  twinloop identify ss --data lab17_walk.csv --inputs 'u:*' --outputs 'gyro:*' --order 24 \\\n",
            "      --method arx-reduce-pem --na 24 --nb 24 --nk 1 --json seed.json\n\n",
            sysid_output_help!()
        )
    )]
    Ss(sysid::SsArgs),
    /// Fit the compact compliant model's corrections to a recorded CoM (seed 002, section 4)
    ///
    /// Minimises the mean squared error MSE = sum[(x - x^)^2 + (z - z^)^2] / 2N of the
    /// compact model (eq 14-17) rolled out along the recorded reference from the first
    /// recorded CoM at rest, over the corrections alpha1..epsilon2 (eta1, eta2 too if
    /// --params names them), from all ones (or --start).
    ///
    /// Methods: lm (default; Levenberg-Marquardt with the exact Jacobian from forward
    /// sensitivities: 40-130 evaluations on the seed's 30 s gait), cmaes (CMA-ES,
    /// derivative-free, 6000-12000 evaluations to 1e-2), power (PoWER, the seed's reinforcement
    /// learning: kept for fidelity, it stalls 0.1-0.2 away on the flat directions).
    ///
    /// DATA.csv columns: t, xr, zr, x, z, phase (0 single, 1 double support), uniform
    /// sampling. PLANT.toml: m, g, Kxx, Kxz, Kzx, Kzz, Dxx, Dxz, Dzx, Dzz, or
    /// `urdf = "coman.urdf"` with support, knee_bend, [q] to compute them (eq 7-8); the
    /// JSON of `compliant stiffness --json` works too.
    ///
    /// Output: the fitted parameters with their Cramer-Rao standard deviations at the
    /// noise estimated from the residuals, flags for poorly determined (relative std above
    /// 1 %) and correlated (|r| > 0.95) parameters, MSE before/after on the data and on
    /// each --val dataset (other gaits).
    ///
    /// The JSON holds params (all ten), mse_before, mse_after, evaluations, the
    /// identifiability (sensitivities, std, correlation, flags) and the validation MSEs.
    ///
    /// Example, on data the compact model makes itself (Table 1, 0.1 mm noise):
    ///   twinloop gait zmp --footsteps 40 --out ref.csv
    ///   twinloop compliant simulate --reference ref.csv --plant PLANT.toml --table1 --noise 1e-4 --out walk.csv
    ///   twinloop identify compliant --data walk.csv --plant PLANT.toml --json fit.json --report fit.html
    /// On the full simulator's COMAN walk:
    ///   twinloop experiment compliant-walk --robot models/coman/coman.urdf --out coman_walk.csv
    ///   twinloop compliant stiffness --robot models/coman/coman.urdf --json kc.json
    ///   twinloop identify compliant --data coman_walk.csv --plant kc.json
    #[command(verbatim_doc_comment)]
    Compliant(compliant::CompliantFitArgs),
    /// Seed 003's identification of a recorded walk: 24th-order ARX, then ARX -> reduce -> PEM
    ///
    /// The initial model is the MIMO ARX of section 7.1 (na 24, nb 12, nk 1); the final one
    /// the state-space model of section 7.2: the ARX realised in state space, reduced by
    /// balanced truncation to the order whose Hankel singular values carry 90 % of their
    /// sum (or --order), refined by the prediction-error method with the simulation focus
    /// (output error, K = 0; --focus prediction estimates K). Inputs are the record's `u:`
    /// columns minus exact copies (the seed's knee and hip pitch move together, and the
    /// two ankle rolls), outputs its six `gyro:` rates; the estimation record's means are
    /// removed first (--no-detrend keeps them).
    ///
    /// Example (estimation record, validation record = cycles 11-20, identification):
    ///   twinloop experiment walk --out est.csv
    ///   twinloop experiment walk --seed 2 --skip-samples 1000 --out val.csv
    ///   twinloop identify walk --data est.csv --val val.csv --json walk_id.json \
    ///       --report-arx arx.html --report ss.html
    ///
    /// Output: a table of FIT per output (MATLAB compare: 100 (1 - |y - yhat| / |y - mean y|),
    /// simulation and one-step prediction, on --val when given) for both models beside the
    /// seed's; the JSON holds both models (ARX `A`, `B`; state space `A`, `B`, `C`, `D`, `K`),
    /// their `fit_percent`, Hankel singular values and residual tests; beside each
    /// report, OUT_3d.html: lab17 walking the record's joint commands in 3D.
    #[command(verbatim_doc_comment)]
    Walk(walk::WalkIdArgs),
    /// A servo model fitted to `experiment servo` logs: parameters, uncertainties, held-out error
    ///
    /// Runs the model of docs/servo-models.md (firmware loop, DC motor, friction rung
    /// --model) against each log's goals and loop registers from its first measured
    /// state, and fits the parameters by Levenberg-Marquardt over their logarithms
    /// (central-difference Jacobian) to the logged positions, and currents where the
    /// servo senses them (MX(2.0), X). Positions alone (RX) determine the motor only
    /// through kt/resistance and kt^2/resistance + friction_viscous: friction_viscous
    /// is held at 0 and both combinations are reported. --defaults MODEL --out FILE
    /// writes the datasheet parameters instead. The load is the pendulum of --load, or
    /// for logs of a limb of a held robot (`experiment servo --map --joint`) the
    /// subtree beyond the joint, rebuilt from the robot (--robot overrides the one
    /// the log names), joint and held pose the log records.
    ///
    /// Logs of several servos of one type (--data ID=LOG.csv, or logs naming
    /// different ids) are fitted together: each alone, all with one set, a chi-square
    /// per parameter of the servos' spread against their deviations (robust to
    /// correlated residuals), then one fit with the parameters that differ (beyond
    /// their deviations and by over 3 %) per servo and the rest shared (--shared LIST
    /// chooses instead).
    ///
    /// Example:
    ///   twinloop identify servo --data rx28.csv --load load.toml --model m1 --out rx28.toml --json -
    ///   twinloop identify servo --data hip.csv --model m1
    ///   twinloop identify servo --defaults XM430-W350 --out xm430.toml
    ///   twinloop identify servo --data 1=a.csv --data 2=b.csv --data 3=c.csv --load load.toml --out fits
    ///
    /// Output: --out the parameter file ([servo], [params], [uncertainty]); stdout each
    /// parameter with one standard deviation, the fitted and held-out position error
    /// (mrad RMS and mean absolute), the condition number and what the logs do not
    /// determine; --json the same with fields servo, model, voltage, params
    /// {NAME: {value, sd}}, fitted, correlation (matrix in `fitted` order),
    /// combinations, fit_rms_mrad, heldout_rms_mrad, heldout_mae_mrad, heldout_rows,
    /// singular_values, condition, undetermined, weakest_direction, iterations,
    /// evaluations, seconds. Several servos: --out DIR gets one id-N.toml per servo
    /// (`--servo-params N=DIR/id-N.toml`); stdout the verdict per parameter, held-out
    /// error per servo (alone / all shared / chosen), the shared and per-servo values;
    /// --json spreads [{name, values, sd, relative_spread, relative_sd, chi2, dof,
    /// p_value, tested, differs}], differing, each, all_shared, chosen ({shared,
    /// per_servo, servos [{name, params, combinations, heldout_rms_mrad, ...}]}), files.
    #[command(verbatim_doc_comment)]
    Servo(servo::ServoIdArgs),
}

pub fn run(cmd: IdentifyCommand) -> CliResult {
    match cmd {
        IdentifyCommand::Static(a) => static_ident::run(&a),
        IdentifyCommand::Arx(a) => sysid::arx(&a),
        IdentifyCommand::Ss(a) => sysid::ss(&a),
        IdentifyCommand::Compliant(a) => compliant::run(&a),
        IdentifyCommand::Walk(a) => walk::run(&a),
        IdentifyCommand::Servo(a) => servo::run(&a),
    }
}
