//! YCB objects as simulated rigid bodies: the collision decomposition split into its convex
//! pieces, recentred, with the catalogue mass (../shared/testdata/objects/README.md).
//!
//! MuJoCo makes one convex hull per mesh geom, so the V-HACD file (64–80 pieces in one STL) is
//! split into connected components and every component becomes its own mesh geom; loaded whole
//! it would lose all concavity (the banana's curve, the mustard bottle's neck).

use crate::SimError;
use nalgebra::{Point3, Vector3};
use std::path::{Path, PathBuf};

/// The objects of the dissertation's Table 5.2, in its order.
pub const TABLE_5_2: [&str; 8] = [
    CHIPS_CAN,
    "tomato_soup_can",
    "tuna_fish_can",
    "potted_meat_can",
    "mustard_bottle",
    "banana",
    "apple",
    "orange",
];

/// The shared objects beyond Table 5.2's eight (two boxes of food, two small boxes, a large
/// can): with them, every object in ../shared/testdata/objects (`--objects all`).
pub const BEYOND_TABLE_5_2: [&str; 5] = [
    "master_chef_can",
    "cracker_box",
    "sugar_box",
    "pudding_box",
    "gelatin_box",
];

/// The chips can (YCB 001): Table 5.2's, from another mirror than the other objects.
pub const CHIPS_CAN: &str = "chips_can";

/// Whether `name` is one of the objects of ../shared/testdata/objects/ycb (YCB 002–011, 013,
/// 017): issue 15's "all 12 shared objects", every object of the standard run but the chips can.
pub fn is_shared_ycb(name: &str) -> bool {
    name != CHIPS_CAN && (TABLE_5_2.contains(&name) || BEYOND_TABLE_5_2.contains(&name))
}

/// One convex piece: its vertices in the object frame, m.
pub type Piece = Vec<Point3<f64>>;

/// A YCB object ready to be placed: convex pieces in a frame with the origin at the centre of the
/// bounding box's footprint, z up and the lowest vertex at z = 0.
#[derive(Debug, Clone)]
pub struct SimObject {
    pub name: String,
    pub pieces: Vec<Piece>,
    /// Catalogue mass from the URDF, kg.
    pub mass: f64,
    /// Axis-aligned extents of the recentred object, m.
    pub extents: Vector3<f64>,
    /// Display colour (mean of the scan's texture; grey when it has none).
    pub rgb: [f32; 3],
}

/// The URDF of `name` and the folder its mesh paths are relative to.
fn urdf_path(objects_dir: &Path, name: &str) -> Result<(PathBuf, PathBuf), SimError> {
    let ycb = objects_dir.join("ycb");
    if name == CHIPS_CAN {
        // The chips can comes from another mirror, with its URDF inside its own folder.
        let dir = ycb.join("001_chips_can");
        return Ok((dir.join("model.urdf"), dir));
    }
    let urdf = ycb.join(format!("{name}.urdf"));
    if !urdf.is_file() {
        return Err(SimError::Input(format!(
            "objects: no object `{name}` ({} missing); known: {}",
            urdf.display(),
            known_objects(objects_dir).join(", ")
        )));
    }
    Ok((urdf, ycb))
}

/// Names of the objects under `objects_dir` (URDF stems, plus the chips can).
pub fn known_objects(objects_dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(objects_dir.join("ycb"))
        .map(|it| {
            it.filter_map(|e| e.ok())
                .filter_map(|e| {
                    let p = e.path();
                    (p.extension()? == "urdf").then(|| p.file_stem()?.to_str().map(String::from))?
                })
                .collect()
        })
        .unwrap_or_default();
    if objects_dir.join("ycb/001_chips_can/model.urdf").is_file() {
        names.push(CHIPS_CAN.into());
    }
    names.sort();
    names
}

