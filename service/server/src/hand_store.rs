//! Hands with known kinematics: imported at start from MJCF/URDF files named in the
//! configuration, and registered at run time from an uploaded document plus its mesh files,
//! persisted in the hands directory (issue 6 §1, §4). Plain Rust, no transport types.
//!
//! # Hands directory layout
//! One folder per registered hand, named after it: `HANDS_DIR/NAME/hand.toml` (the manifest:
//! format, model file, overrides) beside the model document and its assets at the relative paths
//! they were uploaded with. A registration is written into `HANDS_DIR/.tmp-NAME-PID-N/`, parsed
//! from there, and only then renamed to `HANDS_DIR/NAME` (one `rename`, atomic on one file
//! system): a failed registration leaves nothing behind, a crash at worst a `.tmp-*` folder,
//! which the next start removes.

pub use graspd_api::request::{Asset, HandUpload, ModelFormat, StoredOverrides, check_name};
use graspd_core::FieldError;
use graspd_core::hand::kinematics::{HandOverrides, KinematicHand, mjcf, urdf};
use graspd_core::planning::KinematicModel;
use serde::{Deserialize, Serialize};
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// `hand.toml` of a registered hand.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    pub name: String,
    pub format: ModelFormat,
    /// The model document, relative to the hand's folder.
    pub model: String,
    #[serde(default)]
    pub overrides: StoredOverrides,
}

/// A hand read from its model: the kinematics and the description derived from them.
#[derive(Debug, Clone)]
pub struct LoadedHand {
    pub model: Arc<KinematicModel>,
    pub description: graspd_core::HandDescription,
}

/// Name of the manifest file in a hand's folder.
pub const MANIFEST: &str = "hand.toml";
/// File name the uploaded model document is stored under (assets keep their own paths).
const MODEL_FILE: &str = "model";

/// A relative path without `..`, root, drive or empty parts; `field` names it in errors.
pub fn check_relative_path(path: &str, field: &str) -> Result<PathBuf, FieldError> {
    let bad = |why: &str| FieldError::new(field, format!("path '{}' {why}", path.escape_debug()));
    if path.is_empty() {
        return Err(bad("is empty"));
    }
    if path.contains('\\') || path.contains('\0') {
        return Err(bad(
            "contains '\\' or NUL (use '/'-separated relative paths)",
        ));
    }
    if path.len() > 512 {
        return Err(bad("is longer than 512 bytes"));
    }
    let p = Path::new(path);
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::Normal(s) => out.push(s),
            Component::CurDir => {}
            Component::ParentDir => return Err(bad("contains '..'")),
            Component::RootDir | Component::Prefix(_) => return Err(bad("is absolute")),
        }
    }
    if out.as_os_str().is_empty() {
        return Err(bad("names no file"));
    }
    if out.components().count() > 16 {
        return Err(bad("is nested deeper than 16 folders"));
    }
    Ok(out)
}

/// Every file reference of a model document (MJCF `file`, `meshdir`, `assetdir`, `texturedir`;
/// URDF `filename`) must stay inside the uploaded folder: relative, without `..`. URDF's
/// `package://` and `file://` prefixes are accepted and what follows them is checked.
pub fn check_document_references(text: &str, field: &str) -> Result<(), FieldError> {
    let doc = roxmltree::Document::parse_with_options(
        text,
        roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: 1_000_000,
            ..Default::default()
        },
    )
    .map_err(|e| FieldError::new(field, format!("malformed XML: {e}")))?;
    for node in doc.descendants().filter(|n| n.is_element()) {
        for attr in node.attributes() {
            if !matches!(
                attr.name(),
                "file" | "filename" | "meshdir" | "assetdir" | "texturedir"
            ) {
                continue;
            }
            let value = attr.value();
            // `package://PKG/REST` resolves to REST or PKG/REST: both must stay inside.
            let value = value.strip_prefix("package://").unwrap_or(value);
            let value = value.strip_prefix("file://").unwrap_or(value);
            check_relative_path(
                value,
                &format!("{field}: <{} {}>", node.tag_name().name(), attr.name()),
            )?;
        }
    }
    Ok(())
}

