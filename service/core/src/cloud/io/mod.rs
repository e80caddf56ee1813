//! Point-cloud file formats (PCD, PLY) and ROS `sensor_msgs/PointCloud2` as untrusted input.
//!
//! The readers take the whole file as bytes and return a [`PointCloud`] (x, y, z and, when the
//! file has all three components, normals). Errors are [`FieldError`]s on the field
//! `cloud.file` whose message starts with the format and says what is wrong.
//!
//! Why hand-written parsers and not `pcd-rs` / `ply-rs-bw`: the bytes come from callers we do
//! not trust, so a lying header must fail cleanly. `pcd-rs` 0.13 allocates buffers sized from
//! the header (`vec![0; COUNT * SIZE]` for padding fields, the `binary_compressed` sizes) and
//! slices its decompressed buffer by the header's point count (a panic when they disagree).
//! `ply-rs-bw` 4 caps its pre-allocation, but it still loops `count` times over an element
//! that has no properties (a header claiming 10^12 of them never finishes), builds every
//! element of the file (faces included) when we need only the vertices, and would need the
//! same header checks as here to report missing x/y/z. We only need x, y, z and the normals,
//! so the parsers below are small: every count from a header is checked against the bytes
//! that are actually present before anything is allocated, all arithmetic on header numbers
//! is checked, and every read is bounds-checked.
//!
//! Conventions shared by both readers:
//! - Points whose x, y or z is NaN are dropped (PCL writes NaN for invalid pixels of organized
//!   clouds, `is_dense false`); infinities are kept and left to [`PointCloud::validate`].
//! - Normals are read only when all three components are present (`normal_x`/`normal_y`/
//!   `normal_z` or `nx`/`ny`/`nz`, in either format). If any kept point's normal is NaN,
//!   infinite or zero (PCL writes NaN where it could not estimate one), the file's normals are
//!   dropped as a whole and the planner estimates its own.
//!
//! The writers (float32, little-endian where binary) are for tools, tests and fixtures.

mod pcd;
mod ply;
pub mod pointcloud2;

pub use pcd::{read_pcd, write_pcd_ascii, write_pcd_binary};
pub use ply::{read_ply, write_ply_ascii, write_ply_binary};
pub use pointcloud2::{PointCloud2Layout, PointField, read_pointcloud2, write_pointcloud2};

use super::PointCloud;
use crate::error::FieldError;
use nalgebra::{Point3, Vector3};

/// The field named in every error of this module.
pub const FILE_FIELD: &str = "cloud.file";

/// Longest header the readers look through, bytes. Real headers are a few hundred bytes.
pub const MAX_HEADER_BYTES: usize = 64 * 1024;

/// Supported cloud file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloudFormat {
    Pcd,
    Ply,
}

/// Tells the format from the first bytes: PLY by its magic line (`ply` + LF or CR LF), PCD by a
/// header whose first line that is not blank or a `#` comment starts with a PCD keyword
/// (`VERSION`, `FIELDS`, …). `None` when it is neither.
pub fn detect_format(bytes: &[u8]) -> Option<CloudFormat> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
        return Some(CloudFormat::Ply);
    }
    let head = &bytes[..bytes.len().min(MAX_HEADER_BYTES)];
    for line in head.split(|&b| b == b'\n') {
        let Ok(line) = std::str::from_utf8(line) else {
            return None;
        };
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let word = line.split_ascii_whitespace().next().unwrap_or("");
        return pcd::is_keyword(word).then_some(CloudFormat::Pcd);
    }
    None
}

/// Reads a PCD or PLY file (told apart by [`detect_format`]).
pub fn read_cloud_file(bytes: &[u8]) -> Result<PointCloud, FieldError> {
    if bytes.is_empty() {
        return Err(error("the file is empty"));
    }
    match detect_format(bytes) {
        Some(CloudFormat::Ply) => read_ply(bytes),
        Some(CloudFormat::Pcd) => read_pcd(bytes),
        None => Err(error(
            "unrecognised cloud file: expected PLY (first line \"ply\") or PCD (a header with \
             FIELDS and DATA lines)",
        )),
    }
}

pub(crate) fn error(message: impl Into<String>) -> FieldError {
    FieldError::new(FILE_FIELD, message)
}

/// What a property/field of a file is to us.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Slot {
    X,
    Y,
    Z,
    Nx,
    Ny,
    Nz,
}

impl Slot {
    pub(crate) fn of(name: &str) -> Option<Slot> {
        Some(match name {
            "x" => Slot::X,
            "y" => Slot::Y,
            "z" => Slot::Z,
            "nx" | "normal_x" => Slot::Nx,
            "ny" | "normal_y" => Slot::Ny,
            "nz" | "normal_z" => Slot::Nz,
            _ => return None,
        })
    }

    pub(crate) fn index(self) -> usize {
        self as usize
    }
}

