//! Per-instance time of the batched dynamics (`twinloop_dynamics::batch`) against
//! the single call, on OP3 and G1: N = 256 random states (inputs and workspaces stay
//! in cache), the single call looped over them against one batched call, alternating
//! runs, median and minimum of 21 rounds, ns per instance of this thread's time on a CPU (not wall
//! time: see `cpu_ns`). One thread.
//! `cargo bench --profile ci -p twinloop-dynamics --bench batch`
//! (`RUSTFLAGS=-Ctarget-cpu=native` to compile the baseline for this CPU too).

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;
use twinloop_dynamics::configuration::{random_configuration, random_tangent};
use twinloop_dynamics::*;
use twinloop_random::SplitMix64;

const N: usize = 256;
const ROUNDS: usize = 21;

/// Rounds to time: `ROUNDS`, or `BATCH_BENCH_ROUNDS` (1 under callgrind, whose
/// instruction counts need no repetition).
fn rounds() -> usize {
    std::env::var("BATCH_BENCH_ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(ROUNDS)
}

/// Median and minimum: at the shared machine's load the minimum is the round the
/// other processes disturbed least (caches, frequency).
fn median(mut x: Vec<f64>) -> (f64, f64) {
    x.sort_by(f64::total_cmp);
    (x[x.len() / 2], x[0])
}

/// This thread's time on a CPU in ns (`CLOCK_THREAD_CPUTIME_ID`): on a machine shared
/// by more runnable threads than cores the wall time mostly measures the others.
fn cpu_ns(_t0: Instant) -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid clock id and a valid pointer to a timespec.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime");
    ts.tv_sec as f64 * 1e9 + ts.tv_nsec as f64
}

/// ns per instance (on-CPU time) of `single` and `batched`, alternating, medians.
type Times = ((f64, f64), (f64, f64));

/// Whether to time `algo`: all, or those named in `BATCH_BENCH_ALGOS` (comma-separated;
/// valgrind 3.19 stops at an AVX2 instruction of the batched CRBA, so callgrind runs
/// without it).
fn wanted(algo: &str) -> bool {
    std::env::var("BATCH_BENCH_ALGOS").map_or(true, |a| a.split(',').any(|x| x == algo))
}

fn time(
    algo: &str,
    reps: usize,
    mut single: impl FnMut(),
    mut batched: impl FnMut(),
) -> Option<Times> {
    if !wanted(algo) {
        return None;
    }
    let (mut s, mut b) = (Vec::new(), Vec::new());
    let t0 = Instant::now();
    single();
    batched();
    for _ in 0..rounds() {
        let t = cpu_ns(t0);
        for _ in 0..reps {
            single();
        }
        s.push((cpu_ns(t0) - t) / (reps * N) as f64);
        let t = cpu_ns(t0);
        for _ in 0..reps {
            batched();
        }
        b.push((cpu_ns(t0) - t) / (reps * N) as f64);
    }
    Some((median(s), median(b)))
}

fn bench(name: &str, file: &str) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(file);
    let robot = twinloop_description::load(&path).unwrap();
    let model = Model::from_description(&robot).unwrap();
    let (nq, nv) = (model.nq, model.nv);
    let mut rng = SplitMix64(1);
    let (mut q, mut v, mut a) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..N {
        q.extend(random_configuration(&model, &mut rng));
        v.extend(random_tangent(&model, &mut rng));
        a.extend(random_tangent(&model, &mut rng));
    }
    let mut d = Data::new(&model);
    let mut bd = BatchData::new(&model);
    let mut out = vec![0.0; N * nv];
    let mut m = vec![0.0; N * nv * nv];
    let mut m2 = vec![0.0; N * nv * nv];
    let mut com = vec![0.0; N * 3];
    let (q, v, a) = (&q[..], &v[..], &a[..]);
    let row = |x: &'static str, r: usize| -> std::ops::Range<usize> {
        let w = if x == "q" { nq } else { nv };
        r * w..(r + 1) * w
    };
    let rnea_t = time(
        "rnea",
        8,
        || {
            for r in 0..N {
                black_box(rnea(
                    &model,
                    &mut d,
                    &q[row("q", r)],
                    &v[row("v", r)],
                    &a[row("v", r)],
                ));
            }
        },
        || rnea_batch(&model, &mut bd, black_box(q), v, a, &mut out),
    );
    let aba_t = time(
        "aba",
        4,
        || {
            for r in 0..N {
                black_box(aba(
                    &model,
                    &mut d,
                    &q[row("q", r)],
                    &v[row("v", r)],
                    &a[row("v", r)],
                ));
            }
        },
        || aba_batch(&model, &mut bd, black_box(q), v, a, &mut out),
    );
    let crba_t = time(
        "crba",
        8,
        || {
            for r in 0..N {
                black_box(crba(&model, &mut d, &q[row("q", r)]));
            }
        },
        || crba_batch(&model, &mut bd, black_box(q), &mut m),
    );
    // What a caller of the single call does to hand out N whole matrices, as the
    // batch does (the Python package's crba_batch before this change).
    let crba_out_t = time(
        "crba+out",
        8,
        || {
            for r in 0..N {
                crba(&model, &mut d, &q[row("q", r)]);
                d.symmetrize_mass_matrix();
                m[r * nv * nv..(r + 1) * nv * nv].copy_from_slice(d.mass_matrix.as_slice());
            }
        },
        || crba_batch(&model, &mut bd, black_box(q), &mut m2),
    );
    // The compact form: each matrix's packed lower triangle (half the bytes).
    let mut mp = vec![0.0; N * batch::packed_len(nv)];
    let crba_packed_t = time(
        "crba pak",
        8,
        || {
            for r in 0..N {
                black_box(crba(&model, &mut d, &q[row("q", r)]));
            }
        },
        || batch::crba_batch_packed(&model, &mut bd, black_box(q), &mut mp),
    );
    let com_t = time(
        "com",
        16,
        || {
            for r in 0..N {
                black_box(center_of_mass(&model, &mut d, &q[row("q", r)]));
            }
        },
        || center_of_mass_batch(&model, &mut bd, black_box(q), &mut com),
    );
    let results = [
        ("rnea", rnea_t),
        ("aba", aba_t),
        ("crba", crba_t),
        ("crba+out", crba_out_t),
        ("crba pak", crba_packed_t),
        ("com", com_t),
    ];
    for (algo, t) in results {
        let Some(((s, s_min), (b, b_min))) = t else {
            continue;
        };
        println!(
            "{name:4} {algo:8} median: single {s:7.1} ns, batched {b:7.1} ns/instance, {:.2}x; \
             min: {s_min:7.1}, {b_min:7.1}, {:.2}x",
            s / b,
            s_min / b_min
        );
    }
}

fn main() {
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("load average: {}", load.trim());
    #[cfg(target_arch = "x86_64")]
    println!("AVX2 lanes: {}", twinloop_dynamics::batch::has_avx2());
    bench("OP3", "models/op3/robotis_op3.nomesh.urdf");
    bench("G1", "models/unitree_g1/g1_29dof_rev_1_0.nomesh.urdf");
}
