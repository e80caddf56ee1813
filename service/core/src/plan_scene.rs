//! A plan as a 3D scene, written as binary glTF 2.0 (GLB) that any viewer opens (issue 20):
//! the object's points, the support plane, the contacts with their normals, the opposition, and
//! — for a hand with kinematics — the hand posed at the pre-grasp, grasp and squeeze
//! configurations from its own collision geometry (the convex pieces the planner checks:
//! `hand::kinematics::collision_model`). One builder serves REST `?format=glb`, gRPC
//! `output.scene_glb` and `graspctl plan --glb`.
//!
//! Layout: one node per drawn thing, named for what it is — `cloud`, `support_plane`,
//! `contacts`, `contact_normals`, `opposition`, and `<configuration>/<body>/<piece>` for the hand
//! (`pregrasp`, `grasp`, `squeeze`). A hand piece's mesh is in its shape's own frame and its
//! node carries the piece's pose in the world: root pose × forward kinematics of the body ×
//! the piece's pose on the body, so a viewer (or a test) reads where each link sits from the
//! node's translation and rotation. The other meshes are in the world frame (identity nodes).
//! Units are metres; the frame is the plan's.

use crate::planning::{GraspPlan, KinematicModel, Pose};
use nalgebra::{Isometry3, Point3};
use parry3d_f64::shape::SharedShape;
use serde_json::{Value, json};

/// glTF primitive modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    Points = 0,
    Lines = 1,
    Triangles = 4,
}

/// Vertices (and, for triangles and lines, indices) in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    pub mode: Mode,
    pub positions: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
}

/// A drawn thing: a geometry with a colour, placed by a pose.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneNode {
    pub name: String,
    pub geometry: usize,
    /// Linear RGBA.
    pub color: [f32; 4],
    pub pose: Isometry3<f64>,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    pub geometries: Vec<Geometry>,
    pub nodes: Vec<SceneNode>,
}

const CLOUD: [f32; 4] = [0.55, 0.55, 0.6, 1.0];
const PLANE: [f32; 4] = [0.8, 0.8, 0.75, 0.5];
const CONTACT: [f32; 4] = [0.9, 0.1, 0.1, 1.0];
const OPPOSITION: [f32; 4] = [0.1, 0.3, 0.9, 1.0];
/// The hand per configuration: pre-grasp faint, grasp solid, squeeze tinted.
const HANDS: [(&str, [f32; 4]); 3] = [
    ("pregrasp", [0.3, 0.7, 0.3, 0.25]),
    ("grasp", [0.85, 0.65, 0.3, 1.0]),
    ("squeeze", [0.7, 0.3, 0.6, 0.45]),
];
/// Drawn length of a contact normal, m.
const NORMAL_LENGTH: f64 = 0.015;
/// Half the side of the drawn support plane, m.
const PLANE_HALF: f64 = 0.15;

fn f3(p: &Point3<f64>) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

impl Scene {
    fn add(&mut self, name: &str, geometry: Geometry, color: [f32; 4]) {
        self.geometries.push(geometry);
        self.nodes.push(SceneNode {
            name: name.to_string(),
            geometry: self.geometries.len() - 1,
            color,
            pose: Isometry3::identity(),
        });
    }
}

/// The scene of a plan on `points` (module rules); the hand is drawn when `kinematics` is the
/// plan's hand model and the plan carries its root pose.
pub fn plan_scene(
    points: &[Point3<f64>],
    plan: &GraspPlan,
    kinematics: Option<&KinematicModel>,
) -> Scene {
    let mut scene = Scene::default();
    scene.add(
        "cloud",
        Geometry {
            mode: Mode::Points,
            positions: points.iter().map(f3).collect(),
            indices: Vec::new(),
        },
        CLOUD,
    );
    if let Some(plane) = &plan.support_plane
        && !points.is_empty()
    {
        let n = plane.normal.normalize();
        let centre = crate::cloud::point_cloud::centroid(points);
        let on = centre - n * (n.dot(&centre.coords) + plane.offset);
        let (u, v) = crate::cloud::tangents(&n);
        let corner = |a: f64, b: f64| f3(&(on + (u * a + v * b) * PLANE_HALF));
        scene.add(
            "support_plane",
            Geometry {
                mode: Mode::Triangles,
                positions: vec![
                    corner(-1.0, -1.0),
                    corner(1.0, -1.0),
                    corner(1.0, 1.0),
                    corner(-1.0, 1.0),
                ],
                indices: vec![0, 1, 2, 0, 2, 3, 0, 2, 1, 0, 3, 2],
            },
            PLANE,
        );
    }
    if !plan.contacts.is_empty() {
        scene.add(
            "contacts",
            Geometry {
                mode: Mode::Points,
                positions: plan.contacts.iter().map(|c| f3(&c.position)).collect(),
                indices: Vec::new(),
            },
            CONTACT,
        );
        let mut normals = Geometry {
            mode: Mode::Lines,
            positions: Vec::new(),
            indices: Vec::new(),
        };
        for c in &plan.contacts {
            let k = normals.positions.len() as u32;
            normals.positions.push(f3(&c.position));
            normals
                .positions
                .push(f3(&(c.position + c.normal.normalize() * NORMAL_LENGTH)));
            normals.indices.extend([k, k + 1]);
        }
        scene.add("contact_normals", normals, CONTACT);
    }
    let [a, b] = plan.opposition.points;
    scene.add(
        "opposition",
        Geometry {
            mode: Mode::Lines,
            positions: vec![f3(&a), f3(&b)],
            indices: vec![0, 1],
        },
        OPPOSITION,
    );
    if let (Some(model), Some(root)) = (kinematics, plan.root_pose) {
        add_hand(&mut scene, model, plan, &root);
    }
    scene
}