impl SimObject {
    /// Loads object `name` (e.g. `tomato_soup_can`) from the YCB folder `objects_dir`.
    pub fn load(objects_dir: &Path, name: &str) -> Result<Self, SimError> {
        let (urdf, base) = urdf_path(objects_dir, name)?;
        let text = std::fs::read_to_string(&urdf)
            .map_err(|e| SimError::Input(format!("objects: {}: {e}", urdf.display())))?;
        let doc = roxmltree::Document::parse(&text)
            .map_err(|e| SimError::Input(format!("objects: {}: {e}", urdf.display())))?;
        let bad = |what: &str| SimError::Input(format!("objects: {}: {what}", urdf.display()));
        let mass: f64 = doc
            .descendants()
            .find(|n| n.has_tag_name("mass"))
            .and_then(|n| n.attribute("value"))
            .and_then(|v| v.trim().parse().ok())
            .ok_or_else(|| bad("no <mass value>"))?;
        let mesh = doc
            .descendants()
            .find(|n| n.has_tag_name("collision"))
            .and_then(|c| c.descendants().find(|n| n.has_tag_name("mesh")))
            .ok_or_else(|| bad("no <collision><mesh>"))?;
        let file = base.join(
            mesh.attribute("filename")
                .ok_or_else(|| bad("mesh filename"))?,
        );
        let scale: Vec<f64> = mesh
            .attribute("scale")
            .unwrap_or("1 1 1")
            .split_whitespace()
            .filter_map(|s| s.parse().ok())
            .collect();
        let scale = match scale[..] {
            [x, y, z] => Vector3::new(x, y, z),
            _ => return Err(bad("mesh scale is not three numbers")),
        };
        let (vertices, triangles) = read_mesh(&file)?;
        let mut pieces = split_components(&vertices, &triangles);
        // Recentre: footprint centre at the origin, lowest vertex at z = 0.
        let all = || pieces.iter().flatten();
        let scaled = |p: &Point3<f64>| Point3::from(p.coords.component_mul(&scale));
        let (mut lo, mut hi) = (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        );
        for p in all() {
            let p = scaled(p);
            lo = lo.inf(&p.coords);
            hi = hi.sup(&p.coords);
        }
        let shift = Vector3::new(-(lo.x + hi.x) / 2.0, -(lo.y + hi.y) / 2.0, -lo.z);
        for piece in &mut pieces {
            for p in piece.iter_mut() {
                *p = scaled(p) + shift;
            }
        }
        let texture = file.with_file_name("texture_map.png");
        Ok(SimObject {
            name: name.to_string(),
            pieces,
            mass,
            extents: hi - lo,
            rgb: mean_colour(&texture).unwrap_or([0.6, 0.6, 0.6]),
        })
    }

    /// Density that gives the catalogue mass over the pieces' convex volumes, kg/m³.
    pub fn density(&self) -> f64 {
        let volume: f64 = self.pieces.iter().map(|p| convex_volume(p)).sum();
        self.mass / volume.max(1e-9)
    }
}

/// A generated primitive object for grasp labels on shapes beyond the YCB scans
/// (`labels.rs`): by `seed`, a box (20–90 × 20–90 × 20–120 mm), an upright cylinder (25–90 mm
/// across, 30–130 mm tall) or a lying one (25–80 mm across, 60–160 mm long), of a density of
/// 300–900 kg/m³; one convex piece, recentred as the YCB objects are.
pub fn primitive(seed: u64) -> SimObject {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_0b1e);
    let mut u = |lo: f64, hi: f64| rng.random_range(lo..hi);
    let kind = (u(0.0, 3.0)) as usize;
    let ring = |r: f64, along: &dyn Fn(f64, f64) -> Point3<f64>| -> Vec<Point3<f64>> {
        (0..24)
            .map(|k| {
                let a = k as f64 / 24.0 * std::f64::consts::TAU;
                along(r * a.cos(), r * a.sin())
            })
            .collect()
    };
    let (name, piece, volume) = match kind {
        0 => {
            let (w, d, h) = (u(0.02, 0.09), u(0.02, 0.09), u(0.02, 0.12));
            let piece = [-1.0, 1.0]
                .iter()
                .flat_map(|&sx| {
                    [-1.0, 1.0].iter().flat_map(move |&sy| {
                        [0.0, h].map(|z| Point3::new(sx * w / 2.0, sy * d / 2.0, z))
                    })
                })
                .collect();
            let name = format!("box_{:.0}x{:.0}x{:.0}", w * 1e3, d * 1e3, h * 1e3);
            (name, piece, w * d * h)
        }
        1 => {
            let (r, h) = (u(0.0125, 0.045), u(0.03, 0.13));
            let mut piece = ring(r, &|x, y| Point3::new(x, y, 0.0));
            piece.extend(ring(r, &|x, y| Point3::new(x, y, h)));
            let name = format!("cylinder_{:.0}x{:.0}", 2e3 * r, h * 1e3);
            (name, piece, std::f64::consts::PI * r * r * h)
        }
        _ => {
            let (r, l) = (u(0.0125, 0.04), u(0.06, 0.16));
            let mut piece = ring(r, &|y, z| Point3::new(-l / 2.0, y, z + r));
            piece.extend(ring(r, &|y, z| Point3::new(l / 2.0, y, z + r)));
            let name = format!("lying_cylinder_{:.0}x{:.0}", 2e3 * r, l * 1e3);
            (name, piece, std::f64::consts::PI * r * r * l)
        }
    };
    let density = u(300.0, 900.0);
    let grey = u(0.3, 0.8) as f32;
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for p in &piece {
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    SimObject {
        name,
        pieces: vec![piece],
        mass: density * volume,
        extents: hi - lo,
        rgb: [grey, grey * 0.9, grey * 0.8],
    }
}