/// Reads a hand from its model file with `overrides` and prepares it for planning.
pub fn load_model(
    path: &Path,
    format: ModelFormat,
    name: &str,
    overrides: &StoredOverrides,
) -> Result<LoadedHand, FieldError> {
    let tree = match format {
        ModelFormat::Mjcf => mjcf::read_mjcf_file(path)?,
        ModelFormat::Urdf => urdf::read_urdf_file(path)?,
    };
    let hand = KinematicHand::from_tree(
        tree,
        &HandOverrides {
            palm: overrides.palm.clone(),
            fingertips: overrides.fingertips.clone(),
            thumb: overrides.thumb.clone(),
            name: Some(name.to_string()),
        },
    )?;
    let model = KinematicModel::new(hand)?;
    let mut description = model.describe()?;
    description.name = name.to_string();
    Ok(LoadedHand {
        model: Arc::new(model),
        description,
    })
}

/// Loads every registered hand of `dir` (sorted by folder name); removes leftover `.tmp-*`
/// folders of interrupted registrations. Any hand that fails to load is an error naming it.
pub fn load_dir(dir: &Path) -> Result<Vec<LoadedHand>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("hands directory {}: {e}", dir.display()))?;
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("hands directory {}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    let mut out = Vec::new();
    for path in entries {
        let fname = path
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or_default()
            .to_string();
        if fname.starts_with(".tmp-") {
            let _ = std::fs::remove_dir_all(&path);
            continue;
        }
        if !path.is_dir() {
            continue;
        }
        let manifest_path = path.join(MANIFEST);
        let text = std::fs::read_to_string(&manifest_path)
            .map_err(|e| format!("registered hand {}: {e}", manifest_path.display()))?;
        let manifest: Manifest = toml::from_str(&text)
            .map_err(|e| format!("registered hand {}: {e}", manifest_path.display()))?;
        let model = check_relative_path(&manifest.model, "model")
            .map_err(|e| format!("registered hand {}: {e}", manifest_path.display()))?;
        let hand = load_model(
            &path.join(model),
            manifest.format,
            &manifest.name,
            &manifest.overrides,
        )
        .map_err(|e| {
            format!(
                "registered hand '{}' ({}): {e}",
                manifest.name,
                path.display()
            )
        })?;
        out.push(hand);
    }
    Ok(out)
}

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// A folder under `parent` that is removed on drop unless kept.
struct TempDir {
    path: PathBuf,
    keep: bool,
}

