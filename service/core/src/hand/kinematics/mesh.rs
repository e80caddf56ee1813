//! Vertex loading for the mesh files of hand models (STL binary/ASCII, OBJ).
//!
//! Only vertices are needed: the hand description uses the extents of the palm and fingertip
//! collision geometry, and collision checking uses convex hulls of the vertices.

use crate::error::FieldError;
use nalgebra::{Point3, Vector3};
use std::path::Path;

/// Largest mesh file read, bytes.
pub const MAX_MESH_BYTES: u64 = 64 * 1024 * 1024;

/// Loads the vertices of an STL or OBJ file (chosen by extension, case-insensitive), multiplied
/// component-wise by `scale`. Errors name `field`.
pub fn load_vertices(
    path: &Path,
    scale: Vector3<f64>,
    field: &str,
) -> Result<Vec<Point3<f64>>, FieldError> {
    let err = |m: String| FieldError::new(field, format!("mesh '{}': {m}", path.display()));
    let meta = std::fs::metadata(path).map_err(|e| err(format!("cannot read: {e}")))?;
    if meta.len() > MAX_MESH_BYTES {
        return Err(err(format!(
            "{} bytes, over the {MAX_MESH_BYTES}-byte limit",
            meta.len()
        )));
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let raw = match ext.as_str() {
        "stl" => {
            let bytes = std::fs::read(path).map_err(|e| err(format!("cannot read: {e}")))?;
            parse_stl(&bytes).map_err(err)?
        }
        "obj" => load_obj(path).map_err(err)?,
        other => {
            return Err(err(format!(
                "unsupported mesh format '.{other}' (expected .stl or .obj)"
            )));
        }
    };
    if raw.is_empty() {
        return Err(err("has no vertices".into()));
    }
    Ok(raw
        .into_iter()
        .map(|p| Point3::new(p[0] * scale.x, p[1] * scale.y, p[2] * scale.z))
        .collect())
}

/// Parses an STL file: binary when its size matches the triangle count in the header, else ASCII.
pub fn parse_stl(bytes: &[u8]) -> Result<Vec<[f64; 3]>, String> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) {
            let mut out = Vec::with_capacity(3 * n);
            for t in 0..n {
                let base = 84 + 50 * t + 12;
                for v in 0..3 {
                    let mut p = [0.0; 3];
                    for (c, slot) in p.iter_mut().enumerate() {
                        let o = base + 12 * v + 4 * c;
                        *slot = f32::from_le_bytes([
                            bytes[o],
                            bytes[o + 1],
                            bytes[o + 2],
                            bytes[o + 3],
                        ]) as f64;
                    }
                    if p.iter().any(|x| !x.is_finite()) {
                        return Err(format!("triangle {t} has a non-finite vertex"));
                    }
                    out.push(p);
                }
            }
            return Ok(out);
        }
    }
    let text = std::str::from_utf8(bytes)
        .map_err(|_| "neither a binary STL (size does not match its triangle count) nor ASCII")?;
    if !text.trim_start().starts_with("solid") {
        return Err(
            "neither a binary STL (size does not match its triangle count) nor an ASCII \
                    STL (no 'solid' header)"
                .into(),
        );
    }
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut it = line.split_ascii_whitespace();
        if it.next() == Some("vertex") {
            let v: Vec<f64> = it.filter_map(|t| t.parse().ok()).collect();
            if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
                return Err(format!("line {}: malformed vertex", i + 1));
            }
            out.push([v[0], v[1], v[2]]);
        }
    }
    Ok(out)
}

fn load_obj(path: &Path) -> Result<Vec<[f64; 3]>, String> {
    let (models, _materials) = tobj::load_obj(
        path,
        &tobj::LoadOptions {
            ignore_points: true,
            ignore_lines: true,
            ..Default::default()
        },
    )
    .map_err(|e| format!("not a readable OBJ: {e}"))?;
    let mut out = Vec::new();
    for m in &models {
        for c in m.mesh.positions.chunks_exact(3) {
            let p = [c[0] as f64, c[1] as f64, c[2] as f64];
            if p.iter().any(|x| !x.is_finite()) {
                return Err("non-finite vertex".into());
            }
            out.push(p);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_and_ascii_stl() {
        let mut b = vec![0u8; 80];
        b.extend_from_slice(&1u32.to_le_bytes());
        b.extend_from_slice(&[0u8; 12]);
        for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 2., 0.]] {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
        assert_eq!(parse_stl(&b).unwrap()[2], [0.0, 2.0, 0.0]);
        let a = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 3 0\n\
                 endloop\nendfacet\nendsolid t\n";
        assert_eq!(parse_stl(a.as_bytes()).unwrap()[2], [0.0, 3.0, 0.0]);
        assert!(parse_stl(b"garbage").is_err());
    }
}