/// The hand at the pre-grasp, grasp and squeeze configurations (each when planned).
fn add_hand(scene: &mut Scene, model: &KinematicModel, plan: &GraspPlan, root: &Pose) {
    let tree = &model.hand.tree;
    let first = scene.geometries.len();
    for piece in &model.collision.pieces {
        scene.geometries.push(piece_geometry(&piece.shape));
    }
    // The pre-grasp root: the hand frame moved from the grasp to the pre-grasp, the model with it.
    let pre_root =
        plan.pregrasp_pose.isometry() * plan.hand_pose.isometry().inverse() * root.isometry();
    let configurations = [
        (&plan.pregrasp_joints, pre_root),
        (&plan.joints, root.isometry()),
        (&plan.squeeze_joints, root.isometry()),
    ];
    for ((name, color), (joints, root)) in HANDS.iter().zip(configurations) {
        if joints.is_empty() {
            continue;
        }
        let q: Vec<f64> = tree
            .joints
            .iter()
            .map(|j| {
                joints
                    .iter()
                    .find(|(n, _)| *n == j.name)
                    .map_or(0.0, |(_, a)| *a)
            })
            .collect();
        let Ok(fk) = tree.forward(&q) else {
            continue;
        };
        for (k, piece) in model.collision.pieces.iter().enumerate() {
            scene.nodes.push(SceneNode {
                name: format!("{name}/{}/{k}", tree.bodies[piece.body].name),
                geometry: first + k,
                color: *color,
                pose: root * fk.body_poses[piece.body] * piece.pose,
            });
        }
    }
}

/// A convex piece's triangles in its own frame.
fn piece_geometry(shape: &SharedShape) -> Geometry {
    let (vertices, triangles) = if let Some(s) = shape.as_ball() {
        s.to_trimesh(12, 8)
    } else if let Some(s) = shape.as_cuboid() {
        s.to_trimesh()
    } else if let Some(s) = shape.as_capsule() {
        s.to_trimesh(12, 6)
    } else if let Some(s) = shape.as_cylinder() {
        s.to_trimesh(16)
    } else if let Some(s) = shape.as_convex_polyhedron() {
        s.to_trimesh()
    } else {
        (Vec::new(), Vec::new())
    };
    Geometry {
        mode: Mode::Triangles,
        positions: vertices
            .iter()
            .map(|v| [v.x as f32, v.y as f32, v.z as f32])
            .collect(),
        indices: triangles.iter().flatten().copied().collect(),
    }
}

/// The scene as GLB: a JSON chunk and one binary buffer (positions as float32 VEC3 with their
/// bounds, indices as uint32), a material per node colour (alpha blended below 1).
pub fn to_glb(scene: &Scene) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut meshes = Vec::new();
    let mut materials: Vec<Value> = Vec::new();
    let mut material_of = |color: [f32; 4]| -> usize {
        let m = json!({
            "pbrMetallicRoughness": {"baseColorFactor": color, "metallicFactor": 0.0,
                                     "roughnessFactor": 0.9},
            "alphaMode": if color[3] < 1.0 { "BLEND" } else { "OPAQUE" },
            "doubleSided": true,
        });
        match materials.iter().position(|x| *x == m) {
            Some(i) => i,
            None => {
                materials.push(m);
                materials.len() - 1
            }
        }
    };
    // Geometry → (position accessor, index accessor); empty geometries are not written.
    let mut written: Vec<Option<(usize, Option<usize>)>> = Vec::new();
    for g in &scene.geometries {
        if g.positions.is_empty() {
            written.push(None);
            continue;
        }
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let offset = bin.len();
        for p in &g.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
                bin.extend_from_slice(&p[k].to_le_bytes());
            }
        }
        views.push(
            json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset,
                          "target": 34962}),
        );
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126,
                              "count": g.positions.len(), "type": "VEC3", "min": lo, "max": hi}));
        let position = accessors.len() - 1;
        let index = (!g.indices.is_empty()).then(|| {
            let offset = bin.len();
            for i in &g.indices {
                bin.extend_from_slice(&i.to_le_bytes());
            }
            views.push(json!({"buffer": 0, "byteOffset": offset,
                              "byteLength": bin.len() - offset, "target": 34963}));
            accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5125,
                                  "count": g.indices.len(), "type": "SCALAR"}));
            accessors.len() - 1
        });
        written.push(Some((position, index)));
    }
    let mut nodes = Vec::new();
    for n in &scene.nodes {
        let Some(Some((position, index))) = written.get(n.geometry) else {
            continue;
        };
        let mut primitive = json!({"attributes": {"POSITION": position},
                                   "mode": scene.geometries[n.geometry].mode as u32,
                                   "material": material_of(n.color)});
        if let Some(i) = index {
            primitive["indices"] = json!(i);
        }
        meshes.push(json!({"name": n.name, "primitives": [primitive]}));
        let t = n.pose.translation.vector;
        let r = n.pose.rotation;
        nodes.push(json!({"name": n.name, "mesh": meshes.len() - 1,
                          "translation": [t.x, t.y, t.z],
                          "rotation": [r.i, r.j, r.k, r.w]}));
    }
    let document = json!({
        "asset": {"version": "2.0", "generator": "graspd"},
        "scene": 0,
        "scenes": [{"name": "plan", "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    let mut text = serde_json::to_vec(&document).expect("a JSON value serialises");
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut glb = Vec::with_capacity(total);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(text.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&text);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    glb
}
