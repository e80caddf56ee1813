//! The crate map of docs/architecture.md, kept true: every workspace crate depends only on
//! crates of a lower layer, and the domain crate knows no transport.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Layer of each workspace crate (docs/architecture.md): a crate may depend on lower ones only.
const LAYERS: [(&str, u8); 9] = [
    ("graspd-core", 0),
    ("graspd-proto", 0),
    ("graspd-api", 1),
    ("graspd-testkit", 1),
    ("graspd", 2),
    ("graspd-model-data", 2),
    ("graspctl", 2),
    ("graspd-sim", 2),
    ("graspd-e2e", 3),
];

/// Crates of the transports, which the domain crate must not use.
const TRANSPORTS: [&str; 8] = [
    "tonic",
    "tonic-prost",
    "prost",
    "axum",
    "hyper",
    "tokio",
    "tokio-stream",
    "graspd-proto",
];

/// The workspace members' directories, from the root manifest's `members = [...]`.
fn members() -> Vec<PathBuf> {
    let text = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let start = text.find("members = [").expect("a members list");
    let end = start + text[start..].find(']').unwrap();
    text[start..end]
        .split('"')
        .skip(1)
        .step_by(2)
        .map(|m| root().join(m))
        .collect()
}

/// A manifest's package name and the names in its `[dependencies]` section.
fn manifest(dir: &Path) -> (String, Vec<String>) {
    let text = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
    let mut section = String::new();
    let (mut name, mut deps) = (None, Vec::new());
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            section = line.to_string();
            continue;
        }
        let Some(key) = line.split(['=', '.']).next().map(str::trim) else {
            continue;
        };
        if key.is_empty() || key.starts_with('#') {
            continue;
        }
        match section.as_str() {
            "[package]" if key == "name" && name.is_none() => {
                name = line.split('"').nth(1).map(str::to_string);
            }
            "[dependencies]" => deps.push(key.to_string()),
            _ => {}
        }
    }
    (name.expect("a package name"), deps)
}

#[test]
fn crates_depend_only_on_lower_layers_and_the_domain_on_no_transport() {
    let layer: BTreeMap<&str, u8> = LAYERS.into_iter().collect();
    let crates: Vec<(String, Vec<String>)> = members().iter().map(|d| manifest(d)).collect();
    assert_eq!(
        crates.len(),
        LAYERS.len(),
        "a crate without a layer: {crates:?}"
    );
    for (name, deps) in &crates {
        let own = *layer
            .get(name.as_str())
            .unwrap_or_else(|| panic!("{name} has no layer in docs/architecture.md"));
        for d in deps {
            if let Some(&l) = layer.get(d.as_str()) {
                assert!(l < own, "{name} (layer {own}) depends on {d} (layer {l})");
            }
        }
        if name == "graspd-core" {
            for t in TRANSPORTS {
                assert!(!deps.iter().any(|d| d == t), "graspd-core depends on {t}");
            }
        }
    }
}