/// Vertices and triangles of an STL (binary or ASCII) or OBJ file.
/// A triangle soup: vertices and vertex-index triples.
type Soup = (Vec<Point3<f64>>, Vec<[usize; 3]>);

fn read_mesh(path: &Path) -> Result<Soup, SimError> {
    let bad = |e: String| SimError::Input(format!("objects: {}: {e}", path.display()));
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
    {
        let (models, _) = tobj::load_obj(
            path,
            &tobj::LoadOptions {
                triangulate: true,
                single_index: true,
                ..Default::default()
            },
        )
        .map_err(|e| bad(e.to_string()))?;
        let (mut v, mut t) = (Vec::new(), Vec::new());
        for m in models {
            let base = v.len();
            v.extend(
                m.mesh
                    .positions
                    .chunks_exact(3)
                    .map(|c| Point3::new(c[0] as f64, c[1] as f64, c[2] as f64)),
            );
            t.extend(m.mesh.indices.chunks_exact(3).map(|c| {
                [
                    base + c[0] as usize,
                    base + c[1] as usize,
                    base + c[2] as usize,
                ]
            }));
        }
        return Ok((v, t));
    }
    let mut file = std::fs::File::open(path).map_err(|e| bad(e.to_string()))?;
    let mesh = stl_io::read_stl(&mut file).map_err(|e| bad(e.to_string()))?;
    let v = mesh
        .vertices
        .iter()
        .map(|p| Point3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect();
    let t = mesh.faces.iter().map(|f| f.vertices).collect();
    Ok((v, t))
}

/// Splits a triangle soup into its closed pieces. V-HACD writes its pieces one after another,
/// each a closed surface, so a piece ends where every edge seen since its start has been seen
/// twice (edges keyed by vertex position on a 0.01 mm grid, since STL repeats positions per
/// triangle; neighbouring pieces touch, so connectivity alone would merge them). One vertex list
/// per piece; pieces with fewer than 4 distinct vertices cannot make a hull and are dropped.
pub fn split_components(vertices: &[Point3<f64>], triangles: &[[usize; 3]]) -> Vec<Piece> {
    use std::collections::{BTreeSet, HashMap, HashSet};
    let key = |p: &Point3<f64>| {
        (
            (p.x * 1e5).round() as i64,
            (p.y * 1e5).round() as i64,
            (p.z * 1e5).round() as i64,
        )
    };
    let mut canon = HashMap::new();
    let id: Vec<usize> = vertices
        .iter()
        .enumerate()
        .map(|(i, p)| *canon.entry(key(p)).or_insert(i))
        .collect();
    let mut pieces = Vec::new();
    let mut open: HashSet<(usize, usize)> = HashSet::new();
    let mut current: BTreeSet<usize> = BTreeSet::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (id[tri[k]], id[tri[(k + 1) % 3]]);
            let e = (a.min(b), a.max(b));
            if !open.remove(&e) {
                open.insert(e);
            }
            current.insert(a);
        }
        if open.is_empty() || t + 1 == triangles.len() {
            if current.len() >= 4 {
                pieces.push(current.iter().map(|&i| vertices[i]).collect());
            }
            current.clear();
            open.clear();
        }
    }
    pieces
}

