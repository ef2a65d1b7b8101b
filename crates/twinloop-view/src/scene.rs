//! What the page draws, made from any description: a URDF for urdf-loader (so MJCF
//! and built-in robots load the same way), its mesh files by number, and the link
//! and joint facts the overlays need (masses, CoMs, inertia boxes, limits).
//!
//! Mesh references are resolved here, once: relative to the description's folder,
//! `file://`, absolute, or `package://NAME/...` through `--package-dir NAME=DIR`
//! (else a folder NAME above the description). The served URDF names each found
//! mesh `mesh/N.ext`; the server answers only those numbers, so no request path
//! ever reaches the file system. A mesh that is missing (or of a type the page
//! cannot read) becomes the link's collision primitive, or else its inertia box,
//! drawn in orange, with a warning.

use crate::inertia_box::{PlacedBox, equivalent_box};
use serde::Serialize;
use std::path::{Path, PathBuf};
use twinloop_description::{Description, Geometry, JointKind, Material, Pose, Shape};

/// `--package-dir NAME=DIR`: where `package://NAME/` points.
#[derive(Debug, Clone, PartialEq)]
pub struct PackageDir {
    pub name: String,
    pub dir: PathBuf,
}

/// Why a scene's input is refused (a `--package-dir`) or a mesh cannot be shown.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError(pub String);

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SceneError {}

impl PackageDir {
    /// Parse `NAME=DIR`.
    pub fn parse(text: &str) -> Result<PackageDir, SceneError> {
        match text.split_once('=') {
            Some((name, dir)) if !name.is_empty() && !dir.is_empty() => {
                // `NAME=~/dir`: a shell leaves the tilde after `=` alone in some modes.
                let dir = match (dir.strip_prefix("~/"), std::env::var_os("HOME")) {
                    (Some(rest), Some(home)) => PathBuf::from(home).join(rest),
                    _ => PathBuf::from(dir),
                };
                Ok(PackageDir {
                    name: name.to_string(),
                    dir,
                })
            }
            _ => Err(SceneError(format!(
                "\"{text}\" is not NAME=DIR (e.g. op3_description=~/op3)"
            ))),
        }
    }
}

/// Mesh formats the page reads.
const MESH_TYPES: [&str; 3] = ["stl", "obj", "dae"];

/// One mesh file named by the description.
#[derive(Debug, Clone, Serialize)]
pub struct MeshFile {
    /// The reference as the description writes it.
    pub uri: String,
    /// The URL the served URDF uses (`mesh/N.ext`), when the file was found.
    pub url: Option<String>,
    /// Links whose visuals use it.
    pub links: Vec<String>,
    /// Why it is not drawn, when it is not.
    pub problem: Option<String>,
    #[serde(skip)]
    pub path: Option<PathBuf>,
}

#[derive(Debug, Clone, Serialize)]
pub struct LinkInfo {
    pub name: String,
    pub mass: f64,
    /// CoM in the link frame, m.
    pub com: [f64; 3],
    /// The equivalent box of the link's inertia, in the link frame.
    pub inertia_box: Option<PlacedBox>,
}

#[derive(Debug, Clone, Serialize)]
pub struct JointInfo {
    pub name: String,
    pub kind: &'static str,
    pub lower: Option<f64>,
    pub upper: Option<f64>,
}

/// The facts the page reads from `scene.json`.
#[derive(Debug, Clone, Serialize)]
pub struct SceneInfo {
    pub robot: String,
    pub total_mass: f64,
    /// Movable joints in depth-first order (the order of `q:*` columns).
    pub joints: Vec<JointInfo>,
    pub links: Vec<LinkInfo>,
    pub meshes: Vec<MeshFile>,
    pub warnings: Vec<String>,
}

/// A description made ready to serve.
#[derive(Debug, Clone)]
pub struct Scene {
    pub info: SceneInfo,
    /// The URDF the page loads.
    pub urdf: String,
}

/// Colour of a stand-in for a missing mesh.
const STAND_IN_RGBA: [f64; 4] = [1.0, 0.55, 0.1, 1.0];

