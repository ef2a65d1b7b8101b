//! The side panel's warnings about meshes: one per kind of problem, not one per mesh
//! (issue 30 item 10: OP3 without its meshes gave 21).

use std::path::Path;
use twinloop_view::Scene;

#[test]
fn missing_meshes_are_one_warning_per_kind_not_one_per_mesh() {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/op3");
    for (file, kind) in [
        ("robotis_op3.urdf", "package \"op3_description\" is unknown"),
        ("mjcf/op3.xml", "file not found in "),
    ] {
        let path = models.join(file);
        let robot = twinloop_description::load(&path).unwrap();
        let scene = Scene::new(&robot, Some(&path), &[]);
        let n = scene.info.meshes.len();
        assert!(n > 10, "{file}: {n} meshes");
        let w = &scene.info.warnings;
        assert_eq!(w.len(), 1, "{file}: {w:?}");
        assert!(
            w[0].starts_with(&format!("{n} meshes: {kind}")) && w[0].contains("more"),
            "{file}: {w:?}"
        );
        // Each mesh still keeps its own problem.
        assert!(scene.info.meshes.iter().all(|m| m.problem.is_some()));
    }
}
