//! Reads an MJCF (MuJoCo XML) model into a [`KinematicTree`].
//!
//! Supported, with MuJoCo 3.x semantics:
//! - `<include file>` (spliced in place, resolved against the model directory);
//! - `<compiler angle="degree|radian" meshdir assetdir eulerseq autolimits>` (MuJoCo's defaults:
//!   degrees, `xyz`, autolimits on);
//! - `<default>` classes, nested (a class inherits its parent's values), selected by an element's
//!   `class` or else the nearest enclosing body's (or frame's) `childclass`, else `main`;
//! - bodies with `pos` and one of `quat`, `axisangle`, `euler`, `xyaxes`, `zaxis`; `<frame>`;
//! - hinge and slide joints with `pos`, `axis`, `range`, `limited`, `ref`; a `<freejoint>` (or a
//!   free joint) is the floating base and is dropped: the hand's pose belongs to the planner;
//!   ball joints are refused;
//! - geoms (sphere, capsule, cylinder, box, ellipsoid, plane, mesh; `fromto`) and sites;
//! - `<mesh file scale>` assets: every mesh file must exist; collision meshes are loaded;
//! - `<equality><connect|weld body1 body2>` as loop closures.
//!
//! - the force limits of the actuators (and of fixed tendons' joints) as each joint's
//!   `effort` ([`actuators`]).
//!
//! Inertial, sensor and contact sections are not kinematics and are ignored.
//! How an element's attributes are read (compiler settings, default classes, mesh assets):
//! [`attributes`].

mod actuators;
mod attributes;

use super::kinematic_tree::{
    Body, Geom, GeomShape, Joint, JointCoupling, JointKind, KinematicTree, LoopClosure, Site,
};
use super::mesh::load_vertices;
use super::xml::{self, Element};
use crate::error::FieldError;
use attributes::{
    Attrs, ClassAttrs, Compiler, Defaults, MeshAsset, parse_bool, read_mesh_assets, resolve,
};
use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

const FIELD: &str = "hand.mjcf";

fn err(el: &Element, msg: impl std::fmt::Display) -> FieldError {
    FieldError::new(FIELD, format!("{}: <{}>: {msg}", el.at(), el.name))
}

/// Reads an MJCF file; includes and mesh files resolve against its directory.
pub fn read_mjcf_file(path: &Path) -> Result<KinematicTree, FieldError> {
    let text = xml::read_text(path, FIELD)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse_mjcf(&text, dir, &path.display().to_string())
}

/// Reads an MJCF document given as text. `model_dir` is the directory `<include>` files and
/// `meshdir` resolve against; `source` names the document in error messages.
pub fn parse_mjcf(text: &str, model_dir: &Path, source: &str) -> Result<KinematicTree, FieldError> {
    let mut root = xml::parse(text, source, FIELD)?;
    if root.name != "mujoco" {
        return Err(err(&root, "the root element must be <mujoco>"));
    }
    xml::expand_includes(&mut root, model_dir, FIELD)?;
    let compiler = Compiler::read(&root, model_dir)?;
    let mut defaults = Defaults::default();
    defaults
        .classes
        .insert("main".into(), ClassAttrs::default());
    for d in root.children_named("default") {
        let main = defaults.classes["main"].clone();
        defaults.collect(d, &main, true)?;
    }
    let meshes = read_mesh_assets(&root, &compiler, &defaults)?;
    let mut reader = Reader {
        compiler,
        defaults,
        meshes,
        mesh_cache: HashMap::new(),
        tree: KinematicTree {
            name: root.attr("model").unwrap_or("mjcf").to_string(),
            bodies: vec![Body {
                name: "world".into(),
                parent: None,
                children: Vec::new(),
                pose: Isometry3::identity(),
                joints: Vec::new(),
                geoms: Vec::new(),
                sites: Vec::new(),
            }],
            joints: Vec::new(),
            loop_closures: Vec::new(),
            couplings: Vec::new(),
        },
    };
    let mut saw_worldbody = false;
    for wb in root.children_named("worldbody") {
        saw_worldbody = true;
        reader.body_children(wb, 0, Isometry3::identity(), "main")?;
    }
    if !saw_worldbody {
        return Err(err(&root, "no <worldbody>"));
    }
    for eq in root.children_named("equality") {
        for c in &eq.children {
            reader.equality(c)?;
        }
    }
    actuators::read_actuator_limits(&root, &reader.defaults, &reader.compiler, &mut reader.tree)?;
    reader.tree.validate(FIELD)?;
    Ok(reader.tree)
}

