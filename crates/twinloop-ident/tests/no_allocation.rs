//! The hot loops allocate nothing after warm-up: assembling the static regressor over
//! all poses, fitting marker frames (after the first), and the IK solvers. Counted by
//! a global allocator wrapper (its own test binary, so nothing else runs beside it).

use nalgebra::Vector3;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use twinloop_dynamics::{Data, Model};
use twinloop_gait::ik::{Ik, IkOptions, Task};
use twinloop_ident::StaticOptions;
use twinloop_ident::markers::{Marker, MarkerIk, marker_positions};
use twinloop_ident::plate::{PlateOptions, generate_static_poses};
use twinloop_ident::static_ident::{StaticProblem, StaticWorkspace, assemble};
use twinloop_ident::validate::{SquatOptions, squat_motion};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn count(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    f();
    ALLOCATIONS.load(Ordering::SeqCst) - before
}

fn hot_loops_do_not_allocate() {
    let robot = twinloop_description::load(
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../models/unitree_h1/h1.urdf"),
    )
    .unwrap();
    let model = Model::from_description(&robot).unwrap();
    let poses: Vec<_> = generate_static_poses(
        &robot,
        &model,
        &PlateOptions {
            count: 30,
            categories: vec![twinloop_ident::PoseCategory::Arm],
            ..PlateOptions::default()
        },
        |_| {},
    )
    .unwrap()
    .poses
    .into_iter()
    .map(|g| g.pose)
    .collect();

    // The static regressor over every pose.
    let problem = StaticProblem::new(
        &robot,
        &model,
        robot.total_mass(),
        &StaticOptions::default(),
    )
    .unwrap();
    let mut ws = StaticWorkspace::new(&model, &problem, poses.len());
    assemble(&model, &problem, &poses, &mut ws);
    assert_eq!(
        count(|| assemble(&model, &problem, &poses, &mut ws)),
        0,
        "assemble"
    );

    // Marker fitting, frame after frame.
    let markers: Vec<Marker> = (0..model.links.len())
        .filter(|&l| model.links[l].inertia.mass > 0.0)
        .flat_map(|l| {
            let c = model.links[l].inertia.com;
            [Vector3::x(), Vector3::y(), Vector3::z()]
                .into_iter()
                .enumerate()
                .map(move |(k, d)| Marker {
                    name: format!("m{l}_{k}"),
                    link: l,
                    position: c + d * 0.05,
                })
        })
        .collect();
    let mut data = Data::new(&model);
    let squat = squat_motion(
        &robot,
        &model,
        &SquatOptions {
            rest: 0.1,
            duration: 1.0,
            rate: 50.0,
            ..SquatOptions::default()
        },
        |_, _| {},
    )
    .unwrap();
    let frames: Vec<Vec<Option<Vector3<f64>>>> = squat
        .q
        .iter()
        .map(|q| {
            twinloop_dynamics::forward_kinematics(&model, &mut data, q);
            marker_positions(&model, &data, &markers)
                .into_iter()
                .map(Some)
                .collect()
        })
        .collect();
    let mut fitter = MarkerIk::new(&model, markers.clone()).unwrap();
    fitter.fit(&frames[0], 0).unwrap();
    let n = count(|| {
        for (k, f) in frames.iter().enumerate().skip(1) {
            let (_, fit) = fitter.fit(f, k).unwrap();
            assert!(fit.rms < 1e-8);
        }
    });
    assert_eq!(n, 0, "marker fitting");

    // The IK solvers: Levenberg-Marquardt and the least-norm projection.
    let foot = model
        .frames
        .iter()
        .position(|f| f.name == "left_ankle_link")
        .unwrap();
    let mut ik = Ik::new(
        &model,
        vec![
            Task::Point {
                frame: foot,
                point: Vector3::zeros(),
                target: Vector3::new(0.0, 0.1, 0.05),
                weight: Vector3::repeat(1.0),
            },
            Task::Com {
                target: Vector3::zeros(),
                weight: Vector3::new(1.0, 1.0, 0.0),
            },
        ],
    );
    let mut q = poses[0].q.clone();
    let opts = IkOptions::default();
    let n = count(|| {
        ik.solve(&model, &mut data, &mut q, &opts);
        ik.project(&model, &mut data, &mut q, 20, 1e-12);
    });
    assert_eq!(n, 0, "ik");
}

/// Runs without libtest's harness (Cargo.toml: `harness = false`): the harness's own
/// thread allocates while the test runs (its bookkeeping of running tests), and on a
/// loaded CI machine those allocations landed inside the counted window.
fn main() {
    hot_loops_do_not_allocate();
    println!("test hot_loops_do_not_allocate ... ok");
}
