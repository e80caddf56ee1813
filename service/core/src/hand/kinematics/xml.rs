//! A small owned XML element tree built from roxmltree, shared by the MJCF and URDF readers.
//!
//! Owning the tree lets the MJCF reader splice `<include file=…>` documents in place (MuJoCo's
//! include semantics: the children of the included file's `<mujoco>` element replace the
//! `<include>` element) and keeps the source file and line of every element for error messages.

use crate::error::FieldError;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Largest XML document accepted (per file), bytes. Hand models are a few hundred kB at most.
pub const MAX_XML_BYTES: usize = 16 * 1024 * 1024;

/// One XML element: its name, attributes in document order, child elements and where it came from.
#[derive(Debug, Clone)]
pub struct Element {
    pub name: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Element>,
    /// Source file (or `<string>`) and 1-based line, for error messages.
    pub source: Arc<str>,
    pub line: u32,
}

impl Element {
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    /// `file:line` of this element.
    pub fn at(&self) -> String {
        format!("{}:{}", self.source, self.line)
    }

    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

/// Parses `text` into an owned element tree. `source` names the document in messages.
pub fn parse(text: &str, source: &str, field: &str) -> Result<Element, FieldError> {
    if text.len() > MAX_XML_BYTES {
        return Err(FieldError::new(
            field,
            format!(
                "{source}: document of {} bytes exceeds the {MAX_XML_BYTES}-byte limit",
                text.len()
            ),
        ));
    }
    let doc = roxmltree::Document::parse(text)
        .map_err(|e| FieldError::new(field, format!("{source}: malformed XML: {e}")))?;
    let source_name: Arc<str> = Arc::from(source);
    convert(&doc, doc.root_element(), &source_name, 0).ok_or_else(|| {
        FieldError::new(
            field,
            format!("{source}: elements nested deeper than {MAX_DEPTH} levels"),
        )
    })
}

/// Deepest element nesting accepted (the readers recurse over the tree; real hand models nest a
/// few dozen levels).
pub const MAX_DEPTH: usize = 256;

fn convert(
    doc: &roxmltree::Document,
    node: roxmltree::Node,
    source: &Arc<str>,
    depth: usize,
) -> Option<Element> {
    if depth > MAX_DEPTH {
        return None;
    }
    Some(Element {
        name: node.tag_name().name().to_string(),
        attrs: node
            .attributes()
            .map(|a| (a.name().to_string(), a.value().to_string()))
            .collect(),
        children: node
            .children()
            .filter(|c| c.is_element())
            .map(|c| convert(doc, c, source, depth + 1))
            .collect::<Option<_>>()?,
        source: source.clone(),
        line: doc.text_pos_at(node.range().start).row,
    })
}

/// Reads a file as UTF-8 text, naming `field` in the error.
pub fn read_text(path: &Path, field: &str) -> Result<String, FieldError> {
    let meta = std::fs::metadata(path)
        .map_err(|e| FieldError::new(field, format!("cannot read '{}': {e}", path.display())))?;
    if meta.len() > MAX_XML_BYTES as u64 {
        return Err(FieldError::new(
            field,
            format!(
                "'{}' has {} bytes, over the {MAX_XML_BYTES}-byte limit",
                path.display(),
                meta.len()
            ),
        ));
    }
    std::fs::read_to_string(path)
        .map_err(|e| FieldError::new(field, format!("cannot read '{}': {e}", path.display())))
}

/// Most nested `<include>` levels followed before giving up.
const MAX_INCLUDE_DEPTH: usize = 16;

/// Replaces every `<include file="…"/>` below `root` by the children of the included document's
/// root element, recursively. Relative files resolve against `dir` (MuJoCo resolves them against
/// the directory of the main model file). Including the same file twice is an error, as in
/// MuJoCo; this also rules out include cycles.
pub fn expand_includes(root: &mut Element, dir: &Path, field: &str) -> Result<(), FieldError> {
    let mut seen: Vec<PathBuf> = Vec::new();
    expand(root, dir, field, &mut seen, 0)
}

fn expand(
    el: &mut Element,
    dir: &Path,
    field: &str,
    seen: &mut Vec<PathBuf>,
    depth: usize,
) -> Result<(), FieldError> {
    let mut out = Vec::with_capacity(el.children.len());
    for mut child in std::mem::take(&mut el.children) {
        if child.name != "include" {
            expand(&mut child, dir, field, seen, depth)?;
            out.push(child);
            continue;
        }
        if depth >= MAX_INCLUDE_DEPTH {
            return Err(FieldError::new(
                field,
                format!(
                    "{}: <include> nested deeper than {MAX_INCLUDE_DEPTH} levels",
                    child.at()
                ),
            ));
        }
        let file = child.attr("file").ok_or_else(|| {
            FieldError::new(
                field,
                format!("{}: <include> needs a 'file' attribute", child.at()),
            )
        })?;
        let path = dir.join(file);
        let canonical = path.canonicalize().map_err(|e| {
            FieldError::new(
                field,
                format!(
                    "{}: included file '{file}' not found ({}: {e})",
                    child.at(),
                    path.display()
                ),
            )
        })?;
        if seen.contains(&canonical) {
            return Err(FieldError::new(
                field,
                format!(
                    "{}: '{file}' is included more than once (or includes itself)",
                    child.at()
                ),
            ));
        }
        seen.push(canonical);
        let text = read_text(&path, field)?;
        let mut doc = parse(&text, &path.display().to_string(), field)?;
        if doc.name != "mujoco" {
            return Err(FieldError::new(
                field,
                format!(
                    "{}: included file's root element is <{}>, expected <mujoco>",
                    doc.at(),
                    doc.name
                ),
            ));
        }
        expand(&mut doc, dir, field, seen, depth + 1)?;
        out.extend(doc.children);
    }
    el.children = out;
    Ok(())
}

/// Parses a whitespace-separated list of exactly `n` finite numbers.
pub fn numbers(text: &str, n: usize) -> Option<Vec<f64>> {
    let v: Vec<f64> = text
        .split_ascii_whitespace()
        .map(|t| t.parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()?;
    (v.len() == n && v.iter().all(|x| x.is_finite())).then_some(v)
}

/// Parses a whitespace-separated list of 1 to `max` finite numbers.
pub fn numbers_up_to(text: &str, max: usize) -> Option<Vec<f64>> {
    let v: Vec<f64> = text
        .split_ascii_whitespace()
        .map(|t| t.parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()?;
    (!v.is_empty() && v.len() <= max && v.iter().all(|x| x.is_finite())).then_some(v)
}
