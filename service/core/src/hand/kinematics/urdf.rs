//! Reads a URDF document into a [`KinematicTree`].
//!
//! Links become bodies, a joint's `<origin xyz rpy>` the child's pose relative to the parent
//! (rpy = fixed-axis roll about x, then pitch about y, then yaw about z: R = Rz·Ry·Rx), and a movable
//! joint the child's single joint, anchored at the child origin with `<axis xyz>` (default x) in
//! the child frame. `revolute` → limited hinge, `continuous` → unlimited hinge, `prismatic` →
//! limited slide, `fixed` → no joint; `floating` and `planar` are refused. `<mimic>` couplings are
//! not modelled: every movable joint is an independent coordinate of the joint vector, which lists
//! them in document order.
//!
//! The links must form one tree: every joint names known links, no link has two parents, exactly
//! one link has no parent (several roots mean a disconnected model), and every link is reachable
//! from it (an unreachable link lies on a cycle).
//!
//! Mesh `filename`s resolve against `mesh_dir`: `package://PKG/REST` is looked up as
//! `mesh_dir/REST`, then `mesh_dir/PKG/REST`; `file://PATH` and plain paths as `mesh_dir/PATH`
//! (absolute paths stay absolute). Every mesh file must exist; collision meshes are loaded.

use super::kinematic_tree::{Body, Geom, GeomShape, Joint, JointKind, KinematicTree};
use super::mesh::load_vertices;
use super::xml::{self, Element};
use crate::error::FieldError;
use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

const FIELD: &str = "hand.urdf";

fn err(el: &Element, msg: impl std::fmt::Display) -> FieldError {
    FieldError::new(FIELD, format!("{}: <{}>: {msg}", el.at(), el.name))
}

/// Reads a URDF file; meshes resolve against its directory.
pub fn read_urdf_file(path: &Path) -> Result<KinematicTree, FieldError> {
    let text = xml::read_text(path, FIELD)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse_urdf(&text, dir, &path.display().to_string())
}