impl Scene {
    /// Build the scene of `robot`, read from `source` (None for a built-in robot).
    pub fn new(robot: &Description, source: Option<&Path>, packages: &[PackageDir]) -> Scene {
        let base_dir = source
            .and_then(Path::parent)
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let mut served = robot.clone();
        let mut meshes: Vec<MeshFile> = Vec::new();
        let mut warnings = Vec::new();
        for link in &mut served.links {
            let stand_in = stand_in_shape(link);
            let link_name = link.name.clone();
            for visual in &mut link.visuals {
                let Geometry::Mesh { filename, .. } = &visual.geometry else {
                    continue;
                };
                let index = match meshes.iter().position(|m| &m.uri == filename) {
                    Some(i) => i,
                    None => {
                        meshes.push(resolve_mesh(filename, meshes.len(), &base_dir, packages));
                        meshes.len() - 1
                    }
                };
                let mesh = &mut meshes[index];
                if !mesh.links.contains(&link_name) {
                    mesh.links.push(link_name.clone());
                }
                match (&mesh.url, &stand_in) {
                    (Some(url), _) => {
                        if let Geometry::Mesh { filename, .. } = &mut visual.geometry {
                            *filename = url.clone();
                        }
                    }
                    (None, Some(shape)) => *visual = shape.clone(),
                    (None, None) => {}
                }
            }
            // A visual without a file and without any stand-in is dropped (urdf-loader
            // would fetch it).
            link.visuals
                .retain(|v| !matches!(&v.geometry, Geometry::Mesh { filename, .. } if !filename.starts_with("mesh/")));
        }
        warnings.extend(mesh_warnings(&meshes));
        let info = SceneInfo {
            robot: robot.name.clone(),
            total_mass: robot.total_mass(),
            joints: movable_joints(robot),
            links: robot
                .links
                .iter()
                .map(|l| LinkInfo {
                    name: l.name.clone(),
                    mass: l.mass(),
                    com: l.inertial.map_or([0.0; 3], |i| i.origin.xyz),
                    inertia_box: l.inertial.as_ref().and_then(equivalent_box),
                })
                .collect(),
            meshes,
            warnings,
        };
        Scene {
            info,
            urdf: twinloop_description::urdf::to_string(&served),
        }
    }
}

/// The movable joints in depth-first order: the order of the `q:*` columns.
fn movable_joints(robot: &Description) -> Vec<JointInfo> {
    robot
        .joints_depth_first()
        .into_iter()
        .map(|i| &robot.joints[i])
        .filter(|j| !matches!(j.kind, JointKind::Fixed | JointKind::Floating))
        .map(|j| JointInfo {
            name: j.name.clone(),
            kind: j.kind.urdf_name(),
            lower: j.limit.and_then(|l| l.lower),
            upper: j.limit.and_then(|l| l.upper),
        })
        .collect()
}

/// What stands in for a missing mesh: the link's first primitive collision shape,
/// else its inertia box; orange either way.
fn stand_in_shape(link: &twinloop_description::Link) -> Option<Shape> {
    let material = Some(Material {
        name: "twinloop_missing_mesh".into(),
        rgba: Some(STAND_IN_RGBA),
        texture: None,
    });
    if let Some(c) = link
        .collisions
        .iter()
        .find(|c| !matches!(c.geometry, Geometry::Mesh { .. }))
    {
        return Some(Shape {
            name: None,
            origin: c.origin,
            geometry: c.geometry.clone(),
            material,
        });
    }
    let b = link.inertial.as_ref().and_then(equivalent_box)?;
    // A flat or degenerate box still shows where the link is.
    let size = b.size.map(|s| s.max(0.005));
    Some(Shape {
        name: None,
        origin: Pose::from_matrix(b.xyz, b.rotation),
        geometry: Geometry::Box { size },
        material,
    })
}

/// Most mesh names a grouped warning lists before "and N more".
const LISTED_MESHES: usize = 3;

/// One warning per kind of mesh problem, not one per mesh (issue 30 item 10: OP3
/// without its meshes buried the side panel under 21): the meshes whose files are
/// missing from one folder are one warning, as are those of one other problem. Each
/// mesh's own problem stays in [`MeshFile::problem`].
fn mesh_warnings(meshes: &[MeshFile]) -> Vec<String> {
    // (kind, meshes of that kind), in order of first appearance.
    let mut groups: Vec<(String, Vec<&MeshFile>)> = Vec::new();
    for m in meshes {
        let Some(p) = &m.problem else { continue };
        let kind = match p.strip_prefix("file not found: ") {
            Some(path) => format!(
                "file not found in {}",
                Path::new(path)
                    .parent()
                    .map_or(String::new(), |d| d.display().to_string())
            ),
            None => p.clone(),
        };
        match groups.iter_mut().find(|(k, _)| *k == kind) {
            Some((_, g)) => g.push(m),
            None => groups.push((kind, vec![m])),
        }
    }
    const DRAWN: &str = "drawn as its collision primitive or inertia box (orange)";
    groups
        .into_iter()
        .map(|(kind, g)| {
            if let [m] = g.as_slice() {
                let p = m.problem.as_deref().unwrap_or("");
                return format!(
                    "mesh \"{}\" of link {}: {p}; {DRAWN}",
                    m.uri,
                    m.links.join(", ")
                );
            }
            let mut names: Vec<String> = g
                .iter()
                .take(LISTED_MESHES)
                .map(|m| format!("\"{}\"", m.uri))
                .collect();
            if g.len() > LISTED_MESHES {
                names.push(format!("and {} more", g.len() - LISTED_MESHES));
            }
            let links: usize = g.iter().map(|m| m.links.len()).sum();
            format!(
                "{} meshes: {kind} ({}); each of their {links} links {DRAWN}",
                g.len(),
                names.join(", ")
            )
        })
        .collect()
}

