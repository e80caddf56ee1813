//! How an MJCF element's attributes are read: the `<compiler>` settings, the `<default>`
//! classes an element takes its values from, and the `<mesh>` assets.

use super::{FIELD, err};
use crate::error::FieldError;
use crate::hand::kinematics::xml::{self, Element};
use nalgebra::Vector3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// `<compiler>` settings that change how numbers are read.
pub(super) struct Compiler {
    pub(super) degrees: bool,
    pub(super) eulerseq: [u8; 3],
    pub(super) autolimits: bool,
    pub(super) meshdir: PathBuf,
}

impl Compiler {
    pub(super) fn read(root: &Element, model_dir: &Path) -> Result<Self, FieldError> {
        let mut c = Compiler {
            degrees: true,
            eulerseq: *b"xyz",
            autolimits: true,
            meshdir: model_dir.to_path_buf(),
        };
        let mut assetdir = None;
        let mut meshdir = None;
        for el in root.children_named("compiler") {
            if let Some(a) = el.attr("angle") {
                c.degrees = match a {
                    "degree" => true,
                    "radian" => false,
                    _ => return Err(err(el, format!("angle='{a}' must be degree or radian"))),
                };
            }
            if let Some(s) = el.attr("eulerseq") {
                let b = s.as_bytes();
                if b.len() != 3 || !b.iter().all(|c| b"xyzXYZ".contains(c)) {
                    return Err(err(
                        el,
                        format!("eulerseq='{s}' must be 3 of x, y, z, X, Y, Z"),
                    ));
                }
                c.eulerseq = [b[0], b[1], b[2]];
            }
            if let Some(s) = el.attr("autolimits") {
                c.autolimits = parse_bool(el, "autolimits", s)?;
            }
            if let Some(s) = el.attr("coordinate")
                && s != "local"
            {
                return Err(err(
                    el,
                    format!("coordinate='{s}' is not supported (MuJoCo 3 reads local only)"),
                ));
            }
            if let Some(d) = el.attr("assetdir") {
                assetdir = Some(d.to_string());
            }
            if let Some(d) = el.attr("meshdir") {
                meshdir = Some(d.to_string());
            }
        }
        if let Some(d) = meshdir.or(assetdir) {
            c.meshdir = model_dir.join(d);
        }
        Ok(c)
    }

    pub(super) fn angle(&self, v: f64) -> f64 {
        if self.degrees { v.to_radians() } else { v }
    }
}

pub(super) fn parse_bool(el: &Element, name: &str, s: &str) -> Result<bool, FieldError> {
    match s {
        "true" => Ok(true),
        "false" => Ok(false),
        _ => Err(err(el, format!("{name}='{s}' must be true or false"))),
    }
}

/// Attribute values a default class sets, per element type (`joint`, `geom`, `site`, `mesh`).
#[derive(Debug, Clone, Default)]
pub(super) struct ClassAttrs(pub(super) HashMap<String, HashMap<String, String>>);

#[derive(Default)]
pub(super) struct Defaults {
    pub(super) classes: HashMap<String, ClassAttrs>,
}

impl Defaults {
    /// Collects `<default>` `d` whose parent class has `inherited` values. A top-level
    /// `<default>` without `class` is `main`.
    pub(super) fn collect(
        &mut self,
        d: &Element,
        inherited: &ClassAttrs,
        top: bool,
    ) -> Result<(), FieldError> {
        let name = match d.attr("class") {
            Some(n) => n.to_string(),
            None if top => "main".to_string(),
            None => return Err(err(d, "a nested <default> needs a 'class' attribute")),
        };
        let mut attrs = if name == "main" {
            self.classes.get("main").cloned().unwrap_or_default()
        } else {
            if self.classes.contains_key(&name) {
                return Err(err(d, format!("default class '{name}' is defined twice")));
            }
            inherited.clone()
        };
        for c in d.children.iter().filter(|c| c.name != "default") {
            let slot = attrs.0.entry(c.name.clone()).or_default();
            for (k, v) in &c.attrs {
                slot.insert(k.clone(), v.clone());
            }
        }
        self.classes.insert(name, attrs.clone());
        for c in d.children_named("default") {
            self.collect(c, &attrs, false)?;
        }
        Ok(())
    }
}

/// An element with its default class resolved: own attributes first, then the class's.
pub(super) struct Attrs<'a> {
    pub(super) el: &'a Element,
    pub(super) class: Option<&'a HashMap<String, String>>,
}

impl<'a> Attrs<'a> {
    pub(super) fn get(&self, name: &str) -> Option<&'a str> {
        self.el
            .attr(name)
            .or_else(|| self.class.and_then(|c| c.get(name)).map(|s| s.as_str()))
    }

    pub(super) fn numbers(&self, name: &str, n: usize) -> Result<Option<Vec<f64>>, FieldError> {
        match self.get(name) {
            None => Ok(None),
            Some(s) => xml::numbers(s, n)
                .map(Some)
                .ok_or_else(|| err(self.el, format!("{name}='{s}' must be {n} finite numbers"))),
        }
    }

    pub(super) fn vec3(&self, name: &str) -> Result<Option<Vector3<f64>>, FieldError> {
        Ok(self
            .numbers(name, 3)?
            .map(|v| Vector3::new(v[0], v[1], v[2])))
    }
}

pub(super) fn resolve<'a>(
    defaults: &'a Defaults,
    el: &'a Element,
    childclass: &str,
) -> Result<Attrs<'a>, FieldError> {
    let class = el.attr("class").unwrap_or(childclass);
    let c = defaults
        .classes
        .get(class)
        .ok_or_else(|| err(el, format!("unknown default class '{class}'")))?;
    Ok(Attrs {
        el,
        class: c.0.get(&el.name),
    })
}

/// A mesh asset: its file (if any) and scale.
pub(super) struct MeshAsset {
    pub(super) file: Option<PathBuf>,
    pub(super) scale: Vector3<f64>,
}

pub(super) fn read_mesh_assets(
    root: &Element,
    compiler: &Compiler,
    defaults: &Defaults,
) -> Result<HashMap<String, MeshAsset>, FieldError> {
    let mut out = HashMap::new();
    for asset in root.children_named("asset") {
        for m in asset.children_named("mesh") {
            let a = resolve(defaults, m, "main")?;
            let file = a.get("file");
            let name = match (m.attr("name"), file) {
                (Some(n), _) => n.to_string(),
                (None, Some(f)) => Path::new(f)
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or(f)
                    .to_string(),
                (None, None) => return Err(err(m, "a mesh needs a 'name' or a 'file'")),
            };
            let path = match file {
                Some(f) => {
                    let p = compiler.meshdir.join(f);
                    if !p.is_file() {
                        return Err(FieldError::new(
                            format!("{FIELD}.asset.mesh[{name}].file"),
                            format!(
                                "{}: mesh file '{f}' not found (looked for '{}')",
                                m.at(),
                                p.display()
                            ),
                        ));
                    }
                    Some(p)
                }
                None => None,
            };
            let scale = a.vec3("scale")?.unwrap_or(Vector3::new(1.0, 1.0, 1.0));
            if out
                .insert(name.clone(), MeshAsset { file: path, scale })
                .is_some()
            {
                return Err(err(m, format!("mesh '{name}' is defined twice")));
            }
        }
    }
    Ok(out)
}