/// Reads a URDF document given as text; `source` names it in error messages.
pub fn parse_urdf(text: &str, mesh_dir: &Path, source: &str) -> Result<KinematicTree, FieldError> {
    let root = xml::parse(text, source, FIELD)?;
    if root.name != "robot" {
        return Err(err(&root, "the root element must be <robot>"));
    }
    let links: Vec<&Element> = root.children_named("link").collect();
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for (i, l) in links.iter().enumerate() {
        let name = l
            .attr("name")
            .ok_or_else(|| err(l, "a link needs a 'name'"))?;
        if link_index.insert(name, i).is_some() {
            return Err(FieldError::new(
                format!("{FIELD}.link[{name}]"),
                format!("{}: duplicate link name", l.at()),
            ));
        }
    }
    if links.is_empty() {
        return Err(err(&root, "the robot has no <link>"));
    }
    // Parent joint of each link (by link index in document order).
    struct UrdfJoint {
        name: String,
        parent: usize,
        child: usize,
        origin: Isometry3<f64>,
        kind: Option<JointKind>,
        axis: Unit<Vector3<f64>>,
        range: Option<(f64, f64)>,
        effort: Option<f64>,
    }
    let mut joints: Vec<UrdfJoint> = Vec::new();
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    for j in root.children_named("joint") {
        let name = j
            .attr("name")
            .ok_or_else(|| err(j, "a joint needs a 'name'"))?
            .to_string();
        let jf = format!("{FIELD}.joint[{name}]");
        if joints.iter().any(|o| o.name == name) {
            return Err(FieldError::new(
                jf,
                format!("{}: duplicate joint name", j.at()),
            ));
        }
        let link_of = |tag: &str| -> Result<usize, FieldError> {
            let e = j.children_named(tag).next().ok_or_else(|| {
                FieldError::new(
                    format!("{jf}.{tag}"),
                    format!("{}: missing <{tag}>", j.at()),
                )
            })?;
            let l = e.attr("link").ok_or_else(|| {
                FieldError::new(
                    format!("{jf}.{tag}"),
                    format!("{}: <{tag}> needs a 'link'", e.at()),
                )
            })?;
            link_index.get(l).copied().ok_or_else(|| {
                FieldError::new(
                    format!("{jf}.{tag}"),
                    format!("{}: joint '{name}' refers to unknown link '{l}'", e.at()),
                )
            })
        };
        let parent = link_of("parent")?;
        let child = link_of("child")?;
        if let Some(other) = parent_joint[child] {
            return Err(FieldError::new(
                format!("{jf}.child"),
                format!(
                    "{}: link '{}' already has parent joint '{}'; a link can have only one parent",
                    j.at(),
                    links[child].attr("name").unwrap_or(""),
                    joints[other].name
                ),
            ));
        }
        let kind = match j.attr("type") {
            Some("revolute") | Some("continuous") => Some(JointKind::Hinge),
            Some("prismatic") => Some(JointKind::Slide),
            Some("fixed") => None,
            Some(t) => {
                return Err(FieldError::new(
                    format!("{jf}.type"),
                    format!(
                        "{}: joint type '{t}' is not supported (revolute, continuous, prismatic, fixed)",
                        j.at()
                    ),
                ));
            }
            None => {
                return Err(FieldError::new(
                    format!("{jf}.type"),
                    format!("{}: missing", j.at()),
                ));
            }
        };
        let origin = match j.children_named("origin").next() {
            Some(o) => origin_pose(o)?,
            None => Isometry3::identity(),
        };
        let axis = match j.children_named("axis").next().and_then(|a| a.attr("xyz")) {
            Some(s) => {
                let v = xml::numbers(s, 3).ok_or_else(|| {
                    FieldError::new(
                        format!("{jf}.axis"),
                        format!("{}: xyz='{s}' must be 3 numbers", j.at()),
                    )
                })?;
                Unit::try_new(Vector3::new(v[0], v[1], v[2]), 1e-12).ok_or_else(|| {
                    FieldError::new(
                        format!("{jf}.axis"),
                        format!("{}: axis must not be zero", j.at()),
                    )
                })?
            }
            None => Vector3::x_axis(),
        };
        let (range, effort) = if matches!(j.attr("type"), Some("revolute") | Some("prismatic")) {
            let l = j.children_named("limit").next().ok_or_else(|| {
                FieldError::new(
                    format!("{jf}.limit"),
                    format!(
                        "{}: a {} joint needs <limit lower upper>",
                        j.at(),
                        j.attr("type").unwrap_or("")
                    ),
                )
            })?;
            let num = |k: &str| -> Result<f64, FieldError> {
                match l.attr(k) {
                    None => Ok(0.0),
                    Some(s) => s.trim().parse::<f64>().map_err(|_| {
                        FieldError::new(
                            format!("{jf}.limit"),
                            format!("{}: {k}='{s}' is not a number", l.at()),
                        )
                    }),
                }
            };
            // A servo's torque limit: `effort` (required by the URDF spec; 0 or absent reads as
            // none given).
            let effort = num("effort")?.abs();
            (
                Some((num("lower")?, num("upper")?)),
                (effort > 0.0 && effort.is_finite()).then_some(effort),
            )
        } else {
            (None, None)
        };
        parent_joint[child] = Some(joints.len());
        joints.push(UrdfJoint {
            name,
            parent,
            child,
            origin,
            kind,
            axis,
            range,
            effort,
        });
    }
    let roots: Vec<usize> = (0..links.len())
        .filter(|&i| parent_joint[i].is_none())
        .collect();
    let root_link = match roots.as_slice() {
        [r] => *r,
        [] => {
            return Err(FieldError::new(
                FIELD,
                "every link has a parent: the joints form a cycle and the model has no root link",
            ));
        }
        many => {
            let names: Vec<&str> = many
                .iter()
                .map(|&i| links[i].attr("name").unwrap_or(""))
                .collect();
            return Err(FieldError::new(
                FIELD,
                format!(
                    "the model is disconnected: {} links have no parent ({}); a hand must be one tree",
                    names.len(),
                    names.join(", ")
                ),
            ));
        }
    };
    // Depth-first order from the root, children in joint document order.
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
    for (ji, j) in joints.iter().enumerate() {
        children[j.parent].push(ji);
    }
    let mut order = Vec::with_capacity(links.len());
    let mut stack = vec![root_link];
    let mut body_of_link = vec![usize::MAX; links.len()];
    while let Some(l) = stack.pop() {
        body_of_link[l] = order.len();
        order.push(l);
        for &ji in children[l].iter().rev() {
            stack.push(joints[ji].child);
        }
    }
    if order.len() != links.len() {
        let lost: Vec<&str> = (0..links.len())
            .filter(|&i| body_of_link[i] == usize::MAX)
            .map(|i| links[i].attr("name").unwrap_or(""))
            .collect();
        return Err(FieldError::new(
            FIELD,
            format!(
                "links {} are not reachable from the root link '{}': their joints form a cycle",
                lost.join(", "),
                links[root_link].attr("name").unwrap_or("")
            ),
        ));
    }
    let mut tree = KinematicTree {
        name: root.attr("name").unwrap_or("urdf").to_string(),
        bodies: Vec::with_capacity(links.len()),
        joints: Vec::new(),
        loop_closures: Vec::new(),
        couplings: Vec::new(),
    };
    let mut mesh_cache: HashMap<PathBuf, Arc<Vec<Point3<f64>>>> = HashMap::new();
    for &l in &order {
        let (parent, pose) = match parent_joint[l] {
            Some(ji) => (Some(body_of_link[joints[ji].parent]), joints[ji].origin),
            None => (None, Isometry3::identity()),
        };
        let name = links[l].attr("name").unwrap_or("").to_string();
        let mut geoms = Vec::new();
        for (tag, collision) in [("collision", true), ("visual", false)] {
            for g in links[l].children_named(tag) {
                geoms.push(read_geom(g, collision, mesh_dir, &name, &mut mesh_cache)?);
            }
        }
        tree.bodies.push(Body {
            name,
            parent,
            children: Vec::new(),
            pose,
            joints: Vec::new(),
            geoms,
            sites: Vec::new(),
        });
    }
    for b in 1..tree.bodies.len() {
        let p = tree.bodies[b].parent.expect("non-root body has a parent");
        tree.bodies[p].children.push(b);
    }
    for j in &joints {
        let Some(kind) = j.kind else { continue };
        let body = body_of_link[j.child];
        let index = tree.joints.len();
        tree.joints.push(Joint {
            name: j.name.clone(),
            kind,
            body,
            anchor: Point3::origin(),
            axis: j.axis,
            range: j.range,
            reference: 0.0,
            effort: j.effort,
        });
        tree.bodies[body].joints.push(index);
    }
    tree.validate(FIELD)?;
    Ok(tree)
}