struct Reader {
    compiler: Compiler,
    defaults: Defaults,
    meshes: HashMap<String, MeshAsset>,
    mesh_cache: HashMap<String, Arc<Vec<Point3<f64>>>>,
    tree: KinematicTree,
}

impl Reader {
    /// Reads the children of a body (or frame) element into body `body`. `frame` is the pose of
    /// an enclosing `<frame>` relative to the body; `childclass` the active class.
    fn body_children(
        &mut self,
        el: &Element,
        body: usize,
        frame: Isometry3<f64>,
        childclass: &str,
    ) -> Result<(), FieldError> {
        for c in &el.children {
            match c.name.as_str() {
                "body" => self.body(c, body, frame, childclass)?,
                "frame" => {
                    let a = resolve(&self.defaults, c, childclass)?;
                    let pose = frame * self.pose(&a)?;
                    let cc = c.attr("childclass").unwrap_or(childclass).to_string();
                    self.check_class(c, &cc)?;
                    self.body_children(c, body, pose, &cc)?;
                }
                "joint" => self.joint(c, body, frame, childclass)?,
                "freejoint" => {}
                "geom" => {
                    let g = self.geom(c, frame, childclass)?;
                    self.tree.bodies[body].geoms.push(g);
                }
                "site" => {
                    let a = resolve(&self.defaults, c, childclass)?;
                    let pose = frame * self.pose(&a)?;
                    let name = c.attr("name").map(str::to_string).unwrap_or_else(|| {
                        format!(
                            "{}_site{}",
                            self.tree.bodies[body].name,
                            self.tree.bodies[body].sites.len()
                        )
                    });
                    self.tree.bodies[body].sites.push(Site { name, pose });
                }
                "replicate" | "composite" | "flexcomp" | "attach" => {
                    return Err(err(
                        c,
                        "is not supported; expand it into plain bodies first",
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// `<connect>`/`<weld>` between bodies become loop closures, `<joint>` couplings; other
    /// equalities (tendon, flex, site-based) are not kinematic and are skipped.
    fn equality(&mut self, c: &Element) -> Result<(), FieldError> {
        let tree = &self.tree;
        let body = |k: &str| -> Result<Option<usize>, FieldError> {
            match c.attr(k) {
                None => Ok(None),
                Some(n) => tree
                    .body_index(n)
                    .map(Some)
                    .ok_or_else(|| err(c, format!("{k} '{n}' is not a body of the model"))),
            }
        };
        let joint = |k: &str| -> Result<Option<usize>, FieldError> {
            match c.attr(k) {
                None => Ok(None),
                Some(n) => tree.joint_index(n).map(Some).ok_or_else(|| {
                    err(
                        c,
                        format!("{k} '{n}' is not a hinge or slide joint of the model"),
                    )
                }),
            }
        };
        match c.name.as_str() {
            "connect" | "weld" => {
                let (Some(body1), b2) = (body("body1")?, body("body2")?) else {
                    return Ok(());
                };
                let body2 = b2.unwrap_or(0);
                let a = Attrs { el: c, class: None };
                let anchor1 = Point3::from(a.vec3("anchor")?.unwrap_or_else(Vector3::zeros));
                let fk = self.tree.forward(&self.tree.reference_configuration())?;
                let world = fk.body_poses[body1] * anchor1;
                let anchor2 = fk.body_poses[body2].inverse() * world;
                self.tree.loop_closures.push(LoopClosure {
                    body1,
                    body2,
                    anchor1,
                    anchor2,
                });
            }
            "joint" => {
                let Some(joint1) = joint("joint1")? else {
                    return Err(err(c, "needs joint1"));
                };
                let Some(joint2) = joint("joint2")? else {
                    // Without joint2 the joint is locked at its reference (plus polycoef[0]).
                    return Ok(());
                };
                let a = Attrs { el: c, class: None };
                let polycoef = match a.get("polycoef") {
                    None => [0.0, 1.0, 0.0, 0.0, 0.0],
                    Some(s) => {
                        let v = xml::numbers_up_to(s, 5).ok_or_else(|| {
                            err(c, format!("polycoef='{s}' must be up to 5 numbers"))
                        })?;
                        let mut p = [0.0; 5];
                        p[..v.len()].copy_from_slice(&v);
                        p
                    }
                };
                self.tree.couplings.push(JointCoupling {
                    joint1,
                    joint2,
                    polycoef,
                });
            }
            _ => {}
        }
        Ok(())
    }

    fn check_class(&self, el: &Element, class: &str) -> Result<(), FieldError> {
        if self.defaults.classes.contains_key(class) {
            Ok(())
        } else {
            Err(err(el, format!("unknown default class '{class}'")))
        }
    }

    fn body(
        &mut self,
        el: &Element,
        parent: usize,
        frame: Isometry3<f64>,
        childclass: &str,
    ) -> Result<(), FieldError> {
        let a = Attrs { el, class: None };
        let pose = frame * self.pose(&a)?;
        let index = self.tree.bodies.len();
        let name = el
            .attr("name")
            .map(str::to_string)
            .unwrap_or_else(|| format!("body{index}"));
        self.tree.bodies.push(Body {
            name,
            parent: Some(parent),
            children: Vec::new(),
            pose,
            joints: Vec::new(),
            geoms: Vec::new(),
            sites: Vec::new(),
        });
        self.tree.bodies[parent].children.push(index);
        let cc = el.attr("childclass").unwrap_or(childclass).to_string();
        self.check_class(el, &cc)?;
        self.body_children(el, index, Isometry3::identity(), &cc)
    }

    /// Position and orientation of a body, geom, site or frame: `pos` and at most one of `quat`,
    /// `axisangle`, `euler`, `xyaxes`, `zaxis`.
    fn pose(&self, a: &Attrs) -> Result<Isometry3<f64>, FieldError> {
        let pos = a.vec3("pos")?.unwrap_or_else(Vector3::zeros);
        Ok(Isometry3::from_parts(
            Translation3::from(pos),
            self.orientation(a)?,
        ))
    }

    fn orientation(&self, a: &Attrs) -> Result<UnitQuaternion<f64>, FieldError> {
        let given: Vec<&str> = ["quat", "axisangle", "euler", "xyaxes", "zaxis"]
            .into_iter()
            .filter(|k| a.el.attr(k).is_some())
            .collect();
        if given.len() > 1 {
            return Err(err(
                a.el,
                format!("give at most one orientation, got {}", given.join(" and ")),
            ));
        }
        let el = a.el;
        if let Some(q) = a.numbers("quat", 4)? {
            let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
            if n < 1e-12 {
                return Err(err(el, "quat must not be zero"));
            }
            return Ok(UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                q[0], q[1], q[2], q[3],
            )));
        }
        if let Some(v) = a.numbers("axisangle", 4)? {
            let axis = Vector3::new(v[0], v[1], v[2]);
            let axis = Unit::try_new(axis, 1e-12)
                .ok_or_else(|| err(el, "axisangle axis must not be zero"))?;
            return Ok(UnitQuaternion::from_axis_angle(
                &axis,
                self.compiler.angle(v[3]),
            ));
        }
        if let Some(e) = a.numbers("euler", 3)? {
            // MuJoCo: lowercase = intrinsic (post-multiply), uppercase = extrinsic (pre-multiply).
            let mut q = UnitQuaternion::identity();
            for (i, &c) in self.compiler.eulerseq.iter().enumerate() {
                let axis = match c.to_ascii_lowercase() {
                    b'x' => Vector3::x_axis(),
                    b'y' => Vector3::y_axis(),
                    _ => Vector3::z_axis(),
                };
                let r = UnitQuaternion::from_axis_angle(&axis, self.compiler.angle(e[i]));
                q = if c.is_ascii_lowercase() { q * r } else { r * q };
            }
            return Ok(q);
        }
        if let Some(v) = a.numbers("xyaxes", 6)? {
            let x = Vector3::new(v[0], v[1], v[2]);
            let y = Vector3::new(v[3], v[4], v[5]);
            let x = Unit::try_new(x, 1e-12).ok_or_else(|| err(el, "xyaxes x must not be zero"))?;
            let y = Unit::try_new(y - x.into_inner() * x.dot(&y), 1e-12)
                .ok_or_else(|| err(el, "xyaxes y must not be parallel to x"))?;
            let z = x.cross(&y);
            let m = nalgebra::Matrix3::from_columns(&[x.into_inner(), y.into_inner(), z]);
            return Ok(UnitQuaternion::from_rotation_matrix(
                &nalgebra::Rotation3::from_matrix_unchecked(m),
            ));
        }
        if let Some(z) = a.vec3("zaxis")? {
            return z_axis_rotation(&z).ok_or_else(|| err(el, "zaxis must not be zero"));
        }
        Ok(UnitQuaternion::identity())
    }

    fn joint(
        &mut self,
        el: &Element,
        body: usize,
        frame: Isometry3<f64>,
        childclass: &str,
    ) -> Result<(), FieldError> {
        let a = resolve(&self.defaults, el, childclass)?;
        let kind = match a.get("type").unwrap_or("hinge") {
            "hinge" => JointKind::Hinge,
            "slide" => JointKind::Slide,
            "free" => return Ok(()),
            t => {
                return Err(err(
                    el,
                    format!("joint type '{t}' is not supported (hinge, slide or free)"),
                ));
            }
        };
        let name = el
            .attr("name")
            .map(str::to_string)
            .unwrap_or_else(|| format!("joint{}", self.tree.joints.len()));
        let anchor = frame * Point3::from(a.vec3("pos")?.unwrap_or_else(Vector3::zeros));
        let axis = a.vec3("axis")?.unwrap_or_else(Vector3::z);
        let axis = Unit::try_new(frame.rotation * axis, 1e-12)
            .ok_or_else(|| err(el, format!("joint '{name}': axis must not be zero")))?;
        let angle = |v: f64| match kind {
            JointKind::Hinge => self.compiler.angle(v),
            JointKind::Slide => v,
        };
        let range = a.get("range").map(|s| {
            // Non-finite values are reported by the limit check with the joint's name.
            let v: Vec<f64> = s
                .split_ascii_whitespace()
                .map(|t| t.parse::<f64>().unwrap_or(f64::NAN))
                .collect();
            v
        });
        let range = match range {
            Some(v) if v.len() != 2 => {
                return Err(FieldError::new(
                    format!("{FIELD}.joint[{name}].range"),
                    format!("{}: range must be two numbers", el.at()),
                ));
            }
            Some(v) => Some((angle(v[0]), angle(v[1]))),
            None => None,
        };
        let limited = match a.get("limited").unwrap_or("auto") {
            "auto" => range.is_some() && self.compiler.autolimits,
            s => parse_bool(el, "limited", s)?,
        };
        if limited && range.is_none() {
            return Err(FieldError::new(
                format!("{FIELD}.joint[{name}].range"),
                format!("{}: limited joint without a range", el.at()),
            ));
        }
        let reference = match a.get("ref") {
            None => 0.0,
            Some(s) => angle(
                s.trim()
                    .parse::<f64>()
                    .map_err(|_| err(el, format!("ref='{s}' must be a number")))?,
            ),
        };
        let index = self.tree.joints.len();
        self.tree.joints.push(Joint {
            name,
            kind,
            body,
            anchor,
            axis,
            range: if limited { range } else { None },
            reference,
            effort: actuators::joint_limit(&a, &self.compiler)?,
        });
        self.tree.bodies[body].joints.push(index);
        Ok(())
    }

    fn geom(
        &mut self,
        el: &Element,
        frame: Isometry3<f64>,
        childclass: &str,
    ) -> Result<Geom, FieldError> {
        let a = resolve(&self.defaults, el, childclass)?;
        let kind = a.get("type").unwrap_or("sphere");
        let size = match a.get("size") {
            None => Vec::new(),
            Some(s) => xml::numbers_up_to(s, 3)
                .ok_or_else(|| err(el, format!("size='{s}' must be 1 to 3 finite numbers")))?,
        };
        let mut pose = self.pose(&a)?;
        let mut half_from_to = None;
        if let Some(ft) = a.numbers("fromto", 6)? {
            let p0 = Vector3::new(ft[0], ft[1], ft[2]);
            let p1 = Vector3::new(ft[3], ft[4], ft[5]);
            let d = p1 - p0;
            let rot =
                z_axis_rotation(&d).ok_or_else(|| err(el, "fromto end points must differ"))?;
            pose = Isometry3::from_parts(Translation3::from(0.5 * (p0 + p1)), rot);
            half_from_to = Some(0.5 * d.norm());
        }
        let s = |i: usize| -> Result<f64, FieldError> {
            size.get(i)
                .copied()
                .filter(|v| *v >= 0.0)
                .ok_or_else(|| err(el, format!("a {kind} geom needs size[{i}] ≥ 0")))
        };
        let contype = a.get("contype").unwrap_or("1");
        let conaffinity = a.get("conaffinity").unwrap_or("1");
        let collision = !(contype.trim() == "0" && conaffinity.trim() == "0");
        let shape = match kind {
            "sphere" => GeomShape::Sphere { radius: s(0)? },
            "capsule" | "cylinder" => {
                let radius = s(0)?;
                let half_length = match half_from_to {
                    Some(h) => h,
                    None => s(1)?,
                };
                if kind == "capsule" {
                    GeomShape::Capsule {
                        radius,
                        half_length,
                    }
                } else {
                    GeomShape::Cylinder {
                        radius,
                        half_length,
                    }
                }
            }
            "box" => GeomShape::Box {
                half_extents: Vector3::new(s(0)?, s(1)?, s(2)?),
            },
            "ellipsoid" => GeomShape::Ellipsoid {
                radii: Vector3::new(s(0)?, s(1)?, s(2)?),
            },
            "plane" => GeomShape::Plane,
            "mesh" => {
                let name = a
                    .get("mesh")
                    .ok_or_else(|| err(el, "a mesh geom needs a 'mesh' attribute"))?;
                let asset = self
                    .meshes
                    .get(name)
                    .ok_or_else(|| err(el, format!("mesh '{name}' is not declared in <asset>")))?;
                let vertices = match (&asset.file, collision) {
                    (Some(file), true) => match self.mesh_cache.get(name) {
                        Some(v) => v.clone(),
                        None => {
                            let v = Arc::new(load_vertices(
                                file,
                                asset.scale,
                                &format!("{FIELD}.asset.mesh[{name}]"),
                            )?);
                            self.mesh_cache.insert(name.to_string(), v.clone());
                            v
                        }
                    },
                    _ => Arc::new(Vec::new()),
                };
                GeomShape::Mesh {
                    name: name.to_string(),
                    file: asset.file.clone(),
                    vertices,
                }
            }
            t => return Err(err(el, format!("geom type '{t}' is not supported"))),
        };
        Ok(Geom {
            name: el.attr("name").map(str::to_string),
            shape,
            pose: frame * pose,
            collision,
        })
    }
}

/// The rotation that takes +z to `z` by the shortest arc (MuJoCo's `zaxis`, `fromto`).
fn z_axis_rotation(z: &Vector3<f64>) -> Option<UnitQuaternion<f64>> {
    let z = Unit::try_new(*z, 1e-12)?;
    Some(
        UnitQuaternion::rotation_between(&Vector3::z(), &z).unwrap_or_else(|| {
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
        }),
    )
}