/// Whether the normal slots are complete; an error naming the format when only some are present.
pub(crate) fn normals_present(fmt: &str, found: &[Option<String>; 6]) -> Result<bool, FieldError> {
    let present: Vec<&str> = found[3..].iter().flatten().map(String::as_str).collect();
    match present.len() {
        0 => Ok(false),
        3 => Ok(true),
        _ => Err(error(format!(
            "{fmt}: only some normal components are present ({}); give all three of \
             normal_x/normal_y/normal_z (or nx/ny/nz) or none",
            present.join(", ")
        ))),
    }
}

/// Collects points (and normals) while reading, applying the module's NaN conventions.
pub(crate) struct CloudBuilder {
    points: Vec<Point3<f64>>,
    normals: Option<Vec<Vector3<f64>>>,
    normals_usable: bool,
}

impl CloudBuilder {
    /// `capacity` must already be bounded by the bytes present.
    pub(crate) fn new(capacity: usize, with_normals: bool) -> Self {
        Self {
            points: Vec::with_capacity(capacity),
            normals: with_normals.then(|| Vec::with_capacity(capacity)),
            normals_usable: with_normals,
        }
    }

    pub(crate) fn push(&mut self, v: &[f64; 6]) {
        if v[..3].iter().any(|c| c.is_nan()) {
            return;
        }
        self.points.push(Point3::new(v[0], v[1], v[2]));
        if let Some(normals) = &mut self.normals {
            let n = Vector3::new(v[3], v[4], v[5]);
            let len = n.norm();
            if !len.is_finite() || len < 1e-12 {
                self.normals_usable = false;
            }
            normals.push(n);
        }
    }

    pub(crate) fn finish(self) -> PointCloud {
        PointCloud {
            points: self.points,
            normals: if self.normals_usable {
                self.normals
            } else {
                None
            },
        }
    }
}

/// Capacity to reserve for `claimed` records when at most `available` can fit.
pub(crate) fn bounded_capacity(claimed: u64, available: usize) -> usize {
    usize::try_from(claimed)
        .unwrap_or(usize::MAX)
        .min(available)
}

/// One header line: its number (from 1) and its text without CR/LF.
pub(crate) type HeaderLine = (usize, String);

/// Splits off the header: the lines up to and including the first for which `is_last` holds.
/// Returns them and the offset where the body starts (just past that line's LF). Errors when
/// the header is not text, or has no last line within [`MAX_HEADER_BYTES`].
pub(crate) fn split_header(
    bytes: &[u8],
    fmt: &str,
    last_line_name: &str,
    is_last: impl Fn(&str) -> bool,
) -> Result<(Vec<HeaderLine>, usize), FieldError> {
    let mut lines = Vec::new();
    let mut pos = 0usize;
    while pos < bytes.len() {
        if pos >= MAX_HEADER_BYTES {
            break;
        }
        let rest = &bytes[pos..];
        let window = &rest[..rest.len().min(MAX_HEADER_BYTES - pos)];
        let (raw, next) = match window.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], pos + i + 1),
            None if window.len() < rest.len() => {
                pos = MAX_HEADER_BYTES;
                break;
            }
            None => (rest, bytes.len()),
        };
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let line_no = lines.len() + 1;
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(error(format!(
                "{fmt}: header line {line_no} is not text (binary bytes before the {last_line_name} line)"
            )));
        };
        lines.push((line_no, text.to_string()));
        pos = next;
        if is_last(text) {
            return Ok((lines, pos));
        }
    }
    if pos >= MAX_HEADER_BYTES {
        Err(error(format!(
            "{fmt}: no {last_line_name} line within the first {MAX_HEADER_BYTES} bytes"
        )))
    } else {
        Err(error(format!(
            "{fmt}: the header has no {last_line_name} line (the file ends first)"
        )))
    }
}

/// Whitespace-separated tokens of an ASCII body, with the line each starts on.
pub(crate) struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    pub(crate) line: usize,
}

impl<'a> Tokens<'a> {
    pub(crate) fn new(bytes: &'a [u8], first_line: usize) -> Self {
        Self {
            bytes,
            pos: 0,
            line: first_line,
        }
    }

    /// Next token, or `None` at the end.
    pub(crate) fn next_token(&mut self) -> Option<&'a [u8]> {
        while let Some(&b) = self.bytes.get(self.pos) {
            if b == b'\n' {
                self.line += 1;
            } else if !b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        if self.pos >= self.bytes.len() {
            return None;
        }
        let start = self.pos;
        while let Some(&b) = self.bytes.get(self.pos) {
            if b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        Some(&self.bytes[start..self.pos])
    }

    /// Bytes not yet consumed.
    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }
}

/// Parses a number token of an ASCII body (`nan`/`inf` allowed, left to validation).
pub(crate) fn parse_number(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse::<f64>().ok()
}

/// Shows a token in an error message (shortened, non-text bytes escaped).
pub(crate) fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(&tok[..tok.len().min(24)])
        .escape_debug()
        .to_string();
    if tok.len() > 24 { format!("{s}…") } else { s }
}