/// `<origin xyz rpy>`: R = Rz(yaw)·Ry(pitch)·Rx(roll).
fn origin_pose(o: &Element) -> Result<Isometry3<f64>, FieldError> {
    let v3 = |k: &str| -> Result<Vector3<f64>, FieldError> {
        match o.attr(k) {
            None => Ok(Vector3::zeros()),
            Some(s) => xml::numbers(s, 3)
                .map(|v| Vector3::new(v[0], v[1], v[2]))
                .ok_or_else(|| err(o, format!("{k}='{s}' must be 3 finite numbers"))),
        }
    };
    let xyz = v3("xyz")?;
    let rpy = v3("rpy")?;
    Ok(Isometry3::from_parts(
        Translation3::from(xyz),
        UnitQuaternion::from_euler_angles(rpy.x, rpy.y, rpy.z),
    ))
}

fn read_geom(
    g: &Element,
    collision: bool,
    mesh_dir: &Path,
    link: &str,
    cache: &mut HashMap<PathBuf, Arc<Vec<Point3<f64>>>>,
) -> Result<Geom, FieldError> {
    let pose = match g.children_named("origin").next() {
        Some(o) => origin_pose(o)?,
        None => Isometry3::identity(),
    };
    let geometry = g
        .children_named("geometry")
        .next()
        .ok_or_else(|| err(g, format!("link '{link}': <{}> needs a <geometry>", g.name)))?;
    let shape_el = geometry
        .children
        .first()
        .ok_or_else(|| err(geometry, "is empty"))?;
    let num = |k: &str| -> Result<f64, FieldError> {
        let s = shape_el
            .attr(k)
            .ok_or_else(|| err(shape_el, format!("needs '{k}'")))?;
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v >= 0.0)
            .ok_or_else(|| err(shape_el, format!("{k}='{s}' must be a finite number ≥ 0")))
    };
    let shape = match shape_el.name.as_str() {
        "box" => {
            let s = shape_el.attr("size").unwrap_or("");
            let v = xml::numbers(s, 3)
                .ok_or_else(|| err(shape_el, format!("size='{s}' must be 3 numbers")))?;
            GeomShape::Box {
                half_extents: 0.5 * Vector3::new(v[0], v[1], v[2]),
            }
        }
        "sphere" => GeomShape::Sphere {
            radius: num("radius")?,
        },
        "cylinder" => GeomShape::Cylinder {
            radius: num("radius")?,
            half_length: 0.5 * num("length")?,
        },
        "capsule" => GeomShape::Capsule {
            radius: num("radius")?,
            half_length: 0.5 * num("length")?,
        },
        "mesh" => {
            let f = shape_el
                .attr("filename")
                .ok_or_else(|| err(shape_el, "needs a 'filename'"))?;
            let path = resolve_mesh(f, mesh_dir).ok_or_else(|| {
                FieldError::new(
                    format!("{FIELD}.link[{link}].mesh"),
                    format!(
                        "{}: mesh file '{f}' not found under '{}'",
                        shape_el.at(),
                        mesh_dir.display()
                    ),
                )
            })?;
            let scale = match shape_el.attr("scale") {
                None => Vector3::new(1.0, 1.0, 1.0),
                Some(s) => xml::numbers(s, 3)
                    .map(|v| Vector3::new(v[0], v[1], v[2]))
                    .ok_or_else(|| err(shape_el, format!("scale='{s}' must be 3 numbers")))?,
            };
            let vertices = if collision {
                match cache.get(&path) {
                    Some(v) if scale == Vector3::new(1.0, 1.0, 1.0) => v.clone(),
                    _ => {
                        let v = Arc::new(load_vertices(
                            &path,
                            scale,
                            &format!("{FIELD}.link[{link}].mesh"),
                        )?);
                        if scale == Vector3::new(1.0, 1.0, 1.0) {
                            cache.insert(path.clone(), v.clone());
                        }
                        v
                    }
                }
            } else {
                Arc::new(Vec::new())
            };
            GeomShape::Mesh {
                name: f.to_string(),
                file: Some(path),
                vertices,
            }
        }
        other => {
            return Err(err(
                shape_el,
                format!("geometry '{other}' is not supported"),
            ));
        }
    };
    Ok(Geom {
        name: g.attr("name").map(str::to_string),
        shape,
        pose,
        collision,
    })
}

fn resolve_mesh(filename: &str, mesh_dir: &Path) -> Option<PathBuf> {
    let candidates: Vec<PathBuf> = if let Some(rest) = filename.strip_prefix("package://") {
        let (pkg, path) = rest.split_once('/').unwrap_or(("", rest));
        vec![mesh_dir.join(path), mesh_dir.join(pkg).join(path)]
    } else if let Some(rest) = filename.strip_prefix("file://") {
        vec![mesh_dir.join(rest)]
    } else {
        vec![mesh_dir.join(filename)]
    };
    candidates.into_iter().find(|p| p.is_file())
}