impl TempDir {
    fn new(parent: &Path, name: &str) -> std::io::Result<Self> {
        std::fs::create_dir_all(parent)?;
        let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let path = parent.join(format!(".tmp-{name}-{}-{n}", std::process::id()));
        std::fs::create_dir(&path)?;
        Ok(Self { path, keep: false })
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if !self.keep {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// Why a registration failed.
#[derive(Debug)]
pub enum RegisterError {
    /// Bad input, naming the field.
    Invalid(FieldError),
    /// The server could not write (disk full, permissions).
    Io(String),
}

impl From<FieldError> for RegisterError {
    fn from(e: FieldError) -> Self {
        RegisterError::Invalid(e)
    }
}

/// Writes an upload into a fresh temporary folder under `parent`, parses it, and — when `dest`
/// is given — renames the folder to `dest` (which must not exist). Without `dest` the folder is
/// removed after parsing (the hand lives in memory only). Nothing is left behind on failure.
pub fn register(
    upload: &HandUpload,
    parent: &Path,
    dest: Option<&Path>,
) -> Result<LoadedHand, RegisterError> {
    check_name(&upload.name, "name")?;
    if upload.text.trim().is_empty() {
        return Err(FieldError::new("model.text", "missing: give the model document").into());
    }
    check_document_references(&upload.text, "model.text")?;
    let mut paths = Vec::with_capacity(upload.assets.len());
    for (i, a) in upload.assets.iter().enumerate() {
        let field = format!("model.assets[{i}].path");
        let p = check_relative_path(&a.path, &field)?;
        if p == Path::new(MODEL_FILE) || p == Path::new(MANIFEST) {
            return Err(FieldError::new(
                field,
                format!("'{}' is reserved; put assets under another name", a.path),
            )
            .into());
        }
        if paths.contains(&p) {
            return Err(FieldError::new(field, format!("'{}' uploaded twice", a.path)).into());
        }
        paths.push(p);
    }
    let io = |e: std::io::Error| RegisterError::Io(e.to_string());
    let mut tmp = TempDir::new(parent, &upload.name).map_err(io)?;
    let model_name = match upload.format {
        ModelFormat::Mjcf => format!("{MODEL_FILE}.xml"),
        ModelFormat::Urdf => format!("{MODEL_FILE}.urdf"),
    };
    for (p, a) in paths.iter().zip(&upload.assets) {
        let target = tmp.path.join(p);
        if let Some(d) = target.parent() {
            std::fs::create_dir_all(d).map_err(io)?;
        }
        std::fs::write(&target, &a.data).map_err(io)?;
    }
    let model_path = tmp.path.join(&model_name);
    std::fs::write(&model_path, &upload.text).map_err(io)?;
    let manifest = Manifest {
        name: upload.name.clone(),
        format: upload.format,
        model: model_name,
        overrides: upload.overrides.clone(),
    };
    let text = toml::to_string(&manifest).map_err(|e| RegisterError::Io(e.to_string()))?;
    std::fs::write(tmp.path.join(MANIFEST), text).map_err(io)?;
    let hand =
        load_model(&model_path, upload.format, &upload.name, &upload.overrides).map_err(|e| {
            // Errors about files name the upload, not the server's temporary folder.
            let message = e
                .message
                .replace(&tmp.path.display().to_string(), "<upload>");
            RegisterError::Invalid(FieldError::new(format!("model.{}", e.field), message))
        })?;
    if let Some(dest) = dest {
        if dest.exists() {
            return Err(RegisterError::Invalid(FieldError::new(
                "name",
                format!("a hand folder '{}' already exists", upload.name),
            )));
        }
        std::fs::rename(&tmp.path, dest).map_err(io)?;
        tmp.keep = true;
    }
    Ok(hand)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The registration rules both transports decode into: a parametric description is
    /// refused on `hand`, a missing model on `model`; empty overrides mean "detect".
    #[test]
    fn registration_rules_have_one_home() {
        let model = || {
            let o = StoredOverrides::requested(
                Some("  ".into()),
                vec![" a ".into(), "".into()],
                Some(" th ".into()),
            );
            Some((ModelFormat::Mjcf, "<mujoco/>".to_string(), Vec::new(), o))
        };
        let e = HandUpload::from_request("h".into(), true, model()).unwrap_err();
        assert_eq!(e.field, "hand");
        let e = HandUpload::from_request("h".into(), false, None).unwrap_err();
        assert_eq!(e.field, "model");
        let u = HandUpload::from_request("h".into(), false, model()).unwrap();
        assert_eq!(
            u.overrides,
            StoredOverrides {
                palm: None,
                fingertips: Some(vec!["a".into()]),
                thumb: Some("th".into()),
            }
        );
        assert!(StoredOverrides::requested(None, Vec::new(), None) == StoredOverrides::default());
    }

    #[test]
    fn paths_and_names_are_checked() {
        assert!(check_relative_path("assets/a.stl", "p").is_ok());
        assert!(check_relative_path("./a.stl", "p").is_ok());
        for bad in ["", "../a.stl", "a/../../b", "/etc/passwd", "a\\b", "."] {
            let e = check_relative_path(bad, "model.assets[0].path").unwrap_err();
            assert_eq!(e.field, "model.assets[0].path", "{bad}");
        }
        assert!(check_name("shadow_mjcf", "name").is_ok());
        for bad in ["", ".x", "a/b", "a b", &"x".repeat(65)] {
            assert!(check_name(bad, "name").is_err(), "{bad}");
        }
        assert!(
            check_document_references(r#"<mujoco><compiler meshdir="assets"/></mujoco>"#, "m")
                .is_ok()
        );
        let e = check_document_references(
            r#"<mujoco><asset><mesh file="../../secret.stl"/></asset></mujoco>"#,
            "model.text",
        )
        .unwrap_err();
        assert!(e.field.starts_with("model.text"), "{e}");
        assert!(
            check_document_references("<robot><mesh filename=\"/abs.stl\"/></robot>", "m").is_err()
        );
        assert!(
            check_document_references(
                "<robot><mesh filename=\"package://hand/meshes/a.stl\"/></robot>",
                "m"
            )
            .is_ok()
        );
        assert!(check_document_references("<mujoco", "m").is_err());
        assert!(
            check_document_references(
                "<robot><mesh filename=\"package://../etc/passwd\"/></robot>",
                "m"
            )
            .is_err()
        );
    }
}