/// Volume of the convex hull of `points`, m³ (0 when degenerate).
pub fn convex_volume(points: &[Point3<f64>]) -> f64 {
    use parry3d_f64::shape::{ConvexPolyhedron, Shape};
    let pts: Vec<_> = points
        .iter()
        .map(|p| parry3d_f64::math::Vector::new(p.x, p.y, p.z))
        .collect();
    ConvexPolyhedron::from_convex_hull(&pts)
        .map(|c| c.mass_properties(1.0).mass())
        .unwrap_or(0.0)
}

/// Mean colour of a texture image (downsampled reading; decoding the 2048² PNG takes ~0.1 s).
fn mean_colour(path: &Path) -> Option<[f32; 3]> {
    let img = image::open(path).ok()?.to_rgb8();
    let (mut sum, mut n) = ([0f64; 3], 0f64);
    for (x, y, p) in img.enumerate_pixels() {
        if x % 8 != 0 || y % 8 != 0 {
            continue;
        }
        // The texture atlas pads with black; skip it.
        if p.0.iter().all(|&c| c < 8) {
            continue;
        }
        for (s, &c) in sum.iter_mut().zip(&p.0) {
            *s += c as f64;
        }
        n += 1.0;
    }
    (n > 0.0).then(|| sum.map(|s| (s / n / 255.0) as f32))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra(o: Vector3<f64>) -> (Vec<Point3<f64>>, Vec<[usize; 3]>) {
        let v = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
        ]
        .map(|p| p + o)
        .to_vec();
        (v, vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])
    }

    #[test]
    fn two_tetrahedra_make_two_pieces_of_volume_one_sixth() {
        let (mut v, mut t) = tetra(Vector3::zeros());
        let (v2, t2) = tetra(Vector3::new(5.0, 0.0, 0.0));
        t.extend(t2.iter().map(|f| f.map(|i| i + v.len())));
        v.extend(v2);
        let pieces = split_components(&v, &t);
        assert_eq!(pieces.len(), 2);
        for p in &pieces {
            assert_eq!(p.len(), 4);
            assert!((convex_volume(p) - 1.0 / 6.0).abs() < 1e-9);
        }
    }
}

#[cfg(test)]
mod ycb_tests {
    use super::*;

    fn objects_dir() -> Option<PathBuf> {
        let d = graspd_testkit::testdata_dir().join("objects");
        d.is_dir().then_some(d)
    }

    #[test]
    fn tomato_soup_can_has_its_catalogue_size_and_a_plausible_density() {
        let Some(dir) = objects_dir() else {
            eprintln!("skipped: the shared test data's objects/ not found");
            return;
        };
        let can = SimObject::load(&dir, "tomato_soup_can").unwrap();
        // objects/README.md: 67.9 x 67.7 x 101.9 mm (visual mesh; the V-HACD hull is ~2 mm
        // narrower), 66 V-HACD pieces, 0.349 kg.
        assert!((can.extents.x - 0.0679).abs() < 0.004, "{:?}", can.extents);
        assert!((can.extents.z - 0.1019).abs() < 0.002, "{:?}", can.extents);
        assert!(can.pieces.len() >= 30, "{} pieces", can.pieces.len());
        // Volume of a 67.8 mm x 101.9 mm cylinder: 0.368 l -> ~950 kg/m³.
        let d = can.density();
        assert!((700.0..1300.0).contains(&d), "density {d}");
        let lowest = can
            .pieces
            .iter()
            .flatten()
            .map(|p| p.z)
            .fold(f64::INFINITY, f64::min);
        assert!(lowest.abs() < 1e-9);
    }
}
