//! Collision meshes become primitives: quadcl's contacts are with flat
//! ground only, where a mesh's extent is what matters.
//!
//! - A mesh path resolves as ROS tools do: `package://PKG/REL` against the
//!   URDF's folder and each folder above it (`DIR/REL`, `DIR/PKG/REL`, or
//!   `REL` below a folder named PKG), `file://ABS`, or a path relative to
//!   the URDF's folder.
//! - A found STL (binary or ASCII) or OBJ mesh becomes the box of its
//!   vertices' bounds (with the URDF `scale`), or the sphere of half its
//!   mean extent when those bounds are nearly a cube (a foot). MuJoCo would
//!   use the convex hull; against flat ground the two differ little.
//! - A missing or unreadable mesh is dropped when the link has other
//!   collision geometry, else replaced by the box with the link's inertia
//!   (a solid box of the link's mass: `a = sqrt(6 (Iyy + Izz - Ixx) / m)`).
//!
//! Every replacement is a warning; visuals are not used and are dropped.

use rapier3d_urdf::urdf_rs::{Collision, Geometry, Link, Pose, Vec3};
use std::path::{Path, PathBuf};

/// Replaces each mesh collision of every link by a primitive, pushing a warning each.
pub(super) fn replace_meshes(links: &mut [Link], urdf_path: &Path, warnings: &mut Vec<String>) {
    let dir = urdf_path.parent().unwrap_or(Path::new("."));
    for link in links {
        let has_primitive = link.collision.iter().any(|c| !matches!(c.geometry, Geometry::Mesh { .. }));
        let mut replaced = Vec::new();
        for c in std::mem::take(&mut link.collision) {
            let Geometry::Mesh { filename, scale } = &c.geometry else {
                replaced.push(c);
                continue;
            };
            let scale = scale.as_ref().map_or([1.0; 3], |s| s.0);
            let found = resolve(filename, dir);
            let bounds = found.as_deref().map(|p| mesh_bounds(p).map(|b| (p.to_path_buf(), b)));
            match bounds {
                Some(Ok((path, (lo, hi)))) => {
                    let lo: [f64; 3] = std::array::from_fn(|i| lo[i] * scale[i]);
                    let hi: [f64; 3] = std::array::from_fn(|i| hi[i] * scale[i]);
                    let centre: [f64; 3] = std::array::from_fn(|i| 0.5 * (lo[i] + hi[i]));
                    let size: [f64; 3] = std::array::from_fn(|i| (hi[i] - lo[i]).abs());
                    let origin =
                        super::urdf_merge::compose(&c.origin, &Pose { xyz: Vec3(centre), rpy: Vec3([0.0; 3]) });
                    let (geometry, what) = primitive_of_bounds(size);
                    warnings.push(format!(
                        "link '{}': collision mesh {} replaced by {what}",
                        link.name,
                        path.display()
                    ));
                    replaced.push(Collision { name: c.name.clone(), origin, geometry });
                }
                other => {
                    let why = match other {
                        Some(Err(e)) => format!("cannot be read ({e})"),
                        _ => "was not found".to_string(),
                    };
                    if has_primitive {
                        warnings.push(format!(
                            "link '{}': collision mesh '{filename}' {why}; the link's other collision shapes are used",
                            link.name
                        ));
                    } else if let Some(geometry) = inertia_box(link) {
                        warnings.push(format!(
                            "link '{}': collision mesh '{filename}' {why}; replaced by the box of the link's inertia",
                            link.name
                        ));
                        replaced.push(Collision {
                            name: c.name.clone(),
                            origin: link.inertial.origin.clone(),
                            geometry,
                        });
                    } else {
                        warnings.push(format!(
                            "link '{}': collision mesh '{filename}' {why}, and the link has no mass to size a box; it has no collision shape",
                            link.name
                        ));
                    }
                }
            }
        }
        link.collision = replaced;
        link.visual.clear();
    }
}

/// Where a URDF mesh filename points, if a file is there.
fn resolve(filename: &str, urdf_dir: &Path) -> Option<PathBuf> {
    if let Some(abs) = filename.strip_prefix("file://") {
        return Some(PathBuf::from(abs)).filter(|p| p.is_file());
    }
    let Some(rest) = filename.strip_prefix("package://") else {
        let p = Path::new(filename);
        let p = if p.is_absolute() { p.to_path_buf() } else { urdf_dir.join(p) };
        return Some(p).filter(|p| p.is_file());
    };
    let (package, rel) = rest.split_once('/').unwrap_or((rest, ""));
    urdf_dir.ancestors().find_map(|a| {
        let named = a.file_name().is_some_and(|n| n == package);
        [named.then(|| a.join(rel)), Some(a.join(package).join(rel)), Some(a.join(rel))]
            .into_iter()
            .flatten()
            .find(|p| p.is_file())
    })
}

/// The box of a size, or a sphere when the size is nearly a cube.
fn primitive_of_bounds(size: [f64; 3]) -> (Geometry, String) {
    let (min, max) = (size.iter().cloned().fold(f64::MAX, f64::min), size.iter().cloned().fold(0.0, f64::max));
    if min > 0.8 * max {
        let radius = (size[0] + size[1] + size[2]) / 6.0;
        (Geometry::Sphere { radius }, format!("a sphere of radius {radius:.4} m (its bounds are nearly a cube)"))
    } else {
        let s = size.map(|v| v.max(1e-4));
        (Geometry::Box { size: Vec3(s) }, format!("the box of its bounds, {:.3} x {:.3} x {:.3} m", s[0], s[1], s[2]))
    }
}

