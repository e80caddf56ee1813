//! The YCB objects of the shared test data and their meshes.
//!
//! Meshes are in metres, z up, and stand on z = 0; the origin is the YCB scanner's, not the
//! object's centre (e.g. the tomato soup can spans y = +50 … +118 mm). Visual meshes
//! (`google_16k/textured.obj`, ~16k triangles) are used as stored. The chips can has only its
//! collision mesh (`001_chips_can/collision_vhacd.obj`); it is scaled by (0.95, 0.95, 1.0) as
//! its URDF says and then lowered by 5.7 mm, the gap its mesh leaves under it, so that it too
//! stands on the table.

use crate::{Result, TestkitError, testdata_dir};
use nalgebra::Point3;
use parry3d_f64::math::Vector;
use parry3d_f64::shape::TriMesh;
use std::collections::HashMap;
use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::{Arc, Mutex, OnceLock};

/// The 13 YCB objects of the test data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Object {
    ChipsCan,
    MasterChefCan,
    CrackerBox,
    SugarBox,
    TomatoSoupCan,
    MustardBottle,
    TunaFishCan,
    PuddingBox,
    GelatinBox,
    PottedMeatCan,
    Banana,
    Apple,
    Orange,
}

impl Object {
    /// All objects, in YCB order.
    pub const ALL: [Object; 13] = [
        Object::ChipsCan,
        Object::MasterChefCan,
        Object::CrackerBox,
        Object::SugarBox,
        Object::TomatoSoupCan,
        Object::MustardBottle,
        Object::TunaFishCan,
        Object::PuddingBox,
        Object::GelatinBox,
        Object::PottedMeatCan,
        Object::Banana,
        Object::Apple,
        Object::Orange,
    ];

    /// The eight objects of the dissertation's grasping evaluation (Table 5.2).
    pub const TABLE_5_2: [Object; 8] = [
        Object::ChipsCan,
        Object::TomatoSoupCan,
        Object::TunaFishCan,
        Object::PottedMeatCan,
        Object::MustardBottle,
        Object::Banana,
        Object::Apple,
        Object::Orange,
    ];

    /// The YCB id, which is also the folder name, e.g. `005_tomato_soup_can`.
    pub fn id(self) -> &'static str {
        match self {
            Object::ChipsCan => "001_chips_can",
            Object::MasterChefCan => "002_master_chef_can",
            Object::CrackerBox => "003_cracker_box",
            Object::SugarBox => "004_sugar_box",
            Object::TomatoSoupCan => "005_tomato_soup_can",
            Object::MustardBottle => "006_mustard_bottle",
            Object::TunaFishCan => "007_tuna_fish_can",
            Object::PuddingBox => "008_pudding_box",
            Object::GelatinBox => "009_gelatin_box",
            Object::PottedMeatCan => "010_potted_meat_can",
            Object::Banana => "011_banana",
            Object::Apple => "013_apple",
            Object::Orange => "017_orange",
        }
    }

    /// The id without its number, e.g. `tomato_soup_can` (file names of the examples).
    pub fn short_name(self) -> &'static str {
        &self.id()[4..]
    }

    /// Path of the mesh this kit loads for the object.
    pub fn mesh_path(self) -> PathBuf {
        let dir = testdata_dir().join("objects/ycb").join(self.id());
        match self {
            Object::ChipsCan => dir.join("collision_vhacd.obj"),
            _ => dir.join("google_16k/textured.obj"),
        }
    }

    /// Scale applied on loading (the chips can's URDF scale; 1 otherwise).
    pub fn scale(self) -> [f64; 3] {
        match self {
            Object::ChipsCan => [0.95, 0.95, 1.0],
            _ => [1.0; 3],
        }
    }
}

impl fmt::Display for Object {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

impl FromStr for Object {
    type Err = TestkitError;

    /// Accepts the id (`005_tomato_soup_can`) or the short name (`tomato_soup_can`).
    fn from_str(s: &str) -> Result<Self> {
        Object::ALL
            .into_iter()
            .find(|o| o.id() == s || o.short_name() == s)
            .ok_or_else(|| {
                TestkitError(format!(
                    "unknown YCB object \"{s}\"; known: {}",
                    Object::ALL.map(Object::id).join(", ")
                ))
            })
    }
}

/// How the OBJ files are read: triangulated faces, positions and texture coordinates indexed
/// apart ([`crate::texture`] reads the same triangles in the same order).
pub fn obj_load_options() -> tobj::LoadOptions {
    // `..Default::default()` covers the fields that tobj's optional "merging"/"reordering"
    // features add, should another crate turn them on.
    #[allow(clippy::needless_update)]
    tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    }
}