/// Find the file of one mesh reference; `index` numbers its URL.
fn resolve_mesh(uri: &str, index: usize, base_dir: &Path, packages: &[PackageDir]) -> MeshFile {
    let mut mesh = MeshFile {
        uri: uri.to_string(),
        url: None,
        links: Vec::new(),
        problem: None,
        path: None,
    };
    let ext = Path::new(uri)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if !MESH_TYPES.contains(&ext.as_str()) {
        mesh.problem = Some(format!(
            "the page reads STL, OBJ and DAE meshes, not \"{ext}\""
        ));
        return mesh;
    }
    let path = match mesh_path(uri, base_dir, packages) {
        Ok(p) => p,
        Err(e) => {
            mesh.problem = Some(e.0);
            return mesh;
        }
    };
    if path.is_file() {
        mesh.url = Some(format!("mesh/{index}.{ext}"));
        mesh.path = Some(path);
    } else {
        mesh.problem = Some(format!("file not found: {}", path.display()));
    }
    mesh
}

/// The path a mesh reference points to.
fn mesh_path(uri: &str, base_dir: &Path, packages: &[PackageDir]) -> Result<PathBuf, SceneError> {
    if let Some(rest) = uri.strip_prefix("package://") {
        let (name, rel) = rest.split_once('/').unwrap_or((rest, ""));
        if let Some(p) = packages.iter().find(|p| p.name == name) {
            return Ok(p.dir.join(rel));
        }
        // The ROS layout: the description sits somewhere inside the package folder.
        for dir in base_dir.ancestors() {
            if dir.file_name().is_some_and(|n| n == name) {
                return Ok(dir.join(rel));
            }
        }
        return Err(SceneError(format!(
            "package \"{name}\" is unknown (give --package-dir {name}=DIR)"
        )));
    }
    if let Some(rest) = uri.strip_prefix("file://") {
        return Ok(PathBuf::from(rest));
    }
    if uri.contains("://") {
        return Err(SceneError(
            "only package://, file:// and file paths are read".into(),
        ));
    }
    Ok(base_dir.join(uri))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_dirs_parse() {
        let p = PackageDir::parse("op3_description=/x/y").unwrap();
        assert_eq!(p.name, "op3_description");
        assert_eq!(p.dir, PathBuf::from("/x/y"));
        assert!(
            PackageDir::parse("nodir")
                .unwrap_err()
                .0
                .contains("NAME=DIR")
        );
        assert!(PackageDir::parse("=x").is_err());
    }

    #[test]
    fn mesh_references_resolve() {
        let pk = [PackageDir {
            name: "pkg".into(),
            dir: "/p".into(),
        }];
        let base = Path::new("/robots/urdf");
        assert_eq!(
            mesh_path("package://pkg/meshes/a.stl", base, &pk).unwrap(),
            PathBuf::from("/p/meshes/a.stl")
        );
        assert_eq!(
            mesh_path("meshes/a.stl", base, &pk).unwrap(),
            PathBuf::from("/robots/urdf/meshes/a.stl")
        );
        assert_eq!(
            mesh_path("file:///abs/a.stl", base, &pk).unwrap(),
            PathBuf::from("/abs/a.stl")
        );
        assert_eq!(
            mesh_path("package://robots/m/a.stl", base, &[]).unwrap(),
            PathBuf::from("/robots/m/a.stl")
        );
        assert!(
            mesh_path("package://other/a.stl", base, &[])
                .unwrap_err()
                .0
                .contains("--package-dir other=DIR")
        );
        assert!(mesh_path("http://x/a.stl", base, &[]).is_err());
    }
}