/// The solid box with the link's mass and principal inertias (diagonal taken as principal).
fn inertia_box(link: &Link) -> Option<Geometry> {
    let (m, i) = (link.inertial.mass.value, &link.inertial.inertia);
    if m <= 0.0 {
        return None;
    }
    let side = |a: f64, b: f64, c: f64| (6.0 * (a + b - c) / m).max(0.0).sqrt().max(1e-3);
    Some(Geometry::Box {
        size: Vec3([side(i.iyy, i.izz, i.ixx), side(i.ixx, i.izz, i.iyy), side(i.ixx, i.iyy, i.izz)]),
    })
}

/// The lower and upper corners of a mesh's vertices (STL binary or ASCII, OBJ).
fn mesh_bounds(path: &Path) -> anyhow::Result<([f64; 3], [f64; 3])> {
    let bytes = std::fs::read(path)?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let points: Vec<[f64; 3]> = match ext.as_str() {
        "stl" if !bytes.starts_with(b"solid") || !ascii_stl(&bytes) => binary_stl(&bytes)?,
        "stl" => text_vertices(&bytes, "vertex"),
        "obj" => text_vertices(&bytes, "v"),
        other => anyhow::bail!("'{other}' meshes are not read (STL and OBJ are)"),
    };
    anyhow::ensure!(!points.is_empty(), "no vertices");
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in points {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    Ok((lo, hi))
}

/// Binary STLs sometimes start with "solid" too: ASCII ones contain "facet".
fn ascii_stl(bytes: &[u8]) -> bool {
    bytes.windows(5).take(1024).any(|w| w == b"facet")
}

fn binary_stl(bytes: &[u8]) -> anyhow::Result<Vec<[f64; 3]>> {
    anyhow::ensure!(bytes.len() >= 84, "a binary STL of {} bytes (under the 84-byte header)", bytes.len());
    let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    anyhow::ensure!(bytes.len() >= 84 + 50 * count, "a binary STL that claims {count} triangles but is cut short");
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as f64;
    Ok((0..count)
        .flat_map(|t| (1..4).map(move |v| 84 + 50 * t + 12 * v))
        .map(|o| [f(o), f(o + 4), f(o + 8)])
        .filter(|p| p.iter().all(|v| v.is_finite()))
        .collect())
}

fn text_vertices(bytes: &[u8], keyword: &str) -> Vec<[f64; 3]> {
    String::from_utf8_lossy(bytes)
        .lines()
        .filter_map(|line| {
            let mut words = line.split_whitespace();
            (words.next()? == keyword).then_some(())?;
            let v: Vec<f64> = words.take(3).filter_map(|w| w.parse().ok()).collect();
            (v.len() == 3 && v.iter().all(|x| x.is_finite())).then(|| [v[0], v[1], v[2]])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_paths_resolve_against_the_folders_above_the_urdf() {
        let dir = tempfile::tempdir().unwrap();
        let pkg = dir.path().join("my_robot");
        std::fs::create_dir_all(pkg.join("urdf")).unwrap();
        std::fs::create_dir_all(pkg.join("meshes")).unwrap();
        std::fs::write(pkg.join("meshes/foot.obj"), "v 0 0 0\n").unwrap();
        let urdf_dir = pkg.join("urdf");
        let found = resolve("package://my_robot/meshes/foot.obj", &urdf_dir).unwrap();
        assert_eq!(found, pkg.join("meshes/foot.obj"));
        assert_eq!(resolve("../meshes/foot.obj", &urdf_dir).unwrap(), urdf_dir.join("../meshes/foot.obj"));
        assert!(resolve("package://my_robot/meshes/gone.stl", &urdf_dir).is_none());
    }

    #[test]
    fn an_obj_and_a_binary_stl_give_the_bounds_of_their_vertices() {
        let dir = tempfile::tempdir().unwrap();
        let obj = dir.path().join("a.obj");
        std::fs::write(&obj, "# box\nv -1 0 0\nv 2 1 0.5\nvn 9 9 9\nf 1 2 1\n").unwrap();
        assert_eq!(mesh_bounds(&obj).unwrap(), ([-1.0, 0.0, 0.0], [2.0, 1.0, 0.5]));
        let mut stl = vec![0u8; 80];
        stl.extend(1u32.to_le_bytes());
        stl.extend([0.0f32; 3].iter().flat_map(|v| v.to_le_bytes()));
        for p in [[0.0f32, 0.0, 0.0], [0.1, 0.2, 0.0], [0.0, 0.0, -0.3]] {
            stl.extend(p.iter().flat_map(|v| v.to_le_bytes()));
        }
        stl.extend([0u8; 2]);
        let path = dir.path().join("a.stl");
        std::fs::write(&path, &stl).unwrap();
        let (lo, hi) = mesh_bounds(&path).unwrap();
        assert!((lo[2] + 0.3).abs() < 1e-6 && (hi[1] - 0.2).abs() < 1e-6, "{lo:?} {hi:?}");
        std::fs::write(&path, &stl[..100]).unwrap();
        assert!(format!("{}", mesh_bounds(&path).unwrap_err()).contains("cut short"));
    }
}