/// Loads the object's mesh from the test data (uncached; see [`mesh`]). All OBJ groups are
/// merged into one triangle mesh; faces are triangulated.
pub fn load_mesh(object: Object) -> Result<TriMesh> {
    let path = object.mesh_path();
    let (models, _materials) = tobj::load_obj(&path, &obj_load_options()).map_err(|e| {
        TestkitError(format!(
            "cannot load {} ({e}); is the test data there? Set GRASPD_TESTDATA to the folder \
             holding objects/ycb",
            path.display()
        ))
    })?;
    let s = object.scale();
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for m in &models {
        let base = vertices.len() as u32;
        vertices.extend(
            m.mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vector::new(p[0] as f64 * s[0], p[1] as f64 * s[1], p[2] as f64 * s[2])),
        );
        indices.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if object == Object::ChipsCan {
        // Stand it on the table (its collision mesh starts 5.7 mm above z = 0).
        let min_z = vertices.iter().map(|v| v.z).fold(f64::INFINITY, f64::min);
        for v in &mut vertices {
            v.z -= min_z;
        }
    }
    TriMesh::new(vertices, indices)
        .map_err(|e| TestkitError(format!("{}: not a usable mesh: {e:?}", path.display())))
}

/// The object's mesh, loaded once per process and shared.
pub fn mesh(object: Object) -> Result<Arc<TriMesh>> {
    static CACHE: OnceLock<Mutex<HashMap<Object, Arc<TriMesh>>>> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    let mut map = cache.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(m) = map.get(&object) {
        return Ok(m.clone());
    }
    let m = Arc::new(load_mesh(object)?);
    map.insert(object, m.clone());
    Ok(m)
}

/// How far a contact on the completed, unseen side (`Contact::inferred`) may lie from the
/// true surface, m: the YCB objects are only nearly symmetric, and a flat object seen across its
/// broad side is completed deeper than it is (the mustard bottle by about 2 cm; see
/// docs/final-configuration.md, "Completing the unseen side").
pub const MAX_INFERRED_OFF: f64 = 0.025;

/// Distance of `p` (in the mesh's frame, the frame of the views) from `object`'s surface, m.
pub fn surface_distance(object: Object, p: &nalgebra::Point3<f64>) -> f64 {
    let m = mesh(object).unwrap_or_else(|e| panic!("{e}"));
    use parry3d_f64::query::PointQuery;
    m.distance_to_local_point(parry3d_f64::math::Vector::new(p.x, p.y, p.z), false)
        .abs()
}

/// Axis-aligned bounding box of a mesh, (min, max).
pub fn mesh_aabb(mesh: &TriMesh) -> (Point3<f64>, Point3<f64>) {
    let (lo, hi) = mesh.vertices().iter().fold(
        (
            Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
            Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
        ),
        |(lo, hi), v| {
            (
                Point3::new(lo.x.min(v.x), lo.y.min(v.y), lo.z.min(v.z)),
                Point3::new(hi.x.max(v.x), hi.y.max(v.y), hi.z.max(v.z)),
            )
        },
    );
    (lo, hi)
}

/// Signed volume of a closed mesh (positive when its triangles wind counter-clockwise seen from
/// outside, i.e. their right-hand normals point out).
pub fn signed_volume(mesh: &TriMesh) -> f64 {
    let v = mesh.vertices();
    mesh.indices()
        .iter()
        .map(|t| {
            let (a, b, c) = (v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for o in Object::ALL {
            assert_eq!(o.id().parse::<Object>().unwrap(), o);
            assert_eq!(o.short_name().parse::<Object>().unwrap(), o);
        }
        assert!("006_ketchup".parse::<Object>().is_err());
    }

    #[test]
    fn tomato_can_matches_the_readme() {
        let m = mesh(Object::TomatoSoupCan).unwrap();
        assert_eq!(m.indices().len(), 16384);
        let (lo, hi) = mesh_aabb(&m);
        let size = hi - lo;
        // README: 67.9 x 67.7 x 101.9 mm, min corner (-43.1, 50.1, 0.1) mm.
        assert!((size.x - 0.0679).abs() < 5e-4, "{size}");
        assert!((size.z - 0.1019).abs() < 5e-4, "{size}");
        assert!((lo.y - 0.0501).abs() < 5e-4, "{lo}");
        assert!(signed_volume(&m) > 0.0, "outward winding");
    }

    #[test]
    fn chips_can_is_scaled_and_stands_on_the_table() {
        let m = load_mesh(Object::ChipsCan).unwrap();
        let (lo, hi) = mesh_aabb(&m);
        assert!(lo.z.abs() < 1e-9);
        assert!((hi.z - 0.2416).abs() < 5e-4, "{hi}");
        assert!(((hi.x - lo.x) - 0.0786 * 0.95).abs() < 5e-4, "{lo} {hi}");
    }
}