/// Checks the writers' contract: normals, if given, one per point.
pub(crate) fn check_writer_normals(points: &[Point3<f64>], normals: Option<&[Vector3<f64>]>) {
    if let Some(n) = normals {
        assert_eq!(
            n.len(),
            points.len(),
            "cloud writer: {} normals for {} points",
            n.len(),
            points.len()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn cloud(n: usize) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let pts = (0..n)
            .map(|i| Point3::new(i as f64 * 1e-3, -(i as f64) * 2e-3, 0.25))
            .collect();
        let nrm = (0..n)
            .map(|i| Vector3::new(0.0, (i as f64).sin(), (i as f64).cos()))
            .collect();
        (pts, nrm)
    }

    #[test]
    fn read_cloud_file_detects_each_writer() {
        let (pts, nrm) = cloud(64);
        type Writer = fn(&[Point3<f64>], Option<&[Vector3<f64>]>) -> Vec<u8>;
        let writers: [(Writer, CloudFormat); 4] = [
            (write_pcd_ascii, CloudFormat::Pcd),
            (write_pcd_binary, CloudFormat::Pcd),
            (write_ply_ascii, CloudFormat::Ply),
            (write_ply_binary, CloudFormat::Ply),
        ];
        for (write, fmt) in writers {
            for normals in [None, Some(nrm.as_slice())] {
                let bytes = write(&pts, normals);
                assert_eq!(detect_format(&bytes), Some(fmt));
                let c = read_cloud_file(&bytes).unwrap();
                assert_eq!(c.len(), 64);
                assert_eq!(c.normals.is_some(), normals.is_some());
                for (a, b) in c.points.iter().zip(&pts) {
                    assert!((a - b).norm() < 1e-6);
                }
            }
        }
    }

    #[test]
    fn detection_allows_comments_and_rejects_other_files() {
        let pcd = b"\n# made by hand\n# another\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n";
        assert_eq!(detect_format(pcd), Some(CloudFormat::Pcd));
        assert_eq!(
            read_cloud_file(pcd).unwrap().points,
            vec![Point3::new(1.0, 2.0, 3.0)]
        );
        for other in [
            &b""[..],
            b"{\"points\": []}",
            b"solid cube\nfacet normal 0 0 1\n",
            b"\x89PNG\r\n\x1a\n",
            b"plyx\n",
        ] {
            let e = read_cloud_file(other).unwrap_err();
            assert_eq!(e.field, FILE_FIELD);
            assert!(
                e.message.contains("unrecognised cloud file") || e.message.contains("empty"),
                "{}",
                e.message
            );
        }
    }

    /// A few valid files to mutate.
    fn seeds() -> Vec<Vec<u8>> {
        let (pts, nrm) = cloud(20);
        vec![
            write_pcd_ascii(&pts, Some(&nrm)),
            write_pcd_binary(&pts, None),
            write_ply_ascii(&pts, None),
            write_ply_binary(&pts, Some(&nrm)),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
            let _ = read_cloud_file(&bytes);
            let _ = read_pcd(&bytes);
            let _ = read_ply(&bytes);
        }

        #[test]
        fn valid_header_with_arbitrary_body_never_panics(
            which in 0usize..4,
            body in proptest::collection::vec(any::<u8>(), 0..1024),
        ) {
            let file = &seeds()[which];
            let end = file.windows(11).position(|w| w == b"end_header\n").map(|i| i + 11)
                .or_else(|| file.windows(6).position(|w| w == b"DATA a" || w == b"DATA b")
                    .and_then(|i| file[i..].iter().position(|&b| b == b'\n').map(|j| i + j + 1)))
                .unwrap();
            let mut bytes = file[..end].to_vec();
            bytes.extend_from_slice(&body);
            let _ = read_cloud_file(&bytes);
        }

        #[test]
        fn mutated_valid_files_never_panic(
            which in 0usize..4,
            edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..8),
            cut in any::<usize>(),
        ) {
            let mut bytes = seeds()[which].clone();
            for (at, b) in edits {
                let i = at % bytes.len();
                bytes[i] = b;
            }
            bytes.truncate(cut % (bytes.len() + 1));
            if let Ok(c) = read_cloud_file(&bytes)
                && let Some(n) = &c.normals
            {
                prop_assert_eq!(n.len(), c.points.len());
            }
        }

        #[test]
        fn header_numbers_are_untrusted(
            n in any::<u64>(),
            count in any::<u64>(),
            size in prop::sample::select(vec![1u64, 2, 4, 8, 3, 0]),
        ) {
            let pcd = format!(
                "FIELDS x y z w\nSIZE 4 4 4 {size}\nTYPE F F F U\nCOUNT 1 1 1 {count}\nPOINTS {n}\nDATA binary\n\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
            );
            let _ = read_cloud_file(pcd.as_bytes());
            let pcd = pcd.replace("binary", "ascii");
            let _ = read_cloud_file(pcd.as_bytes());
            let ply = format!(
                "ply\nformat binary_little_endian 1.0\nelement face {count}\nproperty list uint int i\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
            );
            let mut bin = ply.as_bytes().to_vec();
            bin.extend_from_slice(&[0xff, 0xff, 0xff, 0xff, 0, 0, 0, 0]);
            let _ = read_cloud_file(&bin);
            let ply = ply.replace("binary_little_endian", "ascii") + "4294967295 0 0 1 2 3\n";
            let _ = read_cloud_file(ply.as_bytes());
        }
    }
}
